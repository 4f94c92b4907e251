"""Campaign specs accepted but wrong, huge grids, and the lazy run list (issue 31): a scalar grid entry, an
exclude that removes everything, a comment-only change of a results folder's spec, 20,000-character names,
grids of millions of runs refused at once, and the same run order, indices and keys as before."""

from __future__ import annotations

import hashlib
import itertools
import subprocess
import sys
import time
from pathlib import Path

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from maps import InvalidInput
from swarm.campaign import make_executor, parse_campaign, run_campaign
from swarm.campaign.cells import count, decode, iter_cells
from swarm.cli import main

from .test_campaign import TINY

ROOT = Path(__file__).resolve().parents[3]
PAPER = ROOT / "examples" / "minotaur-paper.toml"


def error_of(text: str) -> InvalidInput:
    with pytest.raises(InvalidInput) as info:
        parse_campaign(text)
    assert "\n" not in str(info.value) and len(str(info.value)) < 400, str(info.value)
    return info.value


# ------------------------------------------------------------------------------ accepted but wrong ----
@pytest.mark.parametrize("old, new, field, example", [
    ("size = [20]", "size = 40", "grid.size", "a list, e.g. [40]"),
    ('spawn = ["together"]', 'spawn = "together"', "grid.spawn", 'a list, e.g. ["together"]'),
    ('robots = [1, 2]', 'robots = {count = 2}', "grid.robots", "a list"),
])
def test_every_grid_dimension_must_be_a_list(old, new, field, example):
    assert old in TINY
    err = error_of(TINY.replace(old, new))
    assert err.field == field and example in str(err)


def test_an_exclude_that_removes_every_cell_is_an_error_naming_exclude(tmp_path, capsys):
    text = TINY + '\n[[exclude]]\nmap = ["building", "cave"]\n'
    assert error_of(text).field == "exclude"
    path = tmp_path / "all-excluded.toml"
    path.write_text(text)
    assert main(["campaign", "run", str(path), "-o", str(tmp_path / "out")]) == 2
    err = capsys.readouterr().err
    assert err.startswith("swarm: error: exclude:") and "removes every cell" in err


def test_a_spec_differing_only_in_comments_and_layout_reuses_the_folder(tmp_path):
    first = parse_campaign(TINY)
    run_campaign(first, tmp_path, executor=make_executor(inline=True), progress=False, shard=(0, 12))
    reworded = ("# the same campaign, written differently\n"
                + TINY.replace("[stop]\nexplored = 0.6\nmax_ticks = 250",
                               "[stop]   # when a run ends\nmax_ticks = 250\nexplored = 0.6")
                .replace('name = "tiny"', "name = 'tiny'  # quoted the other way"))
    assert reworded != TINY
    again = run_campaign(parse_campaign(reworded), tmp_path, executor=make_executor(inline=True), progress=False,
                         shard=(0, 12))
    assert again.ran == 0 and again.skipped == 2
    assert (tmp_path / "campaign.toml").read_text() == TINY, "the folder keeps the spec it was made with"


@pytest.mark.parametrize("old, new, says", [
    ("seed = 7", "seed = 8", "campaign.seed: 7 -> 8"),
    ("robots = [1, 2]", "robots = [2, 1]", "grid.robots[0]: 1 -> 2"),
    ("explored = 0.6", "explored = 0.60001", "stop.explored: 0.6 -> 0.60001"),
    ("robots = [1, 2]", "robots = [1, 2, 3]", "grid.robots: 2 entries -> 3"),
    ('[[exclude]]\nrobots = 2\nradio = "los"\n', "", "exclude removed"),
])
def test_a_spec_that_changes_results_is_refused_saying_what_changed(tmp_path, old, new, says):
    assert old in TINY
    run_campaign(parse_campaign(TINY), tmp_path, executor=make_executor(inline=True), progress=False, shard=(0, 24))
    with pytest.raises(InvalidInput, match="campaign.toml differs") as info:
        run_campaign(parse_campaign(TINY.replace(old, new)), tmp_path, executor=make_executor(inline=True),
                     progress=False)
    assert says in str(info.value)


HUGE = "x" * 20_000


