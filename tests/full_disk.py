"""A full disk, simulated: the ``swarm`` command line run in a subprocess whose ``os.fsync`` fails with ENOSPC.

Every output swarm writes is fsynced before its atomic rename (``maps.io.atomic_write_bytes``, the campaign's
part files), so failing ``fsync`` is where a real full disk (or quota) is reported at the latest. Only files
whose path contains ``FAIL_NAME`` fail, from the ``FAIL_AT``-th fsync of such a file on (1: the first).
"""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]

FAILING_FSYNC = """
import errno, os, sys
real, calls = os.fsync, [0]
def fsync(fd):
    name = os.readlink(f"/proc/self/fd/{fd}")
    if os.environ["FAIL_NAME"] in name:
        calls[0] += 1
        if calls[0] >= int(os.environ["FAIL_AT"]):
            raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))
    return real(fd)
os.fsync = fsync  # the disk fills up: every write of a matching file from the FAIL_AT-th on fails
from swarm.cli import main
sys.exit(main(sys.argv[1:]))
"""

SUPPORTED = Path("/proc/self/fd").exists()
"""The simulation reads file names from /proc (Linux)."""


def run_on_full_disk(args: list[str], fail_name: str, fail_at: int = 1, timeout: float = 240,
                     cwd: Path = ROOT) -> subprocess.CompletedProcess[str]:
    """``swarm ARGS`` in a subprocess where fsyncing a file whose path holds ``fail_name`` fails with ENOSPC."""
    env = {**os.environ, "FAIL_NAME": fail_name, "FAIL_AT": str(fail_at)}
    return subprocess.run([sys.executable, "-c", FAILING_FSYNC, *args], capture_output=True, text=True, check=False,
                          timeout=timeout, env=env, cwd=cwd)
