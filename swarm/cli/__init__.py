"""The ``swarm`` command line.

Built on click: nested subcommands, ``--help`` everywhere, typed options. :func:`main` is the single
funnel for errors: a bad flag, value or input file prints one line ``swarm: error: ...`` naming the flag
or field, the value and what is allowed, and exits with status 2, without a traceback.
Subcommand modules import heavy dependencies inside their functions so ``swarm --help`` stays fast.
The top of the runtime: may import any package of swarm, maps and radio.
"""

from __future__ import annotations

import signal
import threading

import click

from swarm.base.errors import InvalidInput

from .group import cli

__all__ = ["cli", "main"]


def _register() -> None:
    from . import map_cmd, run_cmd  # noqa: F401  (commands register themselves on import)
    from . import radio_cmd  # noqa: F401
    from . import view_cmd  # noqa: F401
    from . import export_cmd  # noqa: F401
    from . import plan_cmd  # noqa: F401
    from . import campaign_cmd  # noqa: F401


def _usage_message(exc: click.UsageError) -> str:
    from .options import short_message

    lines = exc.format_message().strip().splitlines()
    msg = short_message(lines[0]) if lines else "invalid usage"
    ctx = exc.ctx
    if isinstance(exc, click.BadParameter) or ctx is None:
        return msg  # click already names the flag, the value and the allowed range or choices
    if isinstance(ctx.command, click.Group) and msg.startswith("No such command"):
        return f"{msg} (allowed: {', '.join(ctx.command.list_commands(ctx))})"
    return f"{msg} (see '{ctx.command_path} --help')"


def _terminated(signum: int, frame: object) -> None:
    """SIGTERM (``kill``, a batch system's time limit) unwinds like Ctrl-C: what finished is written, pool
    workers are stopped, locks are released; the command exits 143."""
    raise SystemExit(128 + signum)


def main(argv: list[str] | None = None) -> int:
    """Entry point of the ``swarm`` console command; returns the exit status."""
    _register()
    if threading.current_thread() is threading.main_thread() and signal.getsignal(signal.SIGTERM) is signal.SIG_DFL:
        signal.signal(signal.SIGTERM, _terminated)
    try:
        status = cli.main(args=argv, prog_name="swarm", standalone_mode=False)
        if isinstance(status, int) and not isinstance(status, bool):  # click returns an Exit's code here
            return status
    except click.exceptions.NoArgsIsHelpError as exc:
        click.echo(exc.ctx.get_help() if exc.ctx else exc.format_message())
        return 0
    except click.UsageError as exc:
        click.echo(f"swarm: error: {_usage_message(exc)}", err=True)
        return 2
    except InvalidInput as exc:
        click.echo(f"swarm: error: {exc}", err=True)
        return 2
    except click.exceptions.Exit as exc:
        return exc.exit_code
    except click.Abort:
        click.echo("swarm: aborted", err=True)
        return 130
    except KeyboardInterrupt:
        click.echo("swarm: interrupted", err=True)
        return 130
    except BrokenPipeError:
        return 0
    return 0

