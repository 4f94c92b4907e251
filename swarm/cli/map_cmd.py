"""``swarm map``: generate, show, import and export maps."""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING

import click

from .checks import writing
from .group import cli
from .options import Choice, IntRange, parse_params
from .options import Path as PathType

if TYPE_CHECKING:
    from maps import Map


@cli.group("map")
def map_group() -> None:
    """Generate, render, import and export ground-truth maps."""


def _generated(kind: str, size: str, seed: int, params: tuple[str, ...]) -> Map:
    """The map ``--kind --size --seed --param`` describe; a bad size names ``--size``."""
    from maps import generate, parse_size
    from swarm.base.errors import InvalidInput

    try:
        parse_size(size)
    except InvalidInput as exc:
        raise InvalidInput("--size", size, exc.allowed) from None
    return generate(kind, size, seed, parse_params(params))


@map_group.command("generate")
@click.option("--kind", type=Choice(["building", "cave"]), default="building", show_default=True)
@click.option("--size", default="100", show_default=True, metavar="N|WxH",
              help="Tiles (1 m) per side, >= 20; e.g. 100 or 120x80.")
@click.option("--seed", type=IntRange(0, 2**63 - 1), default=0, show_default=True)
@click.option("--param", "params", multiple=True, metavar="KEY=VALUE",
              help="Generator parameter (repeatable), e.g. --param fill_percent=45; see 'swarm map params'.")
@click.option("-o", "--output", type=PathType(dir_okay=False, path_type=Path), help="Write the map (.npz).")
@click.option("--png", type=PathType(dir_okay=False, path_type=Path), help="Write a picture (.png).")
@click.option("--scale", type=IntRange(1, 32), default=None, help="Pixels per 0.5 m cell in the picture.")
def generate_cmd(kind: str, size: str, seed: int, params: tuple[str, ...], output: Path | None, png: Path | None,
                 scale: int | None) -> None:
    """Generate a cave or building map.

    With neither -o nor --png, writes KIND-SIZE-sSEED.png in the current folder.
    """
    import time

    from maps.io import save_npz
    from maps.render import check_scale, save_png

    t0 = time.perf_counter()
    m = _generated(kind, size, seed, params)
    elapsed = time.perf_counter() - t0
    if output is None and png is None:
        png = Path(f"{kind}-{size}-s{seed}.png")
    if png is not None:
        check_scale(m, scale, "--scale")  # before writing anything
    click.echo(f"{m.summary()} (generated in {elapsed * 1000:.0f} ms)")
    if output is not None:
        with writing("--output", output):
            click.echo(f"wrote {save_npz(m, output)}")
    if png is not None:
        with writing("--png", png):
            click.echo(f"wrote {save_png(m, png, scale=scale, title=f'{kind} {size} seed {seed}')}")


@map_group.command("params")
@click.argument("kind", type=Choice(["building", "cave"]))
def params_cmd(kind: str) -> None:
    """List a generator's parameters with their defaults."""
    import dataclasses

    from maps import params_for

    p = params_for(kind)
    for f in dataclasses.fields(p):
        auto = "  # left out: chosen to fit the other values" if f.default is None else ""
        click.echo(f"{f.name} = {getattr(p, f.name)!r}{auto}")


@map_group.command("show")
@click.argument("path", type=PathType(exists=True, dir_okay=False, path_type=Path))
@click.option("-o", "--output", type=PathType(dir_okay=False, path_type=Path), help="Write a picture (.png).")
@click.option("--legend", type=PathType(exists=True, dir_okay=False, path_type=Path),
              help="Legend TOML when PATH is an image.")
@click.option("--scale", type=IntRange(1, 32), default=None, help="Pixels per 0.5 m cell.")
def show_cmd(path: Path, output: Path | None, legend: Path | None, scale: int | None) -> None:
    """Describe a map file and optionally render it."""
    from maps.io import load_map
    from maps.render import check_scale, save_png

    m = load_map(path, legend=legend)
    if output is not None:
        check_scale(m, scale, "--scale")
    click.echo(m.summary())
    if output is not None:
        with writing("--output", output):
            click.echo(f"wrote {save_png(m, output, scale=scale, title=path.name)}")


@map_group.command("import")
@click.argument("path", type=PathType(exists=True, dir_okay=False, path_type=Path))
@click.option("--legend", type=PathType(exists=True, dir_okay=False, path_type=Path),
              help="Legend TOML mapping colours to materials (images); not needed for .pgm (MAES), .csv (xBOA), "
                   ".yaml (ROS map_server) and .json (HouseExpo).")
