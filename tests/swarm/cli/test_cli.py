"""The command line: subcommands work, and bad input is one line on stderr with exit status 2."""

from __future__ import annotations

import subprocess
import sys

import pytest

from maps.io import load_npz
from swarm.cli import main


def run(capsys, *args: str) -> tuple[int, str, str]:
    code = main(list(args))
    out, err = capsys.readouterr()
    return code, out, err


def test_generate_writes_map_and_png(tmp_path, capsys):
    npz, png = tmp_path / "m.npz", tmp_path / "m.png"
    code, out, _ = run(capsys, "map", "generate", "--kind", "building", "--size", "40", "--seed", "7",
                       "-o", str(npz), "--png", str(png))
    assert code == 0
    assert "building seed 7" in out and png.stat().st_size > 1000
    m = load_npz(npz)
    assert m.kind == "building" and m.seed == 7 and m.shape == (80, 80)


def test_generate_defaults_write_a_png_here(tmp_path, capsys, monkeypatch):
    monkeypatch.chdir(tmp_path)
    code, out, _ = run(capsys, "map", "generate")
    assert code == 0 and (tmp_path / "building-100-s0.png").exists()


def test_generate_passes_params(tmp_path, capsys):
    npz = tmp_path / "c.npz"
    assert run(capsys, "map", "generate", "--kind", "cave", "--size", "40", "--param", "fill_percent=45",
               "--param", "materials={wood = 1}", "-o", str(npz))[0] == 0
    m = load_npz(npz)
    assert m.params["fill_percent"] == 45 and set(m.materials[1:]) >= {"wood"}
    assert {m.materials[i] for i in set(m.material[m.solid].tolist())} == {"wood"}


def test_show_and_import(tmp_path, capsys):
    csv = tmp_path / "g.csv"
    csv.write_text("1,1,1\n1,0,1\n1,1,1\n")
    npz, png = tmp_path / "g.npz", tmp_path / "g.png"
    assert run(capsys, "map", "import", str(csv), "-o", str(npz), "--material", "wood")[0] == 0
    code, out, _ = run(capsys, "map", "show", str(npz), "-o", str(png))
    assert code == 0 and "custom" in out and png.exists()


@pytest.mark.parametrize("args, needle", [
    (["map", "generate", "--size", "10"], "--size"),
    (["map", "generate", "--size", "abc"], "--size"),
    (["map", "generate", "--kind", "castle"], "'castle' is not one of 'building', 'cave'"),
    (["map", "generate", "--seed", "-1"], "--seed"),
    (["map", "generate", "--param", "fill_percent=45"], "building.fill_percent"),
    (["map", "generate", "--kind", "cave", "--param", "fill_percent=100"], "fill_percent: got 100"),
    (["map", "generate", "--param", "nokey"], "--param"),
    (["map", "generate", "--frobnicate"], "No such option"),
    (["mapz"], "allowed: agent, algorithms, campaign, export, map"),
    (["map", "show", "/nonexistent.npz"], "does not exist"),
])
def test_bad_arguments_are_one_line_and_exit_2(capsys, args, needle):
    code, out, err = run(capsys, *args)
    assert code == 2
    assert needle in err
    assert err.count("\n") == 1 and err.startswith("swarm: error: ")
    assert "Traceback" not in err


def test_bad_file_is_one_line(tmp_path, capsys):
    bad = tmp_path / "bad.npz"
    bad.write_bytes(b"not a zip")
    code, _, err = run(capsys, "map", "show", str(bad))
    assert code == 2 and "map file" in err and err.count("\n") == 1


def test_console_script_exit_status_in_a_real_process():
    proc = subprocess.run([sys.executable, "-m", "swarm", "map", "generate", "--size", "5"],
                          capture_output=True, text=True, timeout=60)
    assert proc.returncode == 2
    assert proc.stderr.startswith("swarm: error: --size") and "Traceback" not in proc.stderr


def test_help_everywhere(capsys):
    for args in ([], ["--help"], ["map", "--help"], ["map", "generate", "--help"], ["map", "import", "--help"]):
        code, out, _ = run(capsys, *args)
        assert code == 0 and "Usage:" in out