@pytest.mark.parametrize("text", [
    TINY.replace('label = "frontier-eager"', f'label = "{HUGE}"').replace('"frontier", {', f'"{HUGE}", {{'),
    TINY.replace('label = "frontier-eager"', f'label = "{HUGE}"').replace('algorithm = ["frontier",',
                                                                          f'algorithm = [{{name = "frontier", label = "{HUGE}"}},'),
    TINY + f"\n[{HUGE}]\nx = 1\n",
    TINY.replace("[stop]", f"[stop]\n{HUGE} = 1"),
    TINY.replace("[campaign]", f"[campaign]\n{HUGE} = 1"),
    TINY.replace("[[exclude]]", f"[[exclude]]\n{HUGE} = 1"),
    TINY.replace("max_ticks = 250", f'max_ticks = "{HUGE}"'),
    TINY.replace('name = "tiny"', f'name = "{HUGE}/"'),
    TINY.replace('radio = ["global", "los"]', f'radio = ["global", "{HUGE}"]'),
    TINY.replace("seed = 7", "seed = " + "9" * 5000),
])
def test_errors_about_huge_values_are_one_short_line(text):
    err = str(error_of(text))
    assert len(err) < 400 and "x" * 200 not in err


# ----------------------------------------------------------------------------------- big grids ----
@pytest.mark.timeout(120)
@pytest.mark.parametrize("replicates, sizes", [(100_000, None), (20, list(range(20, 520)))])
def test_a_grid_of_millions_of_runs_is_refused_at_once(replicates, sizes):
    text = PAPER.read_text().replace("replicates = 100", f"replicates = {replicates}")
    if sizes:  # 500 sizes x 1,000 robot counts = 500,000 cells per map kind ...
        text = text.replace("size = [50, 100, 150]", f"size = {sizes}").replace(
            "robots = [1, 2, 4, 8, 16]", f"robots = {list(range(1, 1001))}")
    t0 = time.monotonic()
    err = error_of(text)
    assert err.field == "grid" and "at most 1,000,000 runs" in str(err) and "--max-runs" in str(err)
    assert time.monotonic() - t0 < 30


def test_max_runs_is_the_limit(tmp_path, capsys):
    with pytest.raises(InvalidInput, match="at most 23 runs"):
        parse_campaign(TINY, max_runs=23)
    assert parse_campaign(TINY, max_runs=24).run_count() == 24
    path = tmp_path / "tiny.toml"
    path.write_text(TINY)
    assert main(["campaign", "run", str(path), "-o", str(tmp_path / "o"), "--max-runs", "10"]) == 2
    assert "grid: got '24 runs" in capsys.readouterr().err


@pytest.mark.skipif(not Path("/proc/self/status").exists(), reason="reads the peak RSS from /proc")
@pytest.mark.timeout(300)
def test_the_paper_grid_is_counted_and_listed_without_building_54000_specs(tmp_path):
    """Time and peak memory of ``swarm campaign status`` on a folder of the 54,000-run spec (before: ~24 s
    and ~680 MB here, building every run spec; after: ~3 s and ~190 MB, the bare import being ~150 MB)."""
    t0 = time.monotonic()
    spec = parse_campaign(PAPER.read_text())
    assert spec.run_count() == 54_000 and time.monotonic() - t0 < 10
    folder = tmp_path / "paper"
    (folder / "parts").mkdir(parents=True)
    (folder / "campaign.toml").write_text(PAPER.read_text())
    proc = subprocess.run([sys.executable, "-c", PEAK_AFTER_MAIN, "campaign", "status", str(folder)],
                          capture_output=True, text=True, cwd=ROOT, timeout=240)
    assert "54000 pending of 54000 runs" in proc.stdout, proc.stderr
    peak_mb = int(proc.stdout.split("VmHWM:")[1].split()[0]) // 1024
    assert peak_mb < 400, f"status peaked at {peak_mb} MB"


PEAK_AFTER_MAIN = """
import sys
from swarm.cli import main
code = main(sys.argv[1:])
print([line for line in open("/proc/self/status") if line.startswith("VmHWM:")][0])  # this process's peak RSS
sys.exit(code)
"""


