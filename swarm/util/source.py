"""Which source code computes a run: swarm's package version and, from a git checkout, its commit.

A package version (``0.1.0``) stays the same across many commits, so a runs table that records only the
version cannot say which code made a row (the MAES-parity ablation's rerun found one row of 2,880 that no
committed version reproduces, and nothing recorded what had made it). Runs made from a git work tree (an
editable install, ``PYTHONPATH`` on a checkout) therefore also record the commit, marked ``dirty`` when
tracked files differ from it. An installed wheel has no work tree: its version is all there is.
"""

from __future__ import annotations

import functools
import subprocess
from importlib.metadata import PackageNotFoundError, version
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
"""The directory the ``swarm`` package lives in (this file is ``swarm/util/source.py``): a checkout's root
when swarm runs from one."""


@functools.cache
def package_version() -> str | None:
    """The installed distribution's version (``swarm-sim``), or None in a source tree never installed."""
    try:
        return version("swarm-sim")
    except PackageNotFoundError:
        return None


@functools.cache
def source_commit() -> str | None:
    """The commit of the git work tree this swarm is imported from (12 hex digits), with ``-dirty`` when a
    tracked file differs from it; None outside a work tree or without a working ``git``. Asked once per
    process (two ``git`` calls, ~10 ms)."""
    if not (ROOT / ".git").exists():  # a directory in a clone, a file in a worktree
        return None
    try:
        head = _git("rev-parse", "--short=12", "HEAD")
        changed = _git("status", "--porcelain", "--untracked-files=no")
    except (OSError, subprocess.SubprocessError):
        return None
    return head + ("-dirty" if changed else "") if head else None


def version_label() -> str:
    """The version a results table records: ``0.1.0``, or ``0.1.0+git.<commit>[-dirty]`` from a work tree
    (``unknown`` for a source tree never installed)."""
    base = package_version() or "unknown"
    commit = source_commit()
    return f"{base}+git.{commit}" if commit else base


def _git(*args: str) -> str:
    out = subprocess.run(["git", "-C", str(ROOT), *args], capture_output=True, text=True, timeout=20, check=True)
    return out.stdout.strip()
