"""``swarm plan``: one path planned on a map, drawn, and measured against the optimal lengths."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import click

from .checks import writing
from .group import cli
from .options import POINT, parse_params

SNAP_CELLS = 4          # as the runtime's navigator: a start or goal too near a wall moves at most 2 m


@cli.command("plan")
@click.argument("path", type=click.Path(exists=True, dir_okay=False, path_type=Path))
@click.option("--from", "src", type=POINT, required=True, help="Start x,y in metres.")
@click.option("--to", "dst", type=POINT, required=True, help="Goal x,y in metres.")
@click.option("--planner", default="iboa", show_default=True, metavar="NAME",
              help="A navigation planner: astar, or one registered under swarm.planners (iboa).")
@click.option("--seed", type=click.IntRange(0, 2**63 - 1), default=0, show_default=True,
              help="Seed of the planner's random stream (IBOA).")
@click.option("--param", "params", multiple=True, metavar="KEY=VALUE",
              help="A field of the planner's Params (repeatable), e.g. --param iboa.pop_size=200 "
                   "--param max_window_cells=1000000.")
@click.option("--radius", type=click.FloatRange(0.0, 5.0), default=0.3, show_default=True,
              help="Robot radius in metres.")
@click.option("--margin", type=click.FloatRange(0.0, 1.0), default=0.05, show_default=True,
              help="Clearance beyond the radius in metres.")
@click.option("-o", "--output", type=click.Path(dir_okay=False, path_type=Path), help="Write a picture (.png).")
@click.option("--scale", type=click.IntRange(1, 32), default=None, help="Pixels per 0.5 m cell.")
def plan_cmd(path: Path, src: tuple[float, float], dst: tuple[float, float], planner: str, seed: int,
             params: tuple[str, ...], radius: float, margin: float, output: Path | None, scale: int | None) -> None:
    """Plan a path from --from to --to on a map file with a navigation planner and compare it with the optima.

    Plans on the robot's configuration space of the true map (the map fully known: free where free, solid
    where solid), the space the runtime's navigator uses: every point of the path keeps --radius +
    --margin from the walls. A start or goal too close to a wall moves to the nearest cell with room for
    the robot (at most 2 m, as the navigator snaps). The planner is the one a run's navigator would use
    (``navigation.planner``), with its runtime settings unless --param changes them (IBOA plans in a window
    around start and goal and falls back to A* past max_window_cells). Prints the path as the robot would
    drive it (the navigator's line-of-sight shortcuts of the planner's cells) beside the optimal
    8-connected grid path (A*) and the any-angle shortest path (the physical limit).
    """
    import time

    import numpy as np

    from maps.io import load_map
    from swarm import grid
    from swarm.base.errors import InvalidInput
    from swarm.base.types import FREE, SOLID
    from swarm.plugins import planners
    from swarm.util.jit import JitWatch

    from .compile_notice import compile_notice

    if planner not in planners.available():
        raise InvalidInput("--planner", planner, " | ".join(planners.available()))
    chosen = planners.get_planner(planner, parse_params(params), field="--param")
    truth = load_map(path)
    with compile_notice() as first_use:
        known = np.where(truth.solid, SOLID, FREE).astype(np.uint8)
        space = grid.configuration_space(known, radius, margin)
        start, start_note = _cell(truth, space, "--from", src, radius + margin)
        goal, goal_note = _cell(truth, space, "--to", dst, radius + margin)
        reference = grid.plan(space, start, goal)
        if reference is None:
            raise InvalidInput("--to", _fmt(dst), "a point the robot can reach from --from (no path exists)")
        with JitWatch() as in_plan:
            t0 = time.perf_counter()
            cells = chosen.plan(space, start, goal, np.random.default_rng(seed))
            elapsed = time.perf_counter() - t0
        if cells is None:
            raise InvalidInput("--planner", planner, "a planner that finds the path A* finds (this one found none)")
        describe = getattr(chosen, "describe_last", None)
        result = {"cells": np.asarray(cells, dtype=np.int64), "reference": reference,
                  "elapsed": elapsed - in_plan.seconds, "note": describe() if describe is not None else None,
                  "driven": grid.path_length_m(grid.simplify(space, np.asarray(cells, dtype=np.int64))),
                  "astar": grid.steps_length(reference) * 0.5,
                  "astar_driven": grid.path_length_m(grid.simplify(space, reference)),
                  "any_angle": grid.any_angle_length_m(space, start, goal)}
    result["jit"] = first_use.watch
    for line in report_lines(truth, planner, start, goal, result, radius, margin, (start_note, goal_note)):
        click.echo(line)
    if output is not None:
        title = f"{path.name}: {planner}, {result['driven']:.1f} m (A* {result['astar_driven']:.1f} m)"
        with writing("--output", output):
            click.echo(f"wrote {save_plan_png(truth, space, result, output, scale, title)}")


def _fmt(p: tuple[float, float]) -> str:
    return f"{p[0]:g},{p[1]:g}"


def _cell(truth: Any, space: Any, flag: str, point: tuple[float, float], need_m: float
          ) -> tuple[tuple[int, int], str | None]:
    """The planning cell of a point; bad points raise InvalidInput naming the flag."""
    from swarm import grid
    from swarm.base.errors import InvalidInput

    if not truth.contains(*point):
        raise InvalidInput(flag, _fmt(point), f"a point inside the map: 0 <= x < {truth.width_m:g}, "
                                              f"0 <= y < {truth.height_m:g}")
    if not truth.is_free_at(*point):
        raise InvalidInput(flag, _fmt(point), "a point in free space (this one is inside a wall)")
    cell = truth.cell_of(*point)
    snapped = grid.nearest_in(space, cell, SNAP_CELLS)
    if snapped is None:
        raise InvalidInput(flag, _fmt(point), f"a point with room for the robot ({need_m:.2f} m from every wall) "
                                              "within 2 m")
    note = None
    if snapped != cell:
        x, y = truth.cell_centre(*snapped)
        note = f"{flag} moved to ({x:g}, {y:g}): the robot needs {need_m:.2f} m from every wall"
    return (int(snapped[0]), int(snapped[1])), note


def report_lines(truth: Any, planner: str, start: tuple[int, int], goal: tuple[int, int], result: dict[str, Any],
                 radius: float, margin: float, notes: tuple[str | None, ...]) -> list[str]:
    """The lines ``swarm plan`` prints (metres)."""
    m = 0.5
    sx, sy = truth.cell_centre(*start)
    gx, gy = truth.cell_centre(*goal)
    lines = [f"map: {truth.summary()}",
             f"configuration space of the true map: robot radius {radius:g} m + margin {margin:g} m"]
    lines += [n for n in notes if n]
    lines.append(f"from ({sx:g}, {sy:g}) to ({gx:g}, {gy:g}): straight line {m * _dist(start, goal):.2f} m")
    lines.append(f"{planner}: {result['driven']:.2f} m as driven ({len(result['cells'])} cells planned, "
                 f"shortcut by line of sight as the navigator does), {result['elapsed']:.2f} s planning")
    if result["note"]:
        lines.append(f"  {result['note']}")
    lines.append(f"optimal 8-connected grid path (A*): {result['astar']:.2f} m, {result['astar_driven']:.2f} m "
                 f"as driven (ratio {result['driven'] / result['astar_driven']:.3f})")
    lines.append(f"any-angle shortest path (physical limit): {result['any_angle']:.2f} m "
                 f"(ratio {result['driven'] / result['any_angle']:.3f})")
    jit = result.get("jit")
    if jit is not None and jit.seconds >= 0.05:
        what = (f"compiling {jit.compiled} functions (first use after an install; cached for later calls)"
                if jit.compiled else "loading compiled kernels from its cache")
        lines.append(f"numba: {jit.seconds:.2f} s {what}, not counted in the planning time above")
    return lines


def _dist(a: tuple[int, int], b: tuple[int, int]) -> float:
    return float(((a[0] - b[0]) ** 2 + (a[1] - b[1]) ** 2) ** 0.5)


def save_plan_png(truth: Any, space: Any, result: dict[str, Any], output: Path, scale: int | None,
                  title: str) -> Path:
    """The map with the robot's forbidden margin shaded, the A* path (thin blue), the planned path (red),
    the start (green) and the goal (black)."""
    import io

    import numpy as np
    from PIL import Image, ImageDraw

    from maps.io import atomic_write_bytes
    from maps.render import add_legend, auto_scale, map_rgb

    s = scale or auto_scale(truth)
    rgb = map_rgb(truth).astype(np.int16)
    margin = (truth.free & ~space)[::-1]
    rgb[margin] = (rgb[margin] * 3 + np.array([200, 200, 200])) // 4 - 40
    img = Image.fromarray(np.repeat(np.repeat(np.clip(rgb, 0, 255).astype(np.uint8), s, 0), s, 1), "RGB")
    draw = ImageDraw.Draw(img)
    H = truth.shape[0]

    def px(cell: tuple[int, int]) -> tuple[float, float]:
        return (cell[1] + 0.5) * s, (H - cell[0] - 0.5) * s

    draw.line([px(tuple(c)) for c in result["reference"].tolist()], fill=(40, 90, 220), width=max(1, s // 3))
    draw.line([px(tuple(c)) for c in result["cells"].tolist()], fill=(220, 30, 30), width=max(2, s // 2 + 1))
    for cell, colour in ((tuple(result["cells"][0]), (20, 160, 40)), (tuple(result["cells"][-1]), (0, 0, 0))):
        x, y = px(cell)
        r = max(3, s)
        draw.ellipse([x - r, y - r, x + r, y + r], fill=colour)
    buf = io.BytesIO()
    add_legend(img, truth, title).save(buf, format="PNG")
    return atomic_write_bytes(output, buf.getvalue())
