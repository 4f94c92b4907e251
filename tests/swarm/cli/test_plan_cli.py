"""``swarm plan``: the path's length beside the A* and any-angle optima, the picture, and bad input."""

from __future__ import annotations

import re

import pytest
from PIL import Image

from maps import generate
from maps.io import save_npz
from swarm.cli import main


@pytest.fixture(scope="module")
def map_file(tmp_path_factory):
    path = tmp_path_factory.mktemp("plan") / "b.npz"
    save_npz(generate("building", 20, seed=2), path)
    return path


def run(capsys, *args: str) -> tuple[int, str, str]:
    code = main(list(args))
    out, err = capsys.readouterr()
    return code, out, err


def metres(out: str, label: str) -> float:
    m = re.search(rf"{re.escape(label)}: ([0-9.]+) m", out)
    assert m, f"no '{label}' line in:\n{out}"
    return float(m.group(1))


def test_iboa_path_is_drawn_and_measured_against_both_optima(map_file, tmp_path, capsys):
    png = tmp_path / "p.png"
    code, out, err = run(capsys, "plan", str(map_file), "--from", "3,3", "--to", "16,16", "-o", str(png))
    assert code == 0, err
    iboa = metres(out, "iboa")
    astar = float(re.search(r"A\*\): [0-9.]+ m, ([0-9.]+) m as driven", out).group(1))
    any_angle = metres(out, "any-angle shortest path (physical limit)")
    assert any_angle <= astar and any_angle <= iboa + 1e-9, "nothing beats the physical limit"
    assert any_angle >= 13 * 2 ** 0.5 - 1.0, "at least the straight line between the snapped points"
    ratio = float(re.search(r"as driven \(ratio ([0-9.]+)\)", out).group(1))
    assert ratio == pytest.approx(iboa / astar, abs=2e-3)
    assert "configuration space of the true map" in out and "IBOA-Kent:" in out and "evaluations" in out
    with Image.open(png) as img:
        assert img.width >= 200 and img.height > img.width       # legend strip below the map
        colours = {c for _, c in img.convert("RGB").getcolors(1 << 20)}
    assert (220, 30, 30) in colours and (40, 90, 220) in colours  # planned path and A* reference drawn


def test_astar_planner_matches_the_optimum(map_file, capsys):
    code, out, _ = run(capsys, "plan", str(map_file), "--from", "3,3", "--to", "16,16", "--planner", "astar")
    assert code == 0
    assert "(ratio 1.000)" in out


def test_same_seed_same_path_and_params_reach_the_planner(map_file, capsys):
    """The planner is the runtime's plug-in, built from its Params: --param sets them (nested with dots)."""
    args = ["plan", str(map_file), "--from", "3,3", "--to", "16,16", "--seed", "4"]
    first = run(capsys, *args)[1]
    again = run(capsys, *args)[1]
    note = lambda text: [line for line in text.splitlines() if "IBOA-Kent:" in line]  # noqa: E731
    assert metres(again, "iboa") == metres(first, "iboa") and note(again) == note(first)
    code, out, _ = run(capsys, *args, "--param", "iboa.pop_size=2", "--param", "iboa.max_gen=1")
    evaluations = lambda text: int(re.search(r"([0-9]+) evaluations", text).group(1))  # noqa: E731
    assert code == 0 and evaluations(out) < evaluations(first)
    code, out, _ = run(capsys, *args, "--param", "max_window_cells=10")
    assert code == 0 and "A* instead" in out, "a window over the limit falls back, as in a run"


def test_a_point_next_to_a_wall_snaps_like_the_navigator(map_file, capsys):
    code, out, _ = run(capsys, "plan", str(map_file), "--from", "1.1,3", "--to", "16,16", "--planner", "astar")
    assert code == 0 and "--from moved to" in out


@pytest.mark.parametrize("args, needle", [
    (["--from", "3,3", "--to", "40,3"], "--to: got '40,3'; allowed: a point inside the map"),
    (["--from", "0.2,0.2", "--to", "16,16"], "--from: got '0.2,0.2'; allowed: a point in free space"),
    (["--from", "3,3", "--to", "16,16", "--planner", "rrt"], "--planner: got 'rrt'; allowed: astar | iboa"),
    (["--from", "3,3", "--to", "16,16", "--param", "pop=3"], "--param pop"),
    (["--from", "3,3", "--to", "16,16", "--param", "iboa.pop=3"], "iboa.pop"),
    (["--from", "3,3", "--to", "16,16", "--planner", "astar", "--param", "pop_size=3"], "takes no parameters"),
    (["--from", "3;3", "--to", "16,16"], "--from"),
])
def test_bad_input_is_one_line_and_exit_2(map_file, capsys, args, needle):
    code, out, err = run(capsys, "plan", str(map_file), *args)
    assert code == 2 and needle in err
    assert err.count("\n") == 1 and err.startswith("swarm: error: ") and "Traceback" not in err


def test_unreachable_goal_is_bad_input(tmp_path, capsys):
    import numpy as np

    from maps import Map

    solid = np.ones((40, 40), bool)
    solid[1:-1, 1:19] = False
    solid[1:-1, 21:-1] = False                         # two rooms, no door
    path = tmp_path / "two.npz"
    save_npz(Map(solid=solid, material=solid.astype(np.uint8), materials=("air", "concrete")), path)
    code, _, err = run(capsys, "plan", str(path), "--from", "3,3", "--to", "15,15")
    assert code == 2 and "--to" in err and "reach" in err


def test_numba_compiling_is_reported_apart_from_the_planning_time(map_file, capsys, monkeypatch):
    """A first call's compile (35 s after an install) is not planning time: the planner's time excludes
    what numba spent inside it, and a line says what numba cost."""
    from swarm.util.jit import JitWatch

    real = JitWatch.__exit__

    def slow_compile(self, *exc):  # as if numba had spent 30 s compiling 12 functions in the block
        self.seconds += 30.0
        self.compiled += 12
        return real(self, *exc)

    monkeypatch.setattr(JitWatch, "__exit__", slow_compile)
    code, out, err = run(capsys, "plan", str(map_file), "--from", "3,3", "--to", "16,16", "--planner", "astar")
    assert code == 0, err
    planning = float(re.search(r"astar: [0-9.]+ m as driven .*, (-?[0-9.]+) s planning", out).group(1))
    assert planning < 0, "the 30 s the watch inside the planner's call reported are taken out of its time"
    line = out.strip().splitlines()[-1]
    assert line.startswith("numba: 30.") and "compiling 12 functions" in line and "not counted" in line
