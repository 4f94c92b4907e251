"""Animated GIF of a run: the truth map with wall materials, explored area, robots with headings and trails.

:class:`GifRecorder` is a per-tick observer of :class:`swarm.sim.loop.Simulation`. It keeps every pose
(cheap) and a bit-packed snapshot of the explored raster every ``frame_every`` ticks, doubling the
interval whenever more than ``max_frames`` snapshots pile up, so memory stays bounded however long the
run; the frames are drawn at the end.
"""

from __future__ import annotations

import io
from pathlib import Path

import numpy as np
from PIL import Image

from maps import CELL_M, Map
from maps.render import add_legend, auto_scale, upscale

from swarm.draw import ROBOT_COLOURS, SEEN_FREE, UNSEEN_FREE, draw_robots, union_layer

__all__ = ["ROBOT_COLOURS", "SEEN_FREE", "UNSEEN_FREE", "GifRecorder"]


class GifRecorder:
    def __init__(self, truth: Map, max_frames: int = 200, frame_every: int = 10) -> None:
        self.truth = truth
        self.max_frames = max_frames
        self.frame_every = frame_every
        self.poses: list[np.ndarray] = []
        self.snapshots: list[tuple[int, np.ndarray]] = []

    def __call__(self, view) -> None:  # noqa: ANN001 - a simulation.TickView
        self.poses.append(view.poses.astype(np.float32).copy())
        if view.tick % self.frame_every == 0:
            self.snapshots.append((view.tick, np.packbits(view.tracker.seen)))
            if len(self.snapshots) > self.max_frames:
                self.frame_every *= 2
                self.snapshots = [s for s in self.snapshots if s[0] % self.frame_every == 0]

    def save(self, path: str | Path, duration_ms: int = 80) -> Path:
        """Write the GIF atomically (encoded in memory first): a failed write leaves an existing file as it was."""
        from maps.io import atomic_write_bytes

        frames = self.frames()
        buffer = io.BytesIO()
        frames[0].save(buffer, format="GIF", save_all=True, append_images=frames[1:], duration=duration_ms, loop=0)
        return atomic_write_bytes(Path(path), buffer.getvalue())

    def save_mp4(self, path: str | Path, fps: int = 12) -> Path:
        """The same frames as an H.264 MP4 (for slides), through imageio-ffmpeg's bundled ffmpeg (the
        ``video`` extra). Written to a temporary file first, so a failed encode leaves nothing behind."""
        import imageio_ffmpeg

        frames = self.frames()
        width = max(f.size[0] for f in frames) + max(f.size[0] for f in frames) % 2  # yuv420p: even sides
        height = max(f.size[1] for f in frames) + max(f.size[1] for f in frames) % 2
        path = Path(path)
        tmp = path.with_name(f".{path.name}.tmp.mp4")
        writer = imageio_ffmpeg.write_frames(str(tmp), (width, height), fps=fps, codec="libx264",
                                             pix_fmt_out="yuv420p", macro_block_size=1, quality=7,
                                             output_params=["-movflags", "+faststart"], ffmpeg_log_level="error")
        writer.send(None)
        try:
            for frame in frames:
                canvas = Image.new("RGB", (width, height), (255, 255, 255))
                canvas.paste(frame.convert("RGB"), (0, 0))
                writer.send(canvas.tobytes())
        finally:
            writer.close()
        tmp.replace(path)
        return path

    def frames(self) -> list[Image.Image]:
        """One picture per snapshot: the map with every wall drawn (the building is the backdrop), the
        floor seen so far, each robot with its trail (:mod:`swarm.draw`), a legend and the tick."""
        truth = self.truth
        scale = auto_scale(truth, 600)
        h, w = truth.shape
        out = []
        for tick, packed in self.snapshots or [(0, np.packbits(np.zeros(truth.shape, bool)))]:
            seen = np.unpackbits(packed, count=h * w).reshape(h, w).astype(bool)
            image = upscale(union_layer(truth, seen, fade_unseen_walls=False), scale)
            if self.poses:
                poses = np.stack(self.poses[: tick + 1])
                n = poses.shape[1]
                draw_robots(image, poses[-1], h, scale, [ROBOT_COLOURS[i % len(ROBOT_COLOURS)] for i in range(n)],
                            max(2.0, 0.3 * scale / CELL_M), trails=poses[::5, :, :2])
            out.append(add_legend(image, truth, title=f"tick {tick}"))
        return out
