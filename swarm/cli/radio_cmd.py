"""``swarm radio``: one link budget itemised, or the RSSI field of a transmitter over a map."""

from __future__ import annotations

from pathlib import Path
from typing import Any, Callable

import click

from .checks import writing
from .group import cli
from .options import FLOAT, POINT, Choice, IntRange, parse_params
from .options import Path as PathType

# CLI flag -> RadioConfig field, so a bad value names the flag the user typed.
_FLAGS = {"--model": "model", "--freq": "frequency_ghz", "--tx-power": "tx_power_dbm",
          "--sensitivity": "sensitivity_dbm", "--wall-mode": "wall_mode", "--max-range": "max_range_m"}


@cli.group("radio")
def radio_group() -> None:
    """Link budgets and RSSI maps over a map file (Minotaur paper eqs. 1-2, per-material walls)."""


def radio_options(func: Callable[..., Any]) -> Callable[..., Any]:
    """The radio flags shared by the subcommands."""
    options = [
        click.argument("path", type=PathType(exists=True, dir_okay=False, path_type=Path)),
        click.option("--model", type=Choice(["multiwall", "global", "los", "maes"]), default=None,
                     help="Link model [default: multiwall]."),
        click.option("--freq", type=FLOAT, default=None, metavar="GHZ", help="Carrier frequency [default: 2.4]."),
        click.option("--tx-power", type=FLOAT, default=None, metavar="DBM", help="Transmit power [default: 15]."),
        click.option("--sensitivity", type=FLOAT, default=None, metavar="DBM",
                     help="Receiver sensitivity [default: -82]."),
        click.option("--wall-mode", type=Choice(["crossing", "per_metre"]), default=None,
                     help="Charge walls per crossing or per metre of wall [default: crossing]."),
        click.option("--max-range", type=FLOAT, default=None, metavar="M", help="Range limit in metres (implies --model los)."),
        click.option("--config", "config_path", type=PathType(exists=True, dir_okay=False, path_type=Path),
                     help="TOML file with radio settings (its [radio] table, or top-level keys)."),
        click.option("--param", "params", multiple=True, metavar="KEY=VALUE",
                     help="Radio setting (repeatable), e.g. --param materials.glass=[2,2.5,3]."),
    ]
    for option in reversed(options):
        func = option(func)
    return func


def _load(path: Path, config_path: Path | None, params: tuple[str, ...], flags: dict[str, Any]):
    """The map and its link model from the flags (flags override --param, which overrides --config)."""
    from collections.abc import Mapping

    from maps.io import MAX_LEGEND_BYTES, load_map, parse_toml, read_file_bytes
    from radio import build_link_model, config_from_mapping
    from swarm.base.errors import InvalidInput

    data: dict[str, Any] = {}
    if config_path is not None:
        try:
            text = read_file_bytes(config_path, "--config", MAX_LEGEND_BYTES).decode("utf-8")
        except UnicodeDecodeError:
            raise InvalidInput("--config", str(config_path), "a UTF-8 TOML file") from None
        raw = parse_toml(text, "--config", str(config_path))
        section = raw.get("radio", raw)
        if not isinstance(section, Mapping):
            raise InvalidInput("--config", str(config_path), "a TOML file whose [radio] is a table of settings")
        data = dict(section)
    data.update(parse_params(params))
    set_flags = {flag: value for flag, value in flags.items() if value is not None}
    for flag, value in set_flags.items():
        data[_FLAGS[flag]] = value
    if set_flags.get("--max-range") is not None and "model" not in data:
        data["model"] = "los"
    try:
        config = config_from_mapping(data)
    except InvalidInput as exc:
        flag = next((f for f, name in _FLAGS.items() if name == exc.field and f in set_flags), None)
        if flag is None:
            raise
        raise InvalidInput(flag, exc.value, exc.allowed) from None
    truth = load_map(path)
    return truth, build_link_model(truth, config)


def _check_inside(truth: Any, flag: str, point: tuple[float, float]) -> None:
    from swarm.base.errors import InvalidInput

    if not truth.contains(*point):
        raise InvalidInput(flag, f"{point[0]:g},{point[1]:g}",
                           f"a point inside the map: 0 <= x < {truth.width_m:g}, 0 <= y < {truth.height_m:g}")


def _flags(model: str | None, freq: float | None, tx_power: float | None, sensitivity: float | None,
           wall_mode: str | None, max_range: float | None) -> dict[str, Any]:
    return {"--model": model, "--freq": freq, "--tx-power": tx_power, "--sensitivity": sensitivity,
            "--wall-mode": wall_mode, "--max-range": max_range}


@radio_group.command("link")
@radio_options
@click.option("--from", "src", type=POINT, required=True, help="Transmitter x,y in metres.")
@click.option("--to", "dst", type=POINT, required=True, help="Receiver x,y in metres.")
def link_cmd(path: Path, model: str | None, freq: float | None, tx_power: float | None, sensitivity: float | None,
             wall_mode: str | None, max_range: float | None, config_path: Path | None, params: tuple[str, ...],
             src: tuple[float, float], dst: tuple[float, float]) -> None:
    """Itemise the link budget from --from (transmitter) to --to (receiver).

    Prints the distance, every wall crossed with its materials, the path loss (eq. 1), the RSSI, the margin
    over the receiver sensitivity and the verdict (eq. 2).
    """
    truth, link_model = _load(path, config_path, params,
                              _flags(model, freq, tx_power, sensitivity, wall_mode, max_range))
    _check_inside(truth, "--from", src)
    _check_inside(truth, "--to", dst)
    for line in format_budget(link_model, src, dst):
        click.echo(line)


