"""Writers of a results folder: who is writing which runs, and who is provably dead.

Many processes may write into one results folder at once (``--shard i/N`` jobs of a SLURM array on shared
storage), but never two the same runs. Each writer holds, for its whole life, an exclusive ``flock`` on
its own lock file ``DIR/writers/<host>-<pid>-<nonce>.lock``, which records its host, pid, start time and
run selection (shard, ``--retry-failed``). The kernel (or the NFS server) drops the lock when the process
dies, even by ``kill -9``: a lock file nobody holds is a dead writer, whatever its pid says on whichever host.

Start-up is one critical section under ``DIR/writers/.registry.lock`` (so two writers starting at the same
instant take turns):

1. check ``campaign.toml`` (or write it, for a new folder);
2. look at every lock file: a live writer whose selection overlaps ours is a refusal (exit 2, naming it);
   shards ``i/N`` and ``j/M`` overlap iff some run index ``x`` has ``x = i mod N`` and ``x = j mod M``
   (iff ``i = j mod gcd(N, M)`` and the smallest such ``x`` is below the run count); a writer without
   ``--shard`` overlaps every other;
3. remove what dead writers left: their temporary files and time-series files without runs files, then
   their lock files; files named by older versions (no writer id) only when no other writer is alive;
4. create our lock file: written and locked under a temporary name, then renamed into place, so a lock file
   is never seen unlocked while its writer lives;
5. create and remove a probe file in ``parts/``: a folder we cannot write fails now, before any run.

We chose refusal over splitting the work: shards already split it without any coordination per run (no
claim files: 54,000 of them would be a metadata storm on NFS), a refusal leaves nothing to clean up, and
two writers of the same runs are a mistake worth reporting (a job submitted twice). Liveness needs working
``flock`` across the machines that share the folder: local disks, NFSv3/v4 (Linux emulates ``flock`` with
NFS byte-range locks) and Lustre mounted with ``-o flock`` have it.
"""

from __future__ import annotations

import contextlib
import errno
import fcntl
import json
import math
import os
import re
import socket
import time
import uuid
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from swarm.base.errors import InvalidInput

from .store import ResultsStore

WRITERS = "writers"
REGISTRY = ".registry.lock"
LOCK_SUFFIX = ".lock"
REGISTRY_WAIT_S = 60.0
"""How long a start-up waits for another one to finish its critical section (it takes well under a second)."""

Shard = tuple[int, int]


def new_writer_id() -> str:
    """``<host>-<pid>-<nonce>``: the host shortened to letters, digits, '-' and '_'."""
    host = re.sub(r"[^A-Za-z0-9_-]", "_", socket.gethostname().split(".")[0])[:40] or "host"
    return f"{host}-{os.getpid()}-{uuid.uuid4().hex[:8]}"


@dataclass(frozen=True)
class WriterInfo:
    """What a lock file says about its writer."""

    id: str
    host: str
    pid: int
    started: str
    shard: Shard | None
    retry_failed: bool

    def describe(self) -> str:
        shard = f"shard {self.shard[0]}/{self.shard[1]}" if self.shard else "all runs, no --shard"
        retry = ", --retry-failed" if self.retry_failed else ""
        return f"pid {self.pid} on {self.host} ({shard}{retry}), started {self.started}"

    def to_json(self) -> str:
        return json.dumps({"id": self.id, "host": self.host, "pid": self.pid, "started": self.started,
                           "shard": list(self.shard) if self.shard else None, "retry_failed": self.retry_failed})

    @classmethod
    def from_json(cls, text: str, fallback_id: str) -> "WriterInfo":
        try:
            d = json.loads(text)
            shard = tuple(int(v) for v in d["shard"]) if d.get("shard") else None
            return cls(str(d["id"]), str(d["host"]), int(d["pid"]), str(d["started"]),
                       shard if shard and len(shard) == 2 else None, bool(d.get("retry_failed")))
        except (ValueError, KeyError, TypeError):  # unreadable: assume the worst (it writes every run)
            return cls(fallback_id, "?", 0, "?", None, False)


