"""The README's quick start from a truly fresh state: a fresh clone, a fresh venv, ``pip install .`` from
PyPI (no pip cache), then ``swarm campaign run`` with empty numba, matplotlib and swarm caches.

Prints the time of each step, the time to the campaign's first output line, its total, and how much of it
numba spent compiling (the campaign's own summary line), with the machine's load average before and after
(a shared machine's other work slows every figure; rerun when it is idle for a fresh-machine figure).
``--warm`` then runs the quick campaign a second time in a new folder (kernels cached).

    python benchmarks/speed/bench_first_run.py                 # clone this checkout's HEAD
    python benchmarks/speed/bench_first_run.py --keep /tmp/fresh --warm
"""

from __future__ import annotations

import argparse
import fcntl
import os
import pty
import resource
import struct
import termios
import select
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]


def load() -> str:
    return " ".join(Path("/proc/loadavg").read_text().split()[:3]) if Path("/proc/loadavg").exists() else "?"


def cpu() -> float:
    """CPU seconds (user + system) of this process's finished children and theirs (a campaign's workers)."""
    r = resource.getrusage(resource.RUSAGE_CHILDREN)
    return r.ru_utime + r.ru_stime


def timed(argv: list[str], cwd: Path, env: dict[str, str]) -> float:
    t0 = time.monotonic()
    subprocess.run(argv, cwd=cwd, env=env, check=True, stdout=subprocess.DEVNULL, stderr=subprocess.STDOUT)
    return time.monotonic() - t0


def on_terminal(argv: list[str], cwd: Path, env: dict[str, str]) -> tuple[float, float, list[tuple[float, str]]]:
    """Run ``argv`` with stdout and stderr on one pseudo-terminal, as a user would see it: (seconds to the
    first output, total seconds, [(time, line)] of the output; bar redraws kept as separate lines)."""
    master, slave = pty.openpty()
    fcntl.ioctl(slave, termios.TIOCSWINSZ, struct.pack("HHHH", 40, 110, 0, 0))
    t0 = time.monotonic()
    p = subprocess.Popen(argv, cwd=cwd, env=env, stdout=slave, stderr=slave)
    os.close(slave)
    first = None
    lines: list[tuple[float, str]] = []
    buf = b""
    while True:
        ready, _, _ = select.select([master], [], [], 0.5)
        if ready:
            try:
                chunk = os.read(master, 65536)
            except OSError:
                break
            if not chunk:
                break
            now = time.monotonic() - t0
            first = now if first is None else first
            buf += chunk
            *done, buf = buf.replace(b"\r", b"\n").split(b"\n")
            lines += [(now, d.decode(errors="replace")) for d in done if d.strip()]
        elif p.poll() is not None:
            break
    p.wait()
    if p.returncode:
        raise SystemExit(f"{' '.join(argv)} failed ({p.returncode}):\n" + "\n".join(t for _, t in lines[-20:]))
    return first if first is not None else float("nan"), time.monotonic() - t0, lines


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--source", default=str(ROOT), help="repository to clone (default: this checkout)")
    ap.add_argument("--keep", default=None, help="work in this folder and keep it (default: a temporary one)")
    ap.add_argument("--warm", action="store_true", help="also time a second quick campaign (warm caches)")
    ap.add_argument("--python", default=sys.executable, help="interpreter that makes the venv")
    args = ap.parse_args()
    work = Path(args.keep or tempfile.mkdtemp(prefix="swarm-first-run-"))
    if work.exists() and any(work.iterdir()):
        raise SystemExit(f"{work} is not empty")
    work.mkdir(parents=True, exist_ok=True)
    env = {k: v for k, v in os.environ.items() if k not in ("PYTHONPATH", "VIRTUAL_ENV", "NUMBA_CACHE_DIR")}
    env.update(XDG_CACHE_HOME=str(work / "cache"), MPLCONFIGDIR=str(work / "mpl"), PIP_NO_CACHE_DIR="1",
               COLUMNS="100", LINES="40")
    print(f"load average before: {load()}; {os.cpu_count()} cores; work in {work}")
    head = subprocess.run(["git", "-C", args.source, "rev-parse", "--short", "HEAD"], capture_output=True,
                          text=True).stdout.strip()
    t = timed(["git", "clone", "--quiet", "--no-hardlinks", args.source, str(work / "swarm")], work, env)
    print(f"git clone ({head}): {t:.1f} s")
    t = timed([args.python, "-m", "venv", str(work / "venv")], work, env)
    print(f"python -m venv: {t:.1f} s")
    pip = str(work / "venv" / "bin" / "pip")
    c0 = cpu()
    t = timed([pip, "install", "--quiet", "."], work / "swarm", env)
    print(f"pip install . (from PyPI, no cache): {t:.0f} s ({cpu() - c0:.0f} s CPU)")
    run_dir = work / "quick"
    run_dir.mkdir()
    swarm = str(work / "venv" / "bin" / "swarm")
    c0 = cpu()
    first, total, lines = on_terminal([swarm, "campaign", "run"], run_dir, env)
    print(f"swarm campaign run (fresh caches): first output after {first:.1f} s, total {total:.0f} s "
          f"({cpu() - c0:.0f} s CPU in all its processes)")
    shown = [(t, text) for t, text in lines if not text.startswith(("runs:", "warm-up run", "report:"))]
    bars = [(t, text) for t, text in lines if text.startswith(("runs:", "warm-up run", "report:"))]
    for t, text in shown:
        print(f"  {t:6.1f} s  {text}")
    for prefix in ("warm-up run", "runs:", "report:"):
        first_bar = next(((t, x) for t, x in bars if x.startswith(prefix)), None)
        last_bar = next(((t, x) for t, x in reversed(bars) if x.startswith(prefix)), None)
        if first_bar:
            print(f"  {first_bar[0]:6.1f} s  first: {first_bar[1][:110]}")
            print(f"  {last_bar[0]:6.1f} s  last:  {last_bar[1][:110]}")
    if args.warm:
        again = work / "quick-again"
        again.mkdir()
        c0 = cpu()
        first, total, _ = on_terminal([swarm, "campaign", "run"], again, env)
        print(f"swarm campaign run again (warm caches): first output after {first:.1f} s, total {total:.0f} s "
              f"({cpu() - c0:.0f} s CPU)")
    print(f"load average after: {load()}")
    if args.keep is None:
        shutil.rmtree(work, ignore_errors=True)


if __name__ == "__main__":
    main()
