"""Where a run's time goes by the kind of code running: ``python benchmarks/profiling/profile_kinds.py PROFILE``.

``PROFILE`` is a raw py-spy profile with native frames of a benchmark, for instance::

    taskset -c 0 py-spy record --native -r 200 -f raw -o prof.txt -- python benchmarks/speed/bench_runtime.py
    python benchmarks/profiling/profile_kinds.py prof.txt

Only samples inside ``Simulation._loop`` count (set-up and imports are left out). Each is classed by its
leaf frame: numba's compiled kernels (frames without symbols, ``?`` in py-spy, are nearly all JIT code),
the Python interpreter, numpy, the C library, zlib, numba's dispatch and cache loading, chipmunk with
pymunk's cffi calls. The split says how much a restructure that moves Python steps into compiled code
could gain at most.
"""

from __future__ import annotations

import argparse
import collections
import re

KINDS = (  # first match wins: a frame in numpy's or numba's own .py files is interpreter work
    ("numba kernels (JIT code)", lambda w: w == "?"),
    ("zlib", lambda w: "libz" in w or "zlib" in w),
    ("Python interpreter", lambda w: ".py:" in w or w.startswith(("<string>", "<frozen", "libpython"))
     or bool(re.match(r"(object|ceval|methodobject)\.", w))),
    ("numpy", lambda w: "numpy" in w or "npy" in w),
    ("chipmunk + pymunk's cffi", lambda w: bool(re.match(r"cp[A-Z]\w*\.[ch]:", w)) or "chipmunk" in w
     or "cffi" in w),
    ("C library (malloc, libm)", lambda w: w.startswith(("libc.", "libm."))),
    ("numba dispatch and cache loading", lambda w: any(k in w for k in ("numba", "llvmlite", "_dispatcher",
                                                                         "typeconv", "_typeof", "_pickle"))),
)


def kind_of(leaf: str) -> str:
    """The kind of code of a py-spy frame ``name (file:line)``."""
    m = re.search(r"\(([^()]*)\)$", leaf)
    where = m.group(1) if m else ""
    for kind, test in KINDS:
        if test(where):
            return kind
    return "other"


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("profile", help="py-spy record --native -f raw output")
    args = ap.parse_args()
    counts: collections.Counter[str] = collections.Counter()
    for line in open(args.profile, encoding="utf-8"):
        line = line.rstrip()
        if "Simulation._loop" not in line:
            continue
        stack, n = line.rsplit(" ", 1)
        counts[kind_of(stack.split(";")[-1])] += int(n)
    total = sum(counts.values())
    if not total:
        raise SystemExit(f"{args.profile}: no samples inside Simulation._loop (was it recorded with --native?)")
    print(f"{total} samples in the run loop")
    for kind, n in counts.most_common():
        print(f"{100 * n / total:5.1f} %  {kind}")


if __name__ == "__main__":
    main()
