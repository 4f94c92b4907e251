"""``swarm run --mp4``: the GIF's frames as an H.264 MP4, and a clear error without the video extra."""

from __future__ import annotations

import sys

import numpy as np
import pytest
from PIL import Image

from swarm.cli import main

imageio_ffmpeg = pytest.importorskip("imageio_ffmpeg")

RUN = ["run", "--size", "30", "--robots", "2", "--max-ticks", "300", "--seed", "3"]


def test_mp4_has_the_gif_frames(tmp_path, capsys):
    gif, mp4 = tmp_path / "r.gif", tmp_path / "r.mp4"
    assert main([*RUN, "--gif", str(gif), "--mp4", str(mp4)]) == 0
    with Image.open(gif) as g:
        n_gif, (w, h) = g.n_frames, g.size
        g.seek(n_gif - 1)
        last_gif = np.asarray(g.convert("RGB"), dtype=np.int16)
    reader = imageio_ffmpeg.read_frames(str(mp4))
    meta = next(reader)
    frames = [np.frombuffer(f, np.uint8).reshape(meta["size"][1], meta["size"][0], 3) for f in reader]
    assert len(frames) == n_gif
    assert meta["size"] == (w + w % 2, h + h % 2)
    # lossy, but the same picture: the last frame matches the GIF's within video compression error
    last = frames[-1][:h, :w].astype(np.int16)
    assert np.abs(last - last_gif).mean() < 12
    assert frames[0].std() > 10  # not blank
    assert not list(tmp_path.glob(".*tmp*"))  # no temporary file left


def test_without_the_video_extra_mp4_is_a_one_line_error(tmp_path, capsys, monkeypatch):
    monkeypatch.setitem(sys.modules, "imageio_ffmpeg", None)  # import now raises ImportError
    code = main([*RUN, "--mp4", str(tmp_path / "r.mp4")])
    _, err = capsys.readouterr()
    assert code == 2 and err.count("\n") == 1 and "--mp4" in err and "video" in err
    assert not (tmp_path / "r.mp4").exists()