# ----------------------------------------------------------------------- the same runs as before ----
def test_run_order_indices_and_keys_are_those_of_earlier_versions():
    spec = parse_campaign(TINY)
    runs = spec.runs()
    keys = [r.key for r in runs]
    assert keys[:3] == ["88a0c1ac7554c613", "3c4b38baf2a771df", "8dcf2414bc35d674"]  # computed by v0 (git HEAD)
    assert hashlib.sha256(",".join(keys).encode()).hexdigest()[:16] == "8951ffd5e2e902aa"
    assert [r.index for r in runs] == list(range(24))
    assert [k for _, k in spec.iter_keys()] == keys
    assert [k for _, k in spec.iter_keys((1, 5))] == keys[1::5]
    cells = spec.cells()
    for r in runs:
        built = spec.run_for(cells[r.index // spec.replicates], r.replicate)
        assert r.spec.key == built.key == r.key and r.spec_json == built.spec.to_json()
        assert spec.run_at(r.index) == r and r.canonical() == built.spec.canonical()


def test_duplicate_cells_still_collapse_lazily():
    text = TINY.replace('radio = ["global", "los"]', 'radio = ["global", "los"]\ncomm = [{label = "a"}, {label = "b"}]')
    text += '\n[[include]]\nmap = "building"\nsize = 20\nrobots = 1\nspawn = "together"\nalgorithm = "frontier"\n' \
            'radio = "global"\ncomm = "a"\n'
    spec = parse_campaign(text)
    assert spec.run_bound() == 2 * 12 * 2 + 2 and spec.run_count() == 24, "comm b and the include repeat cells"
    assert len({r.key for r in spec.runs()}) == 24


def test_one_run_per_cell_validates_every_replicate():
    """Replicates differ only in the three seeds, each drawn in 0..2**63-1 and validated as such."""
    spec = parse_campaign(TINY.replace("replicates = 2", "replicates = 50"))
    for r in spec.iter_runs((3, 97)):
        assert 0 <= min(r.seeds.values()) and max(r.seeds.values()) < 2**63
        assert r.spec.key == r.key


boxes_st = st.lists(st.dictionaries(st.integers(0, 3), st.frozensets(st.integers(0, 3), max_size=3), max_size=3),
                    max_size=5)


@settings(max_examples=300, deadline=None)
@given(st.lists(st.integers(1, 4), min_size=1, max_size=4), boxes_st)
def test_cells_are_the_cross_product_minus_excluded_boxes(sizes, boxes):
    boxes = [{d: v for d, v in b.items() if d < len(sizes)} for b in boxes]
    expected = [(code, idx) for code, idx in enumerate(itertools.product(*(range(n) for n in sizes)))
                if not any(all(idx[d] in vals for d, vals in b.items()) for b in boxes)]
    assert list(iter_cells(sizes, boxes)) == expected
    assert count(sizes, boxes) == len(expected)
    assert all(decode(code, sizes) == idx for code, idx in expected)


def test_a_radio_override_is_checked_against_each_cells_robot_count():
    """An override for robot 6 is valid in the 8-robot cells and names the 2-robot cell where it is not;
    excluding that cell makes the campaign valid."""
    grid = TINY.replace("robots = [1, 2]", "robots = [2, 8]").replace(
        'radio = ["global", "los"]', 'radio = ["global", {model = "multiwall", tx_power_overrides = {"6" = 10.0}, label = "weak6"}]')
    grid = grid.split("[[exclude]]")[0]
    err = error_of(grid)
    assert err.field == "radio.tx_power_overrides.6" and "robots=2" in str(err) and "radio=weak6" in str(err)
    ok = parse_campaign(grid + '\n[[exclude]]\nrobots = 2\nradio = "weak6"\n')
    assert all(r.spec.radio.tx_power_overrides == {6: 10.0} for r in ok.runs() if r.cell["radio"] == "weak6")


def test_an_include_adds_a_slice_keys_left_out_take_every_grid_value():
    """One [[include]] adds the frontier algorithm under a third radio on every map, size and robot count of
    the grid: a list is each of its values, a key left out every grid value."""
    extra = '\n[[include]]\nalgorithm = "frontier"\nradio = {model = "multiwall", label = "mw"}\nrobots = [1, 2]\n'
    spec = parse_campaign(TINY + extra)
    added = [r for r in spec.runs() if r.cell["radio"] == "mw"]
    grid = parse_campaign(TINY)
    assert len(added) == 2 * 1 * 2 * 1 * 2  # maps x sizes x robots x spawns x replicates (one algorithm)
    assert {(r.cell["map"], r.cell["robots"]) for r in added} == {(m, n) for m in ("building", "cave") for n in ("1", "2")}
    assert len(spec.runs()) == len(grid.runs()) + len(added) == spec.run_count()
    assert all(r.cell["algorithm"] == "frontier" and r.spec.algorithm.params["recheck_ticks"] == 20 for r in added)
    with pytest.raises(InvalidInput, match=r"include\[0\]\.robots"):
        parse_campaign(TINY + '\n[[include]]\nrobots = []\n')
