"""When a report is up to date: a fingerprint of everything it is built from, kept in the report folder.

A report is a pure function of the results folder and the report's options (:mod:`.output`), so it needs
no rebuilding while neither changed. The fingerprint hashes:

- every file of ``parts/`` (name, size and modification time: parts are written once, atomically, under
  names never reused, so a new run, a retried run or a part moved away all change it) and ``campaign.toml``;
- the options: target, figure format, MAES CSVs, per-cell figures, the layout file (path and content) and
  the two folders as the README's command line names them;
- the code that draws it: the source of ``swarm/campaign`` and the versions of swarm, numpy, pandas,
  pyarrow, scipy and matplotlib.

It is written to ``.fingerprint.json`` in the report folder after a report is complete, so a report cut
off half-way is never taken as current. A report is current when the stored fingerprint equals today's and
every file its ``files.txt`` lists still exists (a deleted figure is redrawn).
"""

from __future__ import annotations

import hashlib
import json
import os
from importlib.metadata import PackageNotFoundError, version
from pathlib import Path
from typing import Any

from ..store import PARTS, SPEC_FILE
from .output import MANIFEST, previous_files

FILE = ".fingerprint.json"
LIBRARIES = ("swarm-sim", "numpy", "pandas", "pyarrow", "scipy", "matplotlib")


def _code_hash() -> str:
    """Hash of the campaign code's source (the report, its loaders, the spec parser, the MAES CSV writer)."""
    root = Path(__file__).resolve().parents[1]
    h = hashlib.sha256()
    for path in sorted(root.rglob("*.py")):
        h.update(str(path.relative_to(root)).encode())
        h.update(path.read_bytes())
    for name in LIBRARIES:
        try:
            h.update(f"{name}={version(name)}".encode())
        except PackageNotFoundError:
            h.update(f"{name}=?".encode())
    return h.hexdigest()


DEFAULTS: dict[str, Any] = {"target": 0.98, "maes_csv": False, "fmt": "png", "figures_file": None,
                            "cell_figures": True, "figure_width": "page"}
""":func:`.build.build_report`'s options and their defaults (a default given or left out is the same report)."""


def _options(options: dict[str, Any]) -> dict[str, Any]:
    out = {**DEFAULTS, **options}
    out["target"] = float(out["target"])
    out["figures_file"] = None if out["figures_file"] is None else str(out["figures_file"])
    return out


def fingerprint(results_dir: str | Path, report_dir: str | Path, options: dict[str, Any]) -> str:
    """The fingerprint of the report ``report_dir`` of ``results_dir`` with ``options`` (those of
    :func:`.build.build_report`; a ``figures_file`` is hashed by content too)."""
    results_dir = Path(results_dir)
    options = _options(options)
    h = hashlib.sha256()
    parts = results_dir / PARTS
    names = sorted(os.listdir(parts)) if parts.is_dir() else []
    for name in names:
        if name.startswith("."):  # temporary files of a writer at work
            continue
        st = (parts / name).stat()
        h.update(f"{name}\0{st.st_size}\0{st.st_mtime_ns}\n".encode())
    spec = results_dir / SPEC_FILE
    h.update(spec.read_bytes() if spec.is_file() else b"<no spec>")
    opts = dict(sorted(options.items()))
    figures = options.get("figures_file")
    if figures is not None and Path(figures).is_file():
        opts["figures_file_sha256"] = hashlib.sha256(Path(figures).read_bytes()).hexdigest()
    h.update(json.dumps({"results": str(results_dir), "report": str(report_dir), "options": opts},
                        sort_keys=True, default=str).encode())
    h.update(_code_hash().encode())
    return h.hexdigest()


def is_current(results_dir: str | Path, report_dir: str | Path, options: dict[str, Any]) -> bool:
    """The report in ``report_dir`` was built, completely, from exactly these results and options."""
    report_dir = Path(report_dir)
    try:
        stored = json.loads((report_dir / FILE).read_text(encoding="utf-8"))["fingerprint"]
    except (OSError, ValueError, KeyError, TypeError):
        return False
    if not (report_dir / MANIFEST).is_file() or not (report_dir / "README.md").is_file():
        return False
    if any(not (report_dir / name).is_file() for name in previous_files(report_dir)):
        return False
    return stored == fingerprint(results_dir, report_dir, options)


def mark_current(results_dir: str | Path, report_dir: str | Path, options: dict[str, Any]) -> None:
    """Record that the report now in ``report_dir`` is complete for these results and options."""
    from maps.io import atomic_write_bytes

    text = json.dumps({"fingerprint": fingerprint(results_dir, report_dir, options),
                       "note": "swarm campaign report skips rebuilding while this matches (see --force)"})
    atomic_write_bytes(Path(report_dir) / FILE, text.encode())


def forget(report_dir: str | Path) -> None:
    """Drop the record (before a rebuild starts: a rebuild cut off half-way is not current)."""
    (Path(report_dir) / FILE).unlink(missing_ok=True)


def update_report(results_dir: str | Path, report_dir: str | Path, *, force: bool = False,
                  progress: Any = None, **options: Any) -> tuple[Path, bool]:
    """Build the report of ``results_dir`` into ``report_dir`` unless it is current (or ``force``); returns
    its README and whether it was built. ``options`` are :func:`.build.build_report`'s."""
    from .build import build_report

    report_dir = Path(report_dir)
    if not force and is_current(results_dir, report_dir, options):
        return report_dir / "README.md", False
    if report_dir.is_dir():
        forget(report_dir)
    readme = build_report(results_dir, report_dir, progress=progress, **options)
    mark_current(results_dir, report_dir, options)
    return readme, True


__all__ = ["FILE", "fingerprint", "forget", "is_current", "mark_current", "update_report"]