def overlaps(a: Shard | None, b: Shard | None, total: int | None = None) -> bool:
    """Do two run selections share a run index below ``total`` (None: any index)?"""
    if a is None or b is None:
        return total is None or total > 0
    (i, n), (j, m) = a, b
    g = math.gcd(n, m)
    if (i - j) % g:
        return False
    if total is None:
        return True
    # smallest x >= 0 with x = i (mod n) and x = j (mod m), by the Chinese remainder theorem
    n_g, m_g = n // g, m // g
    t = ((j - i) // g * pow(n_g, -1, m_g)) % m_g if m_g > 1 else 0
    return i + n * t < total


def _lock_nb(fd: int) -> bool:
    try:
        fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        return True
    except OSError as exc:
        if exc.errno in (errno.EWOULDBLOCK, errno.EAGAIN, errno.EACCES):
            return False
        raise


@contextlib.contextmanager
def registry_lock(folder: Path, wait_s: float = REGISTRY_WAIT_S) -> Iterator[None]:
    """The start-up critical section of ``folder`` (see the module docstring)."""
    path = folder / WRITERS / REGISTRY
    fd = os.open(path, os.O_RDWR | os.O_CREAT, 0o666)
    try:
        deadline = time.monotonic() + wait_s
        while not _lock_nb(fd):
            if time.monotonic() > deadline:
                raise InvalidInput("-o", str(folder), f"a results folder whose start-up lock ({WRITERS}/{REGISTRY}) "
                                                      f"is free; another writer has held it for {wait_s:.0f} s")
            time.sleep(0.05)
        yield
    finally:
        os.close(fd)  # releases the lock


@dataclass
class _Seen:
    path: Path
    info: WriterInfo
    fd: int | None
    """Held open with the lock taken when the writer is dead (so nobody else judges it meanwhile)."""


def _scan(folder: Path, own: str | None = None) -> tuple[list[_Seen], list[_Seen]]:
    """(live, dead) writers of ``folder``; the caller must close the fds of the dead ones."""
    live: list[_Seen] = []
    dead: list[_Seen] = []
    try:
        names = sorted(os.listdir(folder / WRITERS))
    except FileNotFoundError:
        return live, dead
    for name in names:
        if not name.endswith(LOCK_SUFFIX) or name.startswith("."):
            continue
        wid = name[: -len(LOCK_SUFFIX)]
        if wid == own:
            continue
        path = folder / WRITERS / name
        try:
            fd = _open_lock(path)
        except FileNotFoundError:
            continue  # it just ended and removed its lock file
        try:
            info = WriterInfo.from_json(os.read(fd, 65536).decode("utf-8", "replace"), wid)
            if _lock_nb(fd):
                dead.append(_Seen(path, info, fd))
                continue
        except BaseException:
            os.close(fd)
            raise
        os.close(fd)
        live.append(_Seen(path, info, None))
    return live, dead


def _open_lock(path: Path) -> int:
    """Open a lock file to test it (read-write: NFS emulates ``flock`` with write locks)."""
    try:
        return os.open(path, os.O_RDWR)
    except PermissionError:
        return os.open(path, os.O_RDONLY)


def live_writers(folder: str | Path) -> list[WriterInfo] | None:
    """The writers alive now (for ``swarm campaign status``); removes nothing. None when the lock files
    cannot be tested (e.g. a read-only folder)."""
    folder = Path(folder)
    try:
        with registry_lock(folder, wait_s=5.0):  # a test lock taken meanwhile would make a start-up misjudge
            return live_writers_locked(folder)
    except (OSError, InvalidInput):
        return None


def live_writers_locked(folder: Path) -> list[WriterInfo]:
    """:func:`live_writers` for a caller that holds ``folder``'s :func:`registry_lock` (so that none starts
    until it lets go, e.g. while compacting); removes nothing."""
    live, dead = _scan(folder)
    for d in dead:
        os.close(d.fd)
    return [w.info for w in live]


class Writer:
    """This process as the writer of some runs of a results folder, for the life of a ``with`` block."""

    def __init__(self, store: ResultsStore, source: str, shard: Shard | None = None, retry_failed: bool = False,
                 total: int | None = None) -> None:
        self.store = store
        self.source = source
        self.total = total
        self.id = new_writer_id()
        self.info = WriterInfo(self.id, socket.gethostname(), os.getpid(),
                               time.strftime("%Y-%m-%dT%H:%M:%SZ", time.gmtime()), shard, retry_failed)
        self.lock_path = store.folder / WRITERS / f"{self.id}{LOCK_SUFFIX}"
        self._fd: int | None = None
        self.removed: list[Path] = []
        """Files of dead writers this start-up removed."""

    def __enter__(self) -> "Writer":
        folder = self.store.folder
        try:
            self.store.refuse_foreign()
            (folder / WRITERS).mkdir(parents=True, exist_ok=True)
            with registry_lock(folder):
                self.store.prepare(self.source)
                live, dead = _scan(folder, own=self.id)
                try:
                    for other in live:
                        if overlaps(other.info.shard, self.info.shard, self.total):
                            raise InvalidInput("-o", str(folder), "a results folder no live writer of the same runs "
                                               f"uses; {other.info.describe()} writes these runs (lock file "
                                               f"{WRITERS}/{other.path.name}); wait for it to end, or give each job "
                                               "its own --shard i/N")
                    self._clean({w.info.id for w in live}, dead)
                finally:
                    for d in dead:
                        os.close(d.fd)
                self._register()
                self.store.probe(self.id)
        except OSError as exc:
            self._unregister()
            raise self.store.folder_error(exc) from None
        except BaseException:
            self._unregister()
            raise
        return self

    def __exit__(self, *exc: Any) -> None:
        self._unregister()

    # ------------------------------------------------------------------------------------------------
    def _clean(self, live: set[str], dead: list[_Seen]) -> None:
        """Remove what dead writers left (their locks are held by us meanwhile), then their lock files."""
        for path, wid in self.store.leftovers():
            if (wid is None and not live) or (wid is not None and wid not in live):
                with contextlib.suppress(FileNotFoundError):
                    path.unlink()
                    self.removed.append(path)
        for d in dead:
            with contextlib.suppress(FileNotFoundError):
                d.path.unlink()
                self.removed.append(d.path)
        for name in os.listdir(self.store.folder / WRITERS):  # registrations cut short by a crash
            if name.startswith(".") and name.endswith(".tmp"):
                with contextlib.suppress(FileNotFoundError):
                    (self.store.folder / WRITERS / name).unlink()

    def _register(self) -> None:
        tmp = self.lock_path.with_name(f".{self.lock_path.name}.tmp")
        fd = os.open(tmp, os.O_RDWR | os.O_CREAT | os.O_EXCL, 0o644)
        self._fd = fd
        fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        os.write(fd, self.info.to_json().encode())
        os.fsync(fd)
        os.replace(tmp, self.lock_path)

    def _unregister(self) -> None:
        if self._fd is None:
            return
        with contextlib.suppress(OSError):
            self.lock_path.unlink(missing_ok=True)
            self.lock_path.with_name(f".{self.lock_path.name}.tmp").unlink(missing_ok=True)
        with contextlib.suppress(OSError):
            os.close(self._fd)
        self._fd = None
