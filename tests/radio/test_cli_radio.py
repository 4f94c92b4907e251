"""``swarm radio link`` and ``swarm radio heatmap``: output, files, and one-line errors with exit status 2."""

from __future__ import annotations

import pytest
from PIL import Image

from maps.io import save_npz
from swarm.cli import main

from .plans import Plan, vertical_wall


def run(capsys, *args: str) -> tuple[int, str, str]:
    code = main(list(args))
    out, err = capsys.readouterr()
    return code, out, err


@pytest.fixture
def wall_npz(tmp_path):
    return str(save_npz(vertical_wall("concrete"), tmp_path / "wall.npz"))


def test_link_prints_the_budget(capsys, wall_npz):
    code, out, _ = run(capsys, "radio", "link", wall_npz, "--from", "10,20.25", "--to", "30,20.25")
    assert code == 0
    # 20 m through one concrete wall: L = 62.51 dB; 15 - 62.51 - 15 = -62.51 dBm; margin -62.51 + 82 = 19.49 dB
    for needle in ("distance 20.00 m", "walls crossed: 1", "concrete 1.00 m -> 15.00 dB", "path loss: 62.51 dB",
                   "wall loss: 15.00 dB", "RSSI: -62.51 dBm", "margin: +19.49 dB", "verdict: link OK"):
        assert needle in out, needle


def test_link_with_options(capsys, wall_npz):
    # MAES: 15 - 4 x 15 = -45 dBm
    code, out, _ = run(capsys, "radio", "link", wall_npz, "--from", "10,20.25", "--to", "30,20.25", "--model", "maes")
    assert code == 0 and "RSSI: -45.00 dBm" in out
    # 5.2 GHz: L = 69.23 dB, concrete 23 dB: 15 - 69.23 - 23 = -77.23 dBm
    code, out, _ = run(capsys, "radio", "link", wall_npz, "--from", "10,20.25", "--to", "30,20.25", "--freq", "5.2")
    assert code == 0 and "RSSI: -77.23 dBm" in out
    # tx 0 dBm: -77.51 dBm is still >= -82; sensitivity -70 makes it fail, short by 7.51 dB
    code, out, _ = run(capsys, "radio", "link", wall_npz, "--from", "10,20.25", "--to", "30,20.25",
                       "--tx-power", "0", "--sensitivity", "-70")
    assert code == 0 and "verdict: no link (short by 7.51 dB)" in out
    code, out, _ = run(capsys, "radio", "link", wall_npz, "--from", "10,20.25", "--to", "30,20.25", "--model", "los")
    assert code == 0 and "verdict: no link (wall in the way)" in out


def test_link_material_from_param_and_config(capsys, tmp_path):
    npz = str(save_npz(Plan(40, 40, ("air", "concrete", "plaster")).wall(20, 0.5, 21, 39.5, "plaster").build(),
                       tmp_path / "p.npz"))
    code, _, err = run(capsys, "radio", "link", npz, "--from", "10,20.25", "--to", "30,20.25")
    assert code == 2 and "material: got 'plaster'" in err and err.count("\n") == 1
    # 15 - 62.51 - 4 = -51.51 dBm
    code, out, _ = run(capsys, "radio", "link", npz, "--from", "10,20.25", "--to", "30,20.25",
                       "--param", "materials.plaster=4")
    assert code == 0 and "plaster 1.00 m -> 4.00 dB" in out and "RSSI: -51.51 dBm" in out
    toml = tmp_path / "radio.toml"
    toml.write_text("[radio]\ntx_power_dbm = 20.0\n[radio.materials]\nplaster = 4.0\n")
    code, out, _ = run(capsys, "radio", "link", npz, "--from", "10,20.25", "--to", "30,20.25", "--config", str(toml))
    assert code == 0 and "RSSI: -46.51 dBm" in out  # 20 - 62.51 - 4


@pytest.mark.parametrize("extra, needle", [
    (["--freq", "-1"], "--freq: got -1.0"),
    (["--freq", "nan"], "--freq: got nan"),
    (["--max-range", "10", "--model", "multiwall"], "--max-range"),
    (["--model", "rayleigh"], "'rayleigh' is not one of"),
    (["--param", "frequency=2"], "frequency: got 2"),
])
def test_link_bad_options_are_one_line(capsys, wall_npz, extra, needle):
    code, _, err = run(capsys, "radio", "link", wall_npz, "--from", "10,20.25", "--to", "30,20.25", *extra)
    assert code == 2 and needle in err
    assert err.startswith("swarm: error: ") and err.count("\n") == 1


def test_points_outside_the_map(capsys, wall_npz):
    code, _, err = run(capsys, "radio", "link", wall_npz, "--from", "10,20", "--to", "50,20")
    assert code == 2 and "--to: got '50,20'" in err and "0 <= x < 40" in err
    code, _, err = run(capsys, "radio", "heatmap", wall_npz, "--tx", "1e9,3", "-o", "x.png")
    assert code == 2 and "--tx" in err


def test_heatmap_writes_a_picture(capsys, wall_npz, tmp_path):
    png = tmp_path / "rssi.png"
    code, out, _ = run(capsys, "radio", "heatmap", wall_npz, "--tx", "10,20.25", "-o", str(png), "--scale", "2")
    assert code == 0 and "hears the transmitter" in out and png.exists()
    assert Image.open(png).width == 80 * 2  # 40 m = 80 cells at 2 px


def test_link_itemises_shadowing_and_packet_errors(capsys, wall_npz):
    """The shadowing term is the link model's own (the map file's seed) and moves the RSSI by itself; the
    PER line shows the curve at the link's margin."""
    from maps.io import load_map
    from radio import RadioConfig, build_link_model

    args = ("radio", "link", wall_npz, "--from", "10,20.25", "--to", "30,20.25")
    code, out, _ = run(capsys, *args, "--param", "shadowing_sigma_db=6", "--param", "per=bpsk", "--sensitivity", "-65")
    assert code == 0
    truth = load_map(wall_npz)
    shadow = build_link_model(truth, RadioConfig(shadowing_sigma_db=6.0)).budget((10, 20.25), (30, 20.25))
    plain = build_link_model(truth, RadioConfig()).budget((10, 20.25), (30, 20.25))
    assert f"shadowing: {shadow.shadowing_db:+.2f} dB (sigma 6 dB" in out and shadow.shadowing_db != 0.0
    assert shadow.rssi_dbm == pytest.approx(plain.rssi_dbm - shadow.shadowing_db, abs=1e-9)
    assert f"RSSI: {shadow.rssi_dbm:.2f} dBm" in out
    assert "packet error rate (bpsk): 100 B" in out and "4096 B" in out
    code, out, _ = run(capsys, *args)
    assert "shadowing" not in out and "packet error" not in out
    code, _, err = run(capsys, *args, "--model", "los", "--param", "shadowing_sigma_db=6")
    assert code == 2 and "shadowing_sigma_db" in err and len(err.strip().splitlines()) == 1
