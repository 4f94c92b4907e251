"""The replay page at team and swarm size (issue 47): page size, load time, memory, milliseconds per frame.

Builds the page of each recording given, opens it in headless Chromium (Playwright, as the browser test)
and measures:

- ``html MB``: the page (the recording in base64, 4/3 of the file, plus the script);
- ``load s``: from navigation until the viewer is ready (decode, index, keyframes, first frame);
- ``renderer MB``: resident memory of the page's renderer process(es) once loaded (psutil); ``heap MB``:
  the JS heap with the typed arrays' memory after a garbage collection (mostly the decoded recording);
  ``state MB``: the replay state with its keyframes;
- ``ms/frame``: playback, one tick after another (``setTick(t + 1)``), each frame rasterised (a one-pixel
  ``getImageData`` flushes the canvas), mean and 95th percentile over ``--frames`` ticks; with all layers
  on, then with a robot selected (its own knowledge map); ``cpu ms/frame``: the renderer's CPU time per
  frame over the same frames, the steadier figure on a shared machine;
- ``seek ms``: a jump back to an early tick and forward to a late one (keyframes);
- then where a frame's time goes, step by step (the viewer's own ``profile()``).

    python benchmarks/speed/bench_viewer.py run16.swr run1000.swr
    swarm run --map building --size 600 --robots 1000 --algorithm frontier --max-ticks 60 --seed 1 --record r1000.swr

Frame times are software rendering (``--disable-gpu``) on a shared machine: compare rows measured together.
"""

from __future__ import annotations

import argparse
import statistics
import tempfile
import time
from pathlib import Path

import psutil

from swarm.viewer import write_html

CHROMIUM = "/usr/bin/chromium"
FLAGS = ["--headless", "--no-sandbox", "--disable-gpu", "--no-first-run", "--disable-background-networking",
         "--disable-component-update", "--disable-sync", "--js-flags=--expose-gc"]

FRAMES_JS = """async ([from, n, robot]) => {
  const v = swarmViewer, map = document.getElementById('map').getContext('2d');
  if (robot !== null) v.select(robot); else v.select(null);
  v.setTick(from); map.getImageData(0, 0, 1, 1);
  const times = [], steps = {};
  for (let t = from + 1; t <= from + n && t <= v.lastTick; t++) {
    const a = performance.now();
    v.setTick(t);
    const b = performance.now();
    map.getImageData(0, 0, 1, 1);   // rasterise the frame, as showing it would
    times.push(performance.now() - a);
    const p = v.profile ? v.profile() : {};   // (a viewer before issue 47 has no profile)
    p.raster = performance.now() - b;
    for (const [k, ms] of Object.entries(p)) steps[k] = (steps[k] || 0) + ms / n;
  }
  return [times, steps];
}"""

SEEK_JS = """([early, late]) => {
  const v = swarmViewer, map = document.getElementById('map').getContext('2d');
  const out = [];
  for (const t of [late, early, late]) {
    const a = performance.now(); v.setTick(t); map.getImageData(0, 0, 1, 1); out.push(performance.now() - a);
  }
  return out;
}"""


def renderers() -> list[psutil.Process]:
    """Every Chromium renderer process started by this benchmark."""
    out = []
    for proc in psutil.Process().children(recursive=True):
        try:
            if "--type=renderer" in " ".join(proc.cmdline()):
                out.append(proc)
        except psutil.Error:
            continue
    return out


def renderer_rss_mb() -> float:
    return sum(p.memory_info().rss for p in renderers()) / 1e6


def renderer_cpu_s() -> float:
    """CPU seconds of the renderers so far: unlike the page's wall clock, not inflated by other jobs on a
    shared machine."""
    return sum(sum(p.cpu_times()[:2]) for p in renderers())


def measure(browser, recording: Path, folder: Path, frames: int, profiles: list[str]) -> dict[str, float]:
    html = write_html(recording, folder / (recording.stem + ".html"))
    context = browser.new_context(viewport={"width": 1280, "height": 800}, device_scale_factor=1)
    page = context.new_page()
    errors: list[str] = []
    page.on("pageerror", lambda exc: errors.append(str(exc)))
    t0 = time.perf_counter()
    page.goto(html.resolve().as_uri())
    page.wait_for_function("document.body.dataset.ready !== '0'", timeout=600_000, polling=200)
    load_s = time.perf_counter() - t0
    if page.evaluate("document.body.dataset.ready") != "1":
        raise SystemExit(f"{recording}: {page.inner_text('#status')} {errors}")
    last = page.evaluate("swarmViewer.lastTick")
    n_robots = page.evaluate("swarmViewer.nRobots")
    start = max(0, last // 3 - frames // 2)
    for _ in range(2):   # what the page holds, not what decoding left for the collector
        page.evaluate("gc()")
        time.sleep(1)
    heap = page.context.new_cdp_session(page).send("Runtime.getHeapUsage")   # exact, unlike performance.memory
    out = {"robots": n_robots, "ticks": last + 1, "html MB": html.stat().st_size / 1e6, "load s": load_s,
           "renderer MB": renderer_rss_mb(), "heap MB": (heap["usedSize"] + heap["backingStorageSize"]) / 1e6,
           "state MB": page.evaluate("swarmViewer.stateBytes ? swarmViewer.stateBytes().state : NaN") / 1e6}
    for label, robot in (("union", None), ("robot 0", 0)):
        cpu = renderer_cpu_s()
        times, steps = page.evaluate(FRAMES_JS, [start, frames, robot])
        out[f"cpu ms/frame {label}"] = 1000 * (renderer_cpu_s() - cpu) / len(times)
        out[f"ms/frame {label}"] = statistics.fmean(times)
        out[f"p95 {label}"] = sorted(times)[int(0.95 * (len(times) - 1))]
        profiles.append(f"{recording.name}, {label}: " + ", ".join(f"{k} {ms:.1f}" for k, ms in steps.items()))
    out["renderer MB, robot selected"] = renderer_rss_mb()
    page.evaluate("swarmViewer.select(null)")
    seek = page.evaluate(SEEK_JS, [min(3, last), last])
    out["seek back ms"] = seek[1]
    out["seek forward ms"] = seek[2]
    assert not errors, errors
    context.close()
    return out


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("recordings", nargs="+", type=Path)
    parser.add_argument("--frames", type=int, default=40, help="ticks played per measurement (default 40)")
    args = parser.parse_args()
    from playwright import sync_api

    rows, profiles = [], []
    with tempfile.TemporaryDirectory() as tmp, sync_api.sync_playwright() as pw:
        for recording in args.recordings:
            browser = pw.chromium.launch(executable_path=CHROMIUM, args=FLAGS)   # one per row: memory apart
            try:
                rows.append((recording.name, measure(browser, recording, Path(tmp), args.frames, profiles)))
            finally:
                browser.close()
    keys = list(rows[0][1])
    print("| recording | " + " | ".join(keys) + " |")
    print("|---|" + "---:|" * len(keys))
    for name, row in rows:
        print(f"| {name} | " + " | ".join(f"{row[k]:.1f}" if isinstance(row[k], float) else str(row[k])
                                          for k in keys) + " |")
    print("\nms per frame by step (issuing the drawing; 'raster' rasterises it):")
    for line in profiles:
        print("  " + line)


if __name__ == "__main__":
    main()
