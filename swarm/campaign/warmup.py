"""Compile numba's kernels once, in this process, before the workers start.

After an install (or an update) numba's disk cache is empty, and every pool worker would compile the same
kernels on its first runs: about a minute each, in silence, with a first ETA of hours. Instead the runner
first executes a few of the campaign's own runs here, chosen so that every algorithm, radio model, map
kind, map size, transport, lidar mode, map-sharing mode and planner of the campaign (and a lone robot and
a team, where the campaign has them) is met at least once, cheapest cells first, while
:class:`swarm.util.progress.CompileProgress` shows numba compiling. The workers then load the compiled kernels
from the cache. The warm-up runs are ordinary runs of the campaign: their rows are committed like any
other, nothing is computed twice.

Whether the cache is warm is told by a stamp (:func:`stamp_path`, in the user's cache folder): the features
a warm-up met, and for every kernel it left in numba's cache the index file and the source file it was
compiled from, with their modification times. A campaign whose features the stamp covers, and whose
recorded files are all unchanged, skips the warm-up; checking costs a few stat calls. Anything unexpected
(no stamp, an unreadable one, numba internals that moved) means "not known to be warm": a warm-up then
costs a few seconds of loading kernels from the cache, never a wrong result.
"""

from __future__ import annotations

import hashlib
import json
import os
import sys
from collections.abc import Iterable, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from .spec import CampaignSpec

MAX_WARMUP_RUNS = 16
"""At most this many runs before the workers start (a campaign with more features leaves the rest to them)."""
STAMP_VERSION = 1


def features(spec: dict[str, Any]) -> frozenset[str]:
    """What decides which kernels (and argument types) a run compiles, from its canonical spec."""
    size = spec["map"].get("size")
    radio = spec.get("radio", {})
    return frozenset({
        f"algorithm={spec['algorithm']['name']}",
        f"radio={radio.get('model')}/{radio.get('wall_mode')}",
        f"map={spec['map']['kind']}",
        f"size={'x'.join(map(str, size)) if isinstance(size, list) else size}",
        f"transport={spec.get('transport')}",
        f"lidar={spec.get('lidar', {}).get('mode')}",
        f"sharing={spec.get('comm', {}).get('map_sharing')}",
        f"planner={spec.get('navigation', {}).get('planner')}",
        "robots=team" if spec["robots"]["count"] > 1 else "robots=alone",
    })


def _cost(spec: dict[str, Any]) -> float:
    """A rough relative cost of a run, to prefer cheap cells: the map's area, a little more per robot."""
    size = spec["map"].get("size") or 50
    w, h = (size if isinstance(size, list) else (size, size))
    return float(w) * float(h) * (1.0 + 0.1 * spec["robots"]["count"])


@dataclass
class Plan:
    """The warm-up of one campaign start: the run indices to execute here first (may be empty)."""

    indices: list[int]
    needed: frozenset[str]
    covered: frozenset[str] = field(default_factory=frozenset)
    """Features a valid stamp already covers."""


