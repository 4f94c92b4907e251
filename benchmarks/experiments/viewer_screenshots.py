"""Screenshots of the replay page at 1400 x 900 in headless Chromium (Playwright, as the browser test):
a 16-robot frontier run on a 40 m building with weak radios at three ticks, into ``docs/``.

    python benchmarks/experiments/viewer_screenshots.py [--out docs] [--ticks 0,300,900]

Needs ``/usr/bin/chromium`` and the ``playwright`` package. The recording takes about a minute and a half.
"""

from __future__ import annotations

import argparse
import tempfile
from pathlib import Path

from swarm.record import record_run
from swarm.sim.loop import Simulation
from swarm.viewer import write_html

SPEC = {"seed": 4, "map": {"kind": "building", "size": 40}, "robots": {"count": 16},
        "algorithm": {"name": "frontier"}, "radio": {"model": "multiwall", "tx_power_dbm": -30.0},
        "comm": {"loss": 0.1}, "stop": {"max_ticks": 1500}}
SELECT_AT_LAST = 3
"""At the last tick robot 3 is selected: its panel beside the map, its own knowledge map."""


def main() -> None:
    """Record the run, build its page and save ``viewer-16-tick<T>.png`` per tick."""
    from playwright import sync_api

    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", type=Path, default=Path("docs"))
    parser.add_argument("--ticks", default="0,300,900")
    args = parser.parse_args()
    ticks = [int(t) for t in args.ticks.split(",")]
    with tempfile.TemporaryDirectory() as tmp:
        swr = Path(tmp) / "run.swr"
        record_run(Simulation(SPEC), swr)
        html = write_html(swr, Path(tmp) / "run.html")
        with sync_api.sync_playwright() as pw:
            browser = pw.chromium.launch(executable_path="/usr/bin/chromium",
                                         args=["--headless", "--no-sandbox", "--disable-gpu"])
            page = browser.new_page(viewport={"width": 1400, "height": 900}, device_scale_factor=1)
            page.goto(html.resolve().as_uri())
            page.wait_for_function("document.body.dataset.ready !== '0'", timeout=60_000)
            for tick in ticks:
                page.evaluate(f"swarmViewer.setTick({tick})")
                if tick == ticks[-1]:
                    page.evaluate(f"swarmViewer.select({SELECT_AT_LAST})")
                path = args.out / f"viewer-16-tick{tick}.png"
                page.screenshot(path=str(path))
                print(f"wrote {path}")
            browser.close()


if __name__ == "__main__":
    main()
