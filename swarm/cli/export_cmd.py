"""``swarm export run.swr``: a recording as an MCAP file of ROS 2 messages, for Foxglove and ``ros2 bag play``."""

from __future__ import annotations

from pathlib import Path

import click

from .checks import check_output_path, writing
from .group import cli

MAP_EVERY_HELP = "ticks between robot map (and doorway) messages; a map is sent only if it changed"


@cli.command("export")
@click.argument("recording", type=click.Path(dir_okay=False, path_type=Path))
@click.option("-o", "--output", type=click.Path(dir_okay=False, path_type=Path), default=None,
              help="Where to write the MCAP file. [default: RECORDING with .mcap]")
@click.option("--map-every", type=click.IntRange(1, 1_000_000), default=10, show_default=True,
              help=f"The {MAP_EVERY_HELP}.")
def export_cmd(recording: Path, output: Path | None, map_every: int) -> None:
    """Export RECORDING (from 'swarm run --record') as MCAP with ROS 2 messages: open it in Foxglove with
    docs/foxglove-layout.json, or play it with 'ros2 bag play' (docs/ros2.md)."""
    from swarm.base.errors import InvalidInput
    from swarm.ros2 import require_extra

    require_extra("export", str(recording), "a recording to export")
    out = output if output is not None else recording.with_suffix(".mcap")
    if out.resolve() == recording.resolve():
        raise InvalidInput("--output", str(out), "a path other than the recording itself")
    check_output_path("--output", out)
    from swarm.ros2.mcap_export import export_recording

    with writing("--output", out):
        written = export_recording(recording, out, map_every)
    click.echo(f"wrote {written}")
