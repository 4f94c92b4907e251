"""``swarm plan``: one path planned on a map, drawn, and measured against the optimal lengths."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import click

from . import cli
from .options import POINT, parse_params

PLANNERS = ("iboa", "astar")
SNAP_CELLS = 4          # as the runtime's navigator: a start or goal too near a wall moves at most 2 m


@cli.command("plan")
@click.argument("path", type=click.Path(exists=True, dir_okay=False, path_type=Path))
@click.option("--from", "src", type=POINT, required=True, help="Start x,y in metres.")
@click.option("--to", "dst", type=POINT, required=True, help="Goal x,y in metres.")
@click.option("--planner", default="iboa", show_default=True, metavar="NAME", help="iboa | astar.")
@click.option("--seed", type=click.IntRange(0, 2**63 - 1), default=0, show_default=True,
              help="Seed of the planner's random stream (IBOA).")
@click.option("--param", "params", multiple=True, metavar="KEY=VALUE",
              help="IBOA planner parameter (repeatable), e.g. --param pop_size=200 --param simplify=los.")
@click.option("--radius", type=click.FloatRange(0.0, 5.0), default=0.3, show_default=True,
              help="Robot radius in metres.")
@click.option("--margin", type=click.FloatRange(0.0, 1.0), default=0.05, show_default=True,
              help="Clearance beyond the radius in metres.")
@click.option("-o", "--output", type=click.Path(dir_okay=False, path_type=Path), help="Write a picture (.png).")
@click.option("--scale", type=click.IntRange(1, 32), default=None, help="Pixels per 0.5 m cell.")
def plan_cmd(path: Path, src: tuple[float, float], dst: tuple[float, float], planner: str, seed: int,
             params: tuple[str, ...], radius: float, margin: float, output: Path | None, scale: int | None) -> None:
    """Plan a path from --from to --to on a map file and compare its length with the optimum.

    Plans on the robot's configuration space of the true map (the map fully known: free where free, solid
    where solid), the space the runtime's navigator uses: every point of the path keeps --radius +
    --margin from the walls. A start or goal too close to a wall moves to the nearest cell with room for
    the robot (at most 2 m, as the navigator snaps). Prints the path's length beside the optimal
    8-connected grid path (A*) and the any-angle shortest path (the physical limit).

    IBOA (paper 001) runs on the whole map at 0.5 m cells with the runtime planner's budget (population
    30, 30 generations); paths across a 100 m building take tens of seconds.
    """
    import time

    import numpy as np

    from maps.errors import InvalidInput
    from maps.io import load_map
    from maps.params import from_mapping
    from swarm import grid
    from swarm.api import FREE, SOLID

    from algorithms.boa.pathplan import IBOAPlannerParams
    from algorithms.boa.planner_plugin import IBOAPlannerSettings

    if planner not in PLANNERS:
        raise InvalidInput("--planner", planner, " | ".join(PLANNERS))
    if params and planner != "iboa":
        raise InvalidInput("--param", params[0], "only with --planner iboa")
    base = IBOAPlannerSettings().iboa
    iboa = from_mapping(IBOAPlannerParams, {**_fields(base), **parse_params(params)}, prefix="--param ")
    truth = load_map(path)
    known = np.where(truth.solid, SOLID, FREE).astype(np.uint8)
    space = grid.configuration_space(known, radius, margin)
    start, start_note = _cell(truth, space, "--from", src, radius + margin)
    goal, goal_note = _cell(truth, space, "--to", dst, radius + margin)
    blocked = ~space
    t0 = time.perf_counter()
    result = _plan(planner, blocked, start, goal, np.random.default_rng(seed), iboa)
    elapsed = time.perf_counter() - t0
    if result is None:
        raise InvalidInput("--to", _fmt(dst), "a point the robot can reach from --from (no path exists)")
    for line in report_lines(truth, planner, start, goal, result, elapsed, radius, margin,
                             (start_note, goal_note)):
        click.echo(line)
    if output is not None:
        title = f"{path.name}: {planner}, {result['length'] * 0.5:.1f} m (A* {result['astar'] * 0.5:.1f} m)"
        click.echo(f"wrote {save_plan_png(truth, space, result, output, scale, title)}")


def _fields(params: Any) -> dict[str, Any]:
    import dataclasses

    return {f.name: getattr(params, f.name) for f in dataclasses.fields(params)}


def _fmt(p: tuple[float, float]) -> str:
    return f"{p[0]:g},{p[1]:g}"


def _cell(truth: Any, space: Any, flag: str, point: tuple[float, float], need_m: float
          ) -> tuple[tuple[int, int], str | None]:
    """The planning cell of a point; bad points raise InvalidInput naming the flag."""
    from maps.errors import InvalidInput
    from swarm import grid

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


def _plan(planner: str, blocked: Any, start: tuple[int, int], goal: tuple[int, int], rng: Any,
          params: Any) -> dict[str, Any] | None:
    """The path and the reference lengths, in cells."""
    from algorithms.boa import plan_report
    from algorithms.boa.shortest import any_angle_length, astar, astar_length, path_length

    ref = astar(blocked, start, goal)
    if ref is None:
        return None
    if planner == "astar":
        return {"points": ref, "length": path_length(ref), "grid_length": path_length(ref), "nfev": 0,
                "astar": astar_length(blocked, start, goal), "any_angle": any_angle_length(blocked, start, goal),
                "reference": ref}
    rep = plan_report(blocked, start, goal, rng, params)
    if rep.path is None:
        return None
    return {"points": list(rep.path.waypoints), "length": rep.path.length, "grid_length": rep.path.grid_length,
            "nfev": rep.path.nfev, "astar": rep.astar_length, "any_angle": rep.any_angle_length, "reference": ref}


def report_lines(truth: Any, planner: str, start: tuple[int, int], goal: tuple[int, int], result: dict[str, Any],
                 elapsed: float, radius: float, margin: float, notes: tuple[str | None, ...]) -> list[str]:
    """The lines ``swarm plan`` prints (lengths converted from cells to metres)."""
    m = 0.5
    sx, sy = truth.cell_centre(*start)
    gx, gy = truth.cell_centre(*goal)
    lines = [f"map: {truth.summary()}",
             f"configuration space of the true map: robot radius {radius:g} m + margin {margin:g} m"]
    lines += [n for n in notes if n]
    lines.append(f"from ({sx:g}, {sy:g}) to ({gx:g}, {gy:g}): straight line {m * _dist(start, goal):.2f} m")
    if planner == "iboa":
        lines.append(f"iboa: {m * result['length']:.2f} m, {len(result['points'])} waypoints "
                     f"(grid path before simplification {m * result['grid_length']:.2f} m), "
                     f"{result['nfev']} evaluations, {elapsed:.2f} s")
    else:
        lines.append(f"astar: {m * result['length']:.2f} m, {len(result['points'])} cells, {elapsed:.2f} s")
    lines.append(f"optimal 8-connected grid path (A*): {m * result['astar']:.2f} m "
                 f"(ratio {result['length'] / result['astar']:.3f})")
    lines.append(f"any-angle shortest path (physical limit): {m * result['any_angle']:.2f} m "
                 f"(ratio {result['length'] / result['any_angle']:.3f})")
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

    draw.line([px(c) for c in result["reference"]], fill=(40, 90, 220), width=max(1, s // 3))
    draw.line([px(c) for c in result["points"]], fill=(220, 30, 30), width=max(2, s // 2 + 1))
    for cell, colour in ((result["points"][0], (20, 160, 40)), (result["points"][-1], (0, 0, 0))):
        x, y = px(cell)
        r = max(3, s)
        draw.ellipse([x - r, y - r, x + r, y + r], fill=colour)
    buf = io.BytesIO()
    add_legend(img, truth, title).save(buf, format="PNG")
    return atomic_write_bytes(output, buf.getvalue())
