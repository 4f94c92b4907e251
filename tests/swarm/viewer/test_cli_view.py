"""``swarm run --record`` and ``swarm view``: files written, pages self-contained, bad input exits 2."""

from __future__ import annotations

import base64
import re
import subprocess
import sys
import webbrowser

import pytest

from swarm.cli import main
from swarm.record import load_recording


def run(capsys, *args: str) -> tuple[int, str, str]:
    code = main(list(args))
    out, err = capsys.readouterr()
    return code, out, err


@pytest.fixture(scope="module")
def recorded(tmp_path_factory):
    """A recording made by the real command in its own process."""
    path = tmp_path_factory.mktemp("cli") / "run.swr"
    proc = subprocess.run([sys.executable, "-m", "swarm", "run", "--size", "20", "--robots", "2", "--seed", "1",
                           "--max-ticks", "60", "--record", str(path)], capture_output=True, text=True, timeout=300,
                          check=False)
    assert proc.returncode == 0, proc.stderr
    assert f"wrote {path}" in proc.stdout
    return path


def test_run_record_writes_a_recording_of_the_whole_run(recorded):
    rec = load_recording(recorded)
    assert rec.n_robots == 2 and rec.ticks == 61 and rec.summary["stop_reason"] == "max_ticks"
    assert rec.spec["robots"]["count"] == 2 and rec.spec["seed"] == 1


def test_view_writes_one_self_contained_page(recorded, tmp_path, capsys):
    out = tmp_path / "page.html"
    code, stdout, stderr = run(capsys, "view", str(recorded), "--no-open", "-o", str(out))
    assert code == 0 and stderr == "" and f"wrote {out}" in stdout
    page = out.read_text(encoding="utf-8")
    data = recorded.read_bytes()
    assert base64.b64encode(data).decode() in page
    assert 'id="map"' in page and 'id="timeline"' in page and 'id="robot-panel"' in page
    assert "DecompressionStream" in page and "{{" not in page
    assert not re.search(r"""(src|href)\s*=\s*["']?(https?:)?//""", page)  # nothing fetched from anywhere
    assert not re.search(r"""fetch\(|XMLHttpRequest|import\(""", page)
    assert len(page.encode()) < 1.4 * len(data) + 110_000  # the script and style: ~100 KB


def test_view_defaults_to_the_recording_name_with_html(recorded, capsys):
    code, _, _ = run(capsys, "view", str(recorded), "--no-open")
    assert code == 0 and recorded.with_suffix(".html").exists()


@pytest.mark.parametrize("make, needle", [
    (lambda p: None, "readable"),
    (lambda p: p.write_bytes(b"not a recording"), "magic"),
    (lambda p: p.write_bytes(b""), "magic"),
])
def test_view_rejects_bad_files(tmp_path, capsys, make, needle):
    bad = tmp_path / "bad.swr"
    make(bad)
    code, out, err = run(capsys, "view", str(bad), "--no-open")
    assert code == 2 and out == ""
    assert err.startswith("swarm: error: recording:") and needle in err and err.count("\n") == 1


@pytest.mark.parametrize("section", ["algorithm", "map"])
def test_view_rejects_a_spec_whose_sections_are_not_maps(recorded, tmp_path, capsys, section):
    """A crafted HEAD (issue 48): the reader accepts any map as the spec; the viewer needs its sections."""
    from swarm.record.container import HEAD, MAGIC, encode_chunk, iter_chunks

    chunks = [encode_chunk(k, {**b, "spec": {**b["spec"], section: "frontier"}} if k == HEAD else b)
              for k, b in iter_chunks(recorded.read_bytes(), "x")]
    bad = tmp_path / "crafted.swr"
    bad.write_bytes(MAGIC + b"".join(chunks))
    code, out, err = run(capsys, "view", str(bad), "--no-open")
    assert code == 2 and out == "" and err.count("\n") == 1
    assert err.startswith("swarm: error: recording:") and f"spec field '{section}' is not a map" in err
    assert not bad.with_suffix(".html").exists()


def test_view_rejects_a_truncated_recording(recorded, tmp_path, capsys):
    bad = tmp_path / "cut.swr"
    bad.write_bytes(recorded.read_bytes()[:-10])
    code, _, err = run(capsys, "view", str(bad), "--no-open")
    assert code == 2 and "truncated" in err and err.count("\n") == 1
    assert not bad.with_suffix(".html").exists()


def test_view_output_in_a_missing_folder_exits_2(recorded, tmp_path, capsys):
    code, _, err = run(capsys, "view", str(recorded), "--no-open", "-o", str(tmp_path / "no" / "x.html"))
    assert code == 2 and "existing folder" in err


def test_view_never_overwrites_the_recording(recorded, capsys):
    before = recorded.read_bytes()
    code, _, err = run(capsys, "view", str(recorded), "--no-open", "-o", str(recorded))
    assert code == 2 and err.startswith("swarm: error: --output:") and recorded.read_bytes() == before


def test_run_record_into_a_missing_folder_fails_before_running(tmp_path, capsys):
    code, out, err = run(capsys, "run", "--size", "20", "--record", str(tmp_path / "no" / "x.swr"))
    assert code == 2 and out == "" and err.startswith("swarm: error: --record:")


def test_view_opens_the_page_in_a_browser(recorded, capsys, monkeypatch):
    opened = []
    monkeypatch.setenv("DISPLAY", ":0")
    monkeypatch.setattr(webbrowser, "open", lambda url: opened.append(url) or True)
    code, _, err = run(capsys, "view", str(recorded))
    assert code == 0 and err == ""
    assert opened == [recorded.with_suffix(".html").resolve().as_uri()]


@pytest.mark.parametrize("behaviour, needle", [("false", "no browser found"), ("raise", "could not open a browser"),
                                               ("no-display", "no display")])
def test_view_without_a_browser_says_so_in_one_line(recorded, capsys, monkeypatch, behaviour, needle):
    def fake_open(url):
        if behaviour == "raise":
            raise OSError("launcher exploded")
        return False

    for var in ("DISPLAY", "WAYLAND_DISPLAY", "BROWSER"):
        monkeypatch.delenv(var, raising=False)
    if behaviour != "no-display":
        monkeypatch.setenv("DISPLAY", ":0")
    monkeypatch.setattr(webbrowser, "open", fake_open)
    code, out, err = run(capsys, "view", str(recorded))
    assert code == 0 and "wrote" in out
    assert needle in err and err.count("\n") == 1 and "Traceback" not in err
