"""A disk that fills up while a command writes its output (issue 48, item 7): every file-writing command ends in
one line ``swarm: error: <flag>: ...No space left on device...`` with exit status 2, never an ``OSError``
traceback, and leaves neither the output nor a temporary file behind (tests/full_disk.py simulates the disk).
"""

from __future__ import annotations

from pathlib import Path

import pytest

from maps import generate
from maps.io import save_npz

from ... import full_disk

pytestmark = pytest.mark.skipif(not full_disk.SUPPORTED, reason="needs /proc")


@pytest.fixture(scope="module")
def inputs(tmp_path_factory) -> dict[str, Path]:
    """A map file, an xBOA CSV floor plan and a short recording to read."""
    folder = tmp_path_factory.mktemp("inputs")
    save_npz(generate("building", 20, 1), folder / "b.npz")
    rows = ["1" * 20] + ["1" + "0" * 18 + "1"] * 18 + ["1" * 20]
    (folder / "plan.csv").write_text("\n".join(",".join(r) for r in rows) + "\n")
    from swarm.cli import main

    assert main(["run", "--size", "20", "--max-ticks", "5", "--robots", "1", "--record", str(folder / "r.swr")]) == 0
    return {"npz": folder / "b.npz", "csv": folder / "plan.csv", "swr": folder / "r.swr"}


CASES = {
    "map generate -o": (["map", "generate", "--size", "20", "-o", "{out}/m.npz"], "m.npz", "--output"),
    "map generate --png": (["map", "generate", "--size", "20", "--png", "{out}/m.png"], "m.png", "--png"),
    "map import -o": (["map", "import", "{csv}", "-o", "{out}/i.npz"], "i.npz", "--output"),
    "map import --png": (["map", "import", "{csv}", "-o", "{out}/i.npz", "--png", "{out}/i.png"], "i.png", "--png"),
    "map show -o": (["map", "show", "{npz}", "-o", "{out}/s.png"], "s.png", "--output"),
    "map export --ros (image)": (["map", "export", "{npz}", "--ros", "{out}/e.yaml"], "e.pgm", "--ros"),
    "map export --ros (yaml)": (["map", "export", "{npz}", "--ros", "{out}/e.yaml"], "e.yaml", "--ros"),
    "radio heatmap -o": (["radio", "heatmap", "{npz}", "--tx", "5,5", "-o", "{out}/h.png"], "h.png", "--output"),
    "plan -o": (["plan", "{npz}", "--from", "3,3", "--to", "15,15", "--planner", "astar", "-o", "{out}/p.png"],
                "p.png", "--output"),
    "view -o": (["view", "{swr}", "--no-open", "-o", "{out}/v.html"], "v.html", "--output"),
    "run --json": (["run", "--size", "20", "--max-ticks", "3", "--json", "{out}/r.json"], "r.json", "--json"),
}


@pytest.mark.parametrize("case", list(CASES))
def test_a_full_disk_is_a_one_line_error_and_leaves_no_file(case, inputs, tmp_path):
    argv, name, flag = CASES[case]
    out = tmp_path / "out"
    out.mkdir()
    args = [a.format(out=out, **{k: str(v) for k, v in inputs.items()}) for a in argv]
    proc = full_disk.run_on_full_disk(args, name)
    assert proc.returncode == 2, proc.stderr
    assert "Traceback" not in proc.stderr
    last = proc.stderr.strip().splitlines()[-1]
    assert last.startswith(f"swarm: error: {flag}: got ") and "No space left on device" in last, proc.stderr
    assert len(proc.stderr.strip().splitlines()) == 1, proc.stderr
    assert not (out / name).exists()
    assert not [p for p in out.iterdir() if p.name.startswith(".")], "no temporary file is left"
