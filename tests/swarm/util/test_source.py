"""A run records which source computed it: the package version, and the commit of the git checkout it runs
from, marked dirty when a tracked file was changed (swarm.util.source)."""

from __future__ import annotations

import shutil
import subprocess
from pathlib import Path

import pytest

import swarm.util.source as source

pytestmark = pytest.mark.skipif(shutil.which("git") is None, reason="needs git")


def git(root: Path, *args: str) -> str:
    return subprocess.run(["git", "-C", str(root), *args], check=True, capture_output=True, text=True).stdout.strip()


@pytest.fixture
def checkout(tmp_path, monkeypatch):
    """A git repository with one commit, standing in for the checkout swarm is imported from."""
    git(tmp_path, "init", "-q")
    (tmp_path / "tracked.py").write_text("x = 1\n")
    git(tmp_path, "add", "tracked.py")
    git(tmp_path, "-c", "user.name=t", "-c", "user.email=t@t", "commit", "-q", "-m", "one")
    monkeypatch.setattr(source, "ROOT", tmp_path)
    source.source_commit.cache_clear()
    yield tmp_path
    source.source_commit.cache_clear()


def test_a_clean_checkout_gives_its_commit(checkout):
    head = git(checkout, "rev-parse", "HEAD")
    commit = source.source_commit()
    assert commit is not None and head.startswith(commit) and len(commit) == 12
    (checkout / "results.csv").write_text("an untracked file\n")  # untracked files are not the code
    source.source_commit.cache_clear()
    assert source.source_commit() == commit
    assert source.version_label() == f"{source.package_version() or 'unknown'}+git.{commit}"


def test_a_changed_tracked_file_marks_the_commit_dirty(checkout):
    (checkout / "tracked.py").write_text("x = 2\n")
    commit = source.source_commit()
    assert commit is not None and commit.endswith("-dirty")
    assert git(checkout, "rev-parse", "HEAD").startswith(commit.removesuffix("-dirty"))


def test_outside_a_checkout_only_the_version_is_known(tmp_path, monkeypatch):
    monkeypatch.setattr(source, "ROOT", tmp_path)  # an installed wheel: no .git beside the package
    source.source_commit.cache_clear()
    try:
        assert source.source_commit() is None
        assert source.version_label() == (source.package_version() or "unknown")
    finally:
        source.source_commit.cache_clear()


def test_root_is_where_the_swarm_package_lives():
    """ROOT must be the directory holding ``swarm/`` (a checkout's root), wherever this module sits in the
    package: after the issue-46 move to ``swarm/util/`` it pointed at ``swarm/`` and no run recorded a commit."""
    import swarm

    assert source.ROOT == Path(swarm.__file__).resolve().parent.parent
    assert (source.ROOT / "swarm" / "util" / "source.py").is_file()
