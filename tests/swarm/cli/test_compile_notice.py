"""`swarm run` says so on a terminal when numba compiles its kernels (one line, then a live counter), and
prints nothing extra otherwise."""

from __future__ import annotations

import io

import numpy as np
from numba import njit

from swarm.cli.compile_notice import NOTE, compile_notice


class _Terminal(io.StringIO):
    def isatty(self) -> bool:
        return True


def _fresh_kernel():
    @njit  # no cache: compiled on its first call in every process
    def total(a):
        return a.sum() + 1.0

    return total


def test_a_terminal_gets_one_note_and_a_counter_of_what_compiled():
    out = _Terminal()
    with compile_notice(out) as progress:
        assert _fresh_kernel()(np.ones(2)) == 3.0
        assert _fresh_kernel()(np.ones(3)) == 4.0
    text = out.getvalue()
    assert text.count(NOTE) == 1 and text.startswith(NOTE + "\n")
    assert progress.watch.compiled >= 2 and progress.watch.seconds > 0
    final = text.replace("\r", "\n").strip().splitlines()[-1]
    assert final.startswith(f"compiling: {progress.watch.compiled} functions [")


def test_nothing_when_nothing_compiles_or_the_stream_is_not_a_terminal():
    kernel = _fresh_kernel()
    kernel(np.ones(2))  # compiled before the block
    warm = _Terminal()
    with compile_notice(warm):
        assert kernel(np.ones(5)) == 6.0
    assert _fresh_kernel()(np.ones(2)) == 3.0  # after the block: its listener is gone
    assert warm.getvalue() == ""
    piped = io.StringIO()
    with compile_notice(piped):
        assert _fresh_kernel()(np.ones(2)) == 3.0
    assert piped.getvalue() == ""
