"""Inputs of ``swarm campaign`` that used to end in a traceback (issue 31) now end in one line and exit 2:
a spec or figure layout of random bytes, a special file, a bad ``--dask`` address, a scheduler that does
not answer, a report folder inside a file."""

from __future__ import annotations

import socket
import time
from pathlib import Path

import pytest

from maps import InvalidInput
from swarm.campaign.executors import DaskExecutor
from swarm.cli import main

from .test_campaign import TINY

RANDOM = bytes([0x80, 0xFF, 0x00, 0x5B, 0xC3, 0x28, 0x0A, 0xE2, 0x82]) * 20


def one_line_error(capsys, argv: list[str]) -> str:
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and err.startswith("swarm: error: ") and len(err) < 500, err
    return err


def test_a_campaign_file_of_random_bytes(tmp_path, capsys):
    spec = tmp_path / "random.toml"
    spec.write_bytes(RANDOM)
    err = one_line_error(capsys, ["campaign", "run", str(spec), "-o", str(tmp_path / "out")])
    assert "spec:" in err and "UTF-8" in err
    assert not (tmp_path / "out").exists()


@pytest.mark.skipif(not Path("/dev/zero").exists(), reason="needs /dev/zero")
def test_a_special_file_is_refused_before_it_is_read(tmp_path, capsys):
    assert "not a regular file" in one_line_error(capsys, ["campaign", "report", str(tmp_path), "--figures",
                                                           "/dev/zero"])


def test_a_figures_file_of_random_bytes(tmp_path, capsys):
    figures = tmp_path / "figures.toml"
    figures.write_bytes(RANDOM)
    assert "--figures" in one_line_error(capsys, ["campaign", "report", str(tmp_path), "--figures", str(figures)])


def test_a_report_folder_inside_a_file(tmp_path, capsys):
    (tmp_path / "file").write_text("x")
    err = one_line_error(capsys, ["campaign", "report", str(tmp_path), "-o", str(tmp_path / "file" / "rep")])
    assert "-o" in err or "DIR" in err


@pytest.mark.parametrize("address", ["garbage", "tcp://host", "http://h:80", "tcp://h:99999", "x" * 300])
def test_a_malformed_dask_address_fails_before_the_spec_is_read(tmp_path, capsys, address):
    spec = tmp_path / "tiny.toml"
    spec.write_text(TINY)
    err = one_line_error(capsys, ["campaign", "run", str(spec), "-o", str(tmp_path / "out"), "--dask", address])
    assert err.startswith("swarm: error: --dask:")
    assert not (tmp_path / "out").exists()


def test_nothing_listening_at_the_dask_address_fails_at_once(tmp_path, capsys):
    spec = tmp_path / "tiny.toml"
    spec.write_text(TINY)
    t0 = time.monotonic()
    err = one_line_error(capsys, ["campaign", "run", str(spec), "-o", str(tmp_path / "out"), "--dask",
                                  "tcp://127.0.0.1:1"])
    assert "--dask" in err and "127.0.0.1:1" in err and "refused" in err.lower()
    assert time.monotonic() - t0 < 10


@pytest.mark.timeout(60)
def test_a_dask_address_that_accepts_and_never_answers_times_out():
    """Dask bounds its connect but not its handshake: a silent port hung the campaign for good."""
    with socket.socket() as server:
        server.bind(("127.0.0.1", 0))
        server.listen()
        address = f"tcp://127.0.0.1:{server.getsockname()[1]}"
        t0 = time.monotonic()
        with pytest.raises(InvalidInput) as info:
            DaskExecutor(address, 1, timeout_s=1)
        assert time.monotonic() - t0 < 10
    assert info.value.field == "--dask" and "no answer within 1 s" in str(info.value)


def test_dask_connect_timeout_is_named_in_the_help(capsys):
    assert main(["campaign", "run", "--help"]) == 0
    out = " ".join(capsys.readouterr().out.split())
    assert "10 s" in out and "--max-runs" in out


def test_a_damaged_part_is_named_in_one_line(tmp_path, capsys):
    from swarm.campaign import make_executor, parse_campaign, run_campaign

    run_campaign(parse_campaign(TINY), tmp_path, executor=make_executor(inline=True), progress=False, shard=(0, 24))
    (part,) = (tmp_path / "parts").glob("*.runs.parquet")
    part.write_bytes(RANDOM)  # damaged outside the campaign (parts are written atomically)
    assert part.name[:20] in one_line_error(capsys, ["campaign", "report", str(tmp_path)])
    assert main(["campaign", "status", str(tmp_path)]) == 0  # status lists it (swarm.campaign.parts)
    out = capsys.readouterr().out
    assert f"damaged part, its runs count as pending: {part.name[:20]}" in out and "cannot be read" in out


def test_a_damaged_time_series_part_is_named_in_one_line(tmp_path, capsys):
    from swarm.campaign import make_executor, parse_campaign, run_campaign

    run_campaign(parse_campaign(TINY), tmp_path, executor=make_executor(inline=True), progress=False, shard=(0, 24))
    (part,) = (tmp_path / "parts").glob("*.timeseries.parquet")
    part.write_bytes(RANDOM)
    assert part.name[:20] in one_line_error(capsys, ["campaign", "report", str(tmp_path)])