def format_budget(link_model: Any, src: tuple[float, float], dst: tuple[float, float]) -> list[str]:
    """The lines ``swarm radio link`` prints."""
    c = link_model.config
    b = link_model.budget(src, dst)
    lines = [f"map: {link_model.truth.summary()}"]
    describe = {"multiwall": f"path loss (eq. 1, alpha {c.alpha:g}, beta {c.beta:g}, gamma {c.gamma:g}) "
                             f"+ walls per {'crossing' if c.wall_mode == 'crossing' else 'metre'}",
                "maes": "MAES-compatible: no distance term, walls per 0.25 m of wall path",
                "los": "line of sight" + (f", range {c.max_range_m:g} m" if c.max_range_m else ""),
                "global": "global: every message arrives"}[b.model]
    lines.append(f"model: {b.model} ({describe}), {c.frequency_ghz:g} GHz")
    lines.append(f"from ({src[0]:g}, {src[1]:g}) to ({dst[0]:g}, {dst[1]:g}): distance {b.distance_m:.2f} m")
    for name, point in (("from", src), ("to", dst)):
        if not link_model.truth.is_free_at(*point):
            lines.append(f"note: the '{name}' point is inside a wall")
    lines.append(f"walls crossed: {len(b.walls)}")
    for k, wall in enumerate(b.walls, 1):
        mats = " + ".join(f"{name} {metres:.2f} m" for name, metres in wall.materials)
        price = f" -> {wall.db:.2f} dB (charged: {', '.join(wall.charged)})" if link_model.prices_walls else ""
        lines.append(f"  {k}. at {wall.start_m:.2f}-{wall.end_m:.2f} m: {mats}{price}")
    if b.model == "multiwall":
        lines.append(f"path loss: {b.path_loss_db:.2f} dB")
    if b.model in ("multiwall", "maes"):
        lines.append(f"wall loss: {b.wall_db:.2f} dB")
    if link_model.shadowing is not None:
        lines.append(f"shadowing: {b.shadowing_db:+.2f} dB (sigma {c.shadowing_sigma_db:g} dB, correlated over "
                     f"{c.shadowing_corr_m:g} m, field of map seed {link_model.truth.seed or 0})")
    lines.append(f"tx power: {b.tx_power_dbm:.2f} dBm")
    lines.append(f"RSSI: {b.rssi_dbm:.2f} dBm")
    lines.append(f"sensitivity: {b.sensitivity_dbm:.2f} dBm")
    lines.append(f"margin: {b.margin_db:+.2f} dB" if b.model in ("multiwall", "maes") else "margin: -")
    if b.link:
        verdict = "link OK"
    elif b.model == "los":
        verdict = "no link (" + ("wall in the way" if b.walls else "out of range") + ")"
    else:
        verdict = f"no link (short by {-b.margin_db:.2f} dB)"
    lines.append(f"verdict: {verdict}")
    curve = link_model.packet_errors
    if curve is not None:
        pers = ", ".join(f"{size} B {100 * float(curve.per(b.margin_db, size)):.3g} %" for size in (100, 1000, 4096))
        lines.append(f"packet error rate ({c.per}): {pers}")
    return lines


@radio_group.command("heatmap")
@radio_options
@click.option("--tx", type=POINT, required=True, help="Transmitter x,y in metres.")
@click.option("-o", "--output", type=PathType(dir_okay=False, path_type=Path), required=True,
              help="Write the picture (.png).")
@click.option("--scale", type=IntRange(1, 32), default=None, help="Pixels per 0.5 m cell.")
def heatmap_cmd(path: Path, model: str | None, freq: float | None, tx_power: float | None,
                sensitivity: float | None, wall_mode: str | None, max_range: float | None,
                config_path: Path | None, params: tuple[str, ...], tx: tuple[float, float], output: Path,
                scale: int | None) -> None:
    """Render the RSSI received from --tx at every free cell, with the sensitivity contour."""
    import time

    from maps.render import check_scale
    from radio.heatmap import rssi_field, save_heatmap

    truth, link_model = _load(path, config_path, params,
                              _flags(model, freq, tx_power, sensitivity, wall_mode, max_range))
    _check_inside(truth, "--tx", tx)
    check_scale(truth, scale, "--scale")
    t0 = time.perf_counter()
    field = rssi_field(link_model, tx)
    elapsed = time.perf_counter() - t0
    c = link_model.config
    click.echo(f"{truth.summary()}")
    click.echo(f"{link_model.name} at {c.frequency_ghz:g} GHz from ({tx[0]:g}, {tx[1]:g}): "
               f"{100 * field.linked_share:.1f}% of free space hears the transmitter "
               f"(sensitivity {field.sensitivity_dbm:g} dBm; computed in {elapsed * 1000:.0f} ms)")
    title = f"{path.name}: RSSI from ({tx[0]:g}, {tx[1]:g}), {link_model.name}, {c.frequency_ghz:g} GHz"
    with writing("--output", output):
        click.echo(f"wrote {save_heatmap(truth, field, output, scale=scale, title=title)}")

