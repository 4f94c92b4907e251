"""Render a map to a picture: walls coloured by material, free space light, a legend; north up."""

from __future__ import annotations

from pathlib import Path

import numpy as np
from PIL import Image, ImageDraw, ImageFont

from swarm.base.errors import InvalidInput
from .materials import colour_of
from .model import Map

MAX_PICTURE_PIXELS = 2**26
"""A picture (map or heatmap) of more pixels is refused: 64 Mpx is 192 MiB of RGB before PNG encoding."""


def palette(m: Map) -> np.ndarray:
    """(n_materials, 3) uint8 colours for the map's material table."""
    return np.array([colour_of(name) for name in m.materials], dtype=np.uint8)


def map_rgb(m: Map) -> np.ndarray:
    """(H, W, 3) uint8 image of the map, row 0 at the top (north up)."""
    return palette(m)[m.material][::-1]


def auto_scale(m: Map, target_px: int = 900) -> int:
    """Pixels per cell so the picture is about ``target_px`` on its longer side."""
    return max(1, target_px // max(m.shape))


def check_scale(m: Map, scale: int | None, field: str = "scale") -> int:
    """``scale`` (or the automatic one) if the picture of ``m`` stays within ``MAX_PICTURE_PIXELS``, else an
    :class:`InvalidInput` naming ``field`` with the largest scale that fits."""
    scale = scale or auto_scale(m)
    rows, cols = m.shape
    if rows * cols * scale * scale > MAX_PICTURE_PIXELS:
        largest = int((MAX_PICTURE_PIXELS / (rows * cols)) ** 0.5)
        raise InvalidInput(field, scale, f"at most {largest} pixels per cell for this {cols} x {rows}-cell map "
                                         f"(pictures of at most {MAX_PICTURE_PIXELS} pixels)")
    return scale


def upscale(rgb: np.ndarray, scale: int) -> Image.Image:
    """A layer of cell colours (uint8[H, W, 3], row 0 at the bottom, as a map's rows) as a north-up picture
    of ``scale`` pixels per cell: what the map, the radio heatmap and a run's frames are drawn on."""
    return Image.fromarray(np.ascontiguousarray(np.repeat(np.repeat(rgb[::-1], scale, 0), scale, 1)), "RGB")


def render(m: Map, scale: int | None = None, legend: bool = True, title: str | None = None) -> Image.Image:
    """The map as a PIL image; ``scale`` pixels per 0.5 m cell (automatic if None)."""
    scale = check_scale(m, scale)
    image = upscale(palette(m)[m.material], scale)
    if not legend:
        return image
    return add_legend(image, m, title)


def add_legend(image: Image.Image, m: Map, title: str | None = None) -> Image.Image:
    """Append a strip under ``image`` listing the wall materials present in ``m`` and a 10 m scale bar."""
    font = ImageFont.load_default()
    present = np.unique(m.material[m.solid])
    entries = [(m.materials[i], colour_of(m.materials[i])) for i in present.tolist()]
    strip_h = 44 if title else 26
    out = Image.new("RGB", (image.width, image.height + strip_h), (255, 255, 255))
    out.paste(image, (0, 0))
    draw = ImageDraw.Draw(out)
    y = image.height + 6
    x = 6
    for name, colour in entries:
        draw.rectangle([x, y, x + 12, y + 12], fill=colour, outline=(0, 0, 0))
        draw.text((x + 16, y), name, fill=(0, 0, 0), font=font)
        x += 24 + int(draw.textlength(name, font=font))
    px_per_m = image.width / m.width_m
    bar = 10.0 if px_per_m * 10 <= image.width / 3 else 1.0
    x1 = image.width - 8
    x0 = x1 - int(round(bar * px_per_m))
    draw.line([x0, y + 6, x1, y + 6], fill=(0, 0, 0), width=2)
    draw.text((x0, y - 5 if y > 5 else y), f"{bar:g} m", fill=(0, 0, 0), font=font)
    if title:
        draw.text((6, y + 18), title, fill=(0, 0, 0), font=font)
    return out


def save_png(m: Map, path: str | Path, scale: int | None = None, title: str | None = None) -> Path:
    """Render and write a PNG atomically."""
    from .io import atomic_write_bytes
    import io

    buf = io.BytesIO()
    render(m, scale=scale, title=title).save(buf, format="PNG")
    return atomic_write_bytes(Path(path), buf.getvalue())
