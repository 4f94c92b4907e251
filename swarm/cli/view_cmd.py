"""``swarm view run.swr``: write the recording's self-contained replay page and open it in a browser."""

from __future__ import annotations

from pathlib import Path

import click

from .checks import writing
from .group import cli


def open_in_browser(path: Path) -> str | None:
    """Open ``path`` in the default browser; returns a one-line problem, or None if a browser took it.

    ``webbrowser`` returns False (or raises) when it finds no browser, as on a headless CI machine; that is
    not an error of the command, since the page has been written already. Without a display (and no
    ``BROWSER`` chosen) we do not ask: ``webbrowser`` would fall back to a text browser such as lynx, which
    cannot run the viewer and would take over the terminal."""
    import os
    import sys
    import webbrowser

    graphical = sys.platform in ("darwin", "win32") or any(
        os.environ.get(v) for v in ("DISPLAY", "WAYLAND_DISPLAY", "BROWSER"))
    if not graphical:
        return "no display to open a browser on"
    try:
        opened = webbrowser.open(path.resolve().as_uri())
    except Exception as exc:  # webbrowser raises whatever the launcher raises
        return f"could not open a browser ({type(exc).__name__}: {exc})"
    return None if opened else "no browser found"


@cli.command("view")
@click.argument("recording", type=click.Path(dir_okay=False, path_type=Path))
@click.option("-o", "--output", type=click.Path(dir_okay=False, path_type=Path), default=None,
              help="Where to write the page. [default: RECORDING with .html]")
@click.option("--no-open", is_flag=True, help="Only write the page; do not start a browser.")
def view_cmd(recording: Path, output: Path | None, no_open: bool) -> None:
    """Write a self-contained HTML replay of RECORDING (from 'swarm run --record') and open it.

    The page holds the recording and the viewer script: it needs no server and no network, so it can be
    mailed or archived as one file.
    """
    from swarm.base.errors import InvalidInput

    from swarm.viewer import write_html

    out = output if output is not None else recording.with_suffix(".html")
    if out.resolve() == recording.resolve():
        raise InvalidInput("--output", str(out), "a path other than the recording itself")
    with writing("--output", out):
        written = write_html(recording, out)
    click.echo(f"wrote {written}")
    if not no_open:
        problem = open_in_browser(written)
        if problem:
            click.echo(f"swarm: {problem}; open {written} yourself", err=True)
