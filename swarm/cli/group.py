"""The ``swarm`` command group that every subcommand module registers itself on."""

from __future__ import annotations

import click

CONTEXT = {"help_option_names": ["-h", "--help"], "max_content_width": 100}


@click.group(context_settings=CONTEXT, no_args_is_help=True)
@click.version_option(package_name="swarm-sim", prog_name="swarm")
def cli() -> None:
    """swarm: multi-robot exploration under realistic radio.

    Generate maps, run exploration with Minotaur, TNF, Greed or xBOA over a material-aware radio, and run
    whole campaigns of them.
    """