def plan(spec: CampaignSpec, todo: Iterable[int], stamp: Path | None = None) -> Plan:
    """Choose the warm-up runs among ``todo`` (run indices): a greedy weighted set cover of the features the
    stamp does not cover, each step taking the cell that adds the most uncovered features per unit of cost."""
    reps = spec.replicates
    first: dict[int, int] = {}
    for index in todo:
        first.setdefault(int(index) // reps, int(index))
    candidates = []
    for index in first.values():
        canonical = spec.run_at(index).canonical()
        candidates.append((index, features(canonical), _cost(canonical)))
    needed = frozenset().union(*(f for _, f, _ in candidates)) if candidates else frozenset()
    covered = warm_features(stamp if stamp is not None else stamp_path())
    missing = set(needed - covered)
    chosen: list[int] = []
    while missing and len(chosen) < MAX_WARMUP_RUNS:
        index, feats, cost = max(candidates, key=lambda c: (len(c[1] & missing) / c[2], -c[0]))
        if not feats & missing:
            break
        chosen.append(index)
        missing -= feats
    return Plan(sorted(chosen), needed, covered & needed)


# ------------------------------------------------------------------------------------------ stamp ----
CACHE_ENV = "SWARM_CACHE_DIR"
"""Folder for the stamp instead of ``$XDG_CACHE_HOME/swarm`` (``~/.cache/swarm``)."""


def stamp_path() -> Path:
    """Where the stamp of this installation lives: ``$SWARM_CACHE_DIR``, else the user's cache folder; one
    file per installed swarm (its package folder), Python and numba version."""
    from importlib.metadata import PackageNotFoundError, version

    try:
        numba_version = version("numba")
    except PackageNotFoundError:
        numba_version = "?"
    here = str(Path(__file__).resolve().parents[2])
    key = hashlib.sha256(f"{here}\0{sys.version}\0{numba_version}".encode()).hexdigest()[:16]
    if os.environ.get(CACHE_ENV):
        return Path(os.environ[CACHE_ENV]) / f"kernels-{key}.json"
    base = Path(os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache")
    return base / "swarm" / f"kernels-{key}.json"


def _mtime(path: str) -> tuple[int, int] | None:
    try:
        st = os.stat(path)
    except OSError:
        return None
    return st.st_mtime_ns, st.st_size


def warm_features(path: Path) -> frozenset[str]:
    """The features the stamp at ``path`` covers, if every file it records is unchanged; else none."""
    try:
        data = json.loads(path.read_text(encoding="utf-8"))
        if data.get("version") != STAMP_VERSION:
            return frozenset()
        for index, index_stat, source, source_stat in data["files"]:
            if _mtime(index) != tuple(index_stat) or _mtime(source) != tuple(source_stat):
                return frozenset()
        return frozenset(data["features"])
    except (OSError, ValueError, KeyError, TypeError):
        return frozenset()


def _cached_kernels() -> list[tuple[str, str]]:
    """(index file, source file) of every numba kernel of this process that has compiled code in numba's disk
    cache (kernels without ``cache=True``, or never called, are left out)."""
    from numba.core.dispatcher import Dispatcher

    out: set[tuple[str, str]] = set()
    for module in list(sys.modules.values()):
        for value in list(getattr(module, "__dict__", {}).values()):
            if not isinstance(value, Dispatcher) or not value.overloads:
                continue
            cache = getattr(value, "_cache", None)
            index = getattr(getattr(cache, "_cache_file", None), "_index_path", None)
            source = getattr(getattr(value, "py_func", None), "__code__", None)
            if index and source is not None and os.path.isfile(index):
                out.add((str(index), source.co_filename))
    return sorted(out)


def record(path: Path, covered: Iterable[str]) -> bool:
    """Write the stamp after a warm-up: ``covered`` features, and the kernels now in numba's cache.
    Returns False when it could not be written (the next campaign warms up again: slower, never wrong)."""
    try:
        files = []
        for index, source in _cached_kernels():
            i, s = _mtime(index), _mtime(source)
            if i is not None and s is not None:
                files.append([index, list(i), source, list(s)])
        old = warm_features(path)
        data = {"version": STAMP_VERSION, "features": sorted(set(covered) | old), "files": files}
        path.parent.mkdir(parents=True, exist_ok=True)
        tmp = path.with_name(f".{path.name}.{os.getpid()}.tmp")
        tmp.write_text(json.dumps(data, indent=0), encoding="utf-8")
        os.replace(tmp, path)
        return True
    except Exception:  # numba internals moved, a read-only home: only a missed shortcut next time
        return False


def describe(chosen: Sequence[Any]) -> str:
    return f"{len(chosen)} warm-up run{'s' if len(chosen) != 1 else ''}"


__all__ = ["MAX_WARMUP_RUNS", "Plan", "features", "plan", "record", "stamp_path", "warm_features"]
