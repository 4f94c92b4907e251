"""Writing the report folder: every file atomically, unchanged files left alone, stale files removed.

The report folder is a pure function of the results folder and the options. Files a previous report wrote
but this one does not (a MAES CSV whose ``_e..-c..`` suffix changed, a figure of a cell that no longer
exists) are deleted using the previous ``files.txt``; files the report never wrote are never touched.
"""

from __future__ import annotations

import re
from collections.abc import Callable
from pathlib import Path

from maps.io import atomic_write_bytes
from swarm.base.errors import InvalidInput

MANIFEST = "files.txt"
_HEADER = "# files written by `swarm campaign report` (the next report deletes those it no longer writes)\n"


class ReportWriter:
    """``on_write(relative)`` is called after each file is written (a progress display)."""

    def __init__(self, folder: Path, on_write: Callable[[str], None] | None = None) -> None:
        if folder.exists() and not folder.is_dir():
            raise InvalidInput("-o", str(folder), "a folder for the report (this is a file)")
        folder.mkdir(parents=True, exist_ok=True)
        self.folder = folder
        self.written: list[str] = []
        self._dirs: set[Path] = set()
        self.on_write = on_write

    def write(self, relative: str, data: bytes | str) -> Path:
        """Write ``folder/relative`` atomically (skipped when the bytes are already there)."""
        blob = data.encode("utf-8") if isinstance(data, str) else data
        path = self.folder / relative
        if path.parent not in self._dirs:
            path.parent.mkdir(parents=True, exist_ok=True)
            self._dirs.add(path.parent)
        if not (path.is_file() and path.stat().st_size == len(blob) and path.read_bytes() == blob):
            atomic_write_bytes(path, blob)
        self.written.append(relative)
        if self.on_write is not None:
            self.on_write(relative)
        return path

    def finish(self) -> None:
        """Remove what the previous report wrote and this one did not, then record this report's files."""
        keep = set(self.written)
        for old in previous_files(self.folder):
            if old not in keep:
                (self.folder / old).unlink(missing_ok=True)
                _prune_empty(self.folder, (self.folder / old).parent)
        self.write(MANIFEST, _HEADER + "".join(f"{f}\n" for f in sorted(keep | {MANIFEST})))


def previous_files(folder: Path) -> list[str]:
    path = folder / MANIFEST
    if not path.is_file():
        return []
    out = []
    for line in path.read_text(encoding="utf-8").splitlines():
        name = line.strip()
        if name and not name.startswith("#") and _safe(name):
            out.append(name)
    return out


def _safe(name: str) -> bool:
    """A relative path inside the report folder (a hand-edited manifest cannot delete anything outside it)."""
    parts = Path(name).parts
    return bool(parts) and not Path(name).is_absolute() and ".." not in parts and name != MANIFEST


def _prune_empty(root: Path, folder: Path) -> None:
    while folder != root and root in folder.parents:
        try:
            folder.rmdir()
        except OSError:
            return
        folder = folder.parent


def slug(label: str) -> str:
    """A label as a file-name piece: letters, digits, '.', '+' and '-' kept, anything else becomes '-'."""
    return re.sub(r"[^A-Za-z0-9.+-]+", "-", label).strip("-") or "x"