@click.option("-o", "--output", type=PathType(dir_okay=False, path_type=Path), required=True,
              help="Write the map (.npz).")
@click.option("--png", type=PathType(dir_okay=False, path_type=Path), help="Also write a picture.")
@click.option("--material", default=None, help="Wall material for .pgm/.csv/.yaml/.json walls (default concrete).")
@click.option("--border", type=IntRange(0, 10), default=0, show_default=True,
              help="Add a wall border this many tiles thick.")
@click.option("--border-material", default="concrete", show_default=True)
@click.option("--plan-scale", type=float, default=None,
              help="HouseExpo .json and ROS .yaml: multiply the map's metres (default 1; 2.5 lets the default "
                   "robot through HouseExpo's 0.8 m doors, 1.5 through Explore-Bench's 1.4 m ones).")
def import_cmd(path: Path, legend: Path | None, output: Path, png: Path | None, material: str | None, border: int,
               border_material: str, plan_scale: float | None) -> None:
    """Import a floor plan: an image with a legend, a MAES ASCII PGM, an xBOA 0/1 CSV, a ROS map_server YAML or a
    HouseExpo JSON plan."""
    from maps.io import load_map, save_npz
    from maps.materials import check_known_material
    from maps.render import save_png
    from swarm.base.errors import InvalidInput

    if path.suffix.lower() == ".npz":
        for flag, value, unset in (("--material", material, None), ("--border", border, 0),
                                   ("--legend", legend, None)):
            if value != unset:
                raise InvalidInput(flag, str(value),
                                   "only for .pgm, .csv, .yaml, .json and image files (a .npz is a swarm map)")
    check_known_material(border_material, "--border-material")
    options: dict[str, object] = {"border": border, "border_material": border_material}
    if material is not None:
        if legend is not None:
            raise InvalidInput("--material", material,
                               "only for .pgm, .csv, .yaml and .json files (images take materials from the legend)")
        check_known_material(material, "--material")
        options["material"] = material
    if plan_scale is not None:
        if path.suffix.lower() not in (".json", ".yaml", ".yml"):
            raise InvalidInput("--plan-scale", plan_scale, "only for HouseExpo .json plans and ROS .yaml maps")
        from maps.houseexpo import check_scale

        options["scale"] = check_scale(plan_scale, "--plan-scale")
    m = load_map(path, legend=legend, **options)
    click.echo(m.summary())
    with writing("--output", output):
        click.echo(f"wrote {save_npz(m, output)}")
    if png is not None:
        with writing("--png", png):
            click.echo(f"wrote {save_png(m, png, title=path.name)}")


@map_group.command("export")
@click.argument("path", required=False, type=PathType(exists=True, dir_okay=False, path_type=Path))
@click.option("--kind", type=Choice(["building", "cave"]), default=None, help="Export a generated map instead of PATH.")
@click.option("--size", default=None, metavar="N|WxH", help="With --kind: tiles (1 m) per side [default: 100].")
@click.option("--seed", type=IntRange(0, 2**63 - 1), default=None, help="With --kind [default: 0].")
@click.option("--param", "params", multiple=True, metavar="KEY=VALUE", help="With --kind: a generator parameter.")
@click.option("--ros", "ros_yaml", type=PathType(dir_okay=False, path_type=Path), required=True,
              help="Write ROS map_server files: this .yaml and the .pgm image next to it.")
def export_cmd(path: Path | None, kind: str | None, size: str | None, seed: int | None, params: tuple[str, ...],
               ros_yaml: Path) -> None:
    """Export a map file (PATH) or a generated map (--kind) for ROS map_server and nav2.

    Writes what map_saver writes in trinary mode: free cells 254, walls 0, 0.5 m per pixel, and the origin
    a ROS import recorded (else 0, 0), so a map imported from ROS goes back where it came from.
    """
    from maps.io import load_map, save_ros
    from maps.ros import ros_image_path
    from swarm.base.errors import InvalidInput

    with writing("--ros", ros_yaml):
        ros_image_path(ros_yaml)  # a bad name fails before any work
    if (path is None) == (kind is None):
        raise InvalidInput("PATH", None if path is None else str(path), "a map file or --kind (not both)")
    if path is not None:
        for flag, value in (("--size", size), ("--seed", seed), ("--param", params or None)):
            if value is not None:
                raise InvalidInput(flag, value, "only with --kind (PATH is a map file)")
        m = load_map(path)
    else:
        m = _generated(kind, "100" if size is None else size, 0 if seed is None else seed, params)
    click.echo(m.summary())
    with writing("--ros", ros_yaml):
        written = save_ros(m, ros_yaml)
    click.echo(f"wrote {written[0]} and {written[1]}")
