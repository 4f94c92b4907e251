"""RSSI over a whole map from one transmitter, and its picture with the sensitivity contour.

The picture a researcher wants before a campaign: where a robot at ``tx`` can be heard. Every free cell
centre is a receiver (one numba walk per cell; ``benchmarks/speed/bench_radio.py`` times it); walls are drawn in
their material colours, free space in a viridis-like ramp of RSSI, cells below the receiver sensitivity
are dimmed, and the cells on the edge of the linked region (the sensitivity contour) are drawn in magenta
(brick walls are red). Rendering uses Pillow only (no matplotlib dependency), like :mod:`maps.render`.
"""

from __future__ import annotations

import io
import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from PIL import Image, ImageDraw, ImageFont

from maps.io import atomic_write_bytes
from maps.model import CELL_M, Map
from maps.render import check_scale, palette, upscale

from .models import LinkModel, Point

# Viridis at nine evenly spaced stops (matplotlib's colormap, sampled), interpolated linearly.
_RAMP = np.array([(68, 1, 84), (71, 44, 122), (59, 81, 139), (44, 113, 142), (33, 144, 141), (39, 173, 129),
                  (92, 200, 99), (170, 220, 50), (253, 231, 37)], dtype=np.float64)
CONTOUR_RGB = (255, 0, 255)
DIM_BELOW_SENSITIVITY = 0.45
"""Cells that cannot hear ``tx`` keep this fraction of their colour (blended towards grey)."""


@dataclass(frozen=True, eq=False)
class RssiField:
    """RSSI (dBm) and link verdict at every cell centre for one transmitter; NaN / False on solid cells."""

    tx: tuple[float, float]
    rssi: np.ndarray
    link: np.ndarray
    sensitivity_dbm: float
    tx_power_dbm: float
    model: str

    @property
    def linked_share(self) -> float:
        """Fraction of the free cells that hear the transmitter."""
        free = ~np.isnan(self.rssi)
        return float(self.link[free].mean()) if free.any() else 0.0


def rssi_field(model: LinkModel, tx: Point, *, tx_power_dbm: float | None = None,
               sensitivity_dbm: float | None = None) -> RssiField:
    """Evaluate ``model`` from ``tx`` to the centre of every free cell of its map."""
    truth = model.truth
    rows, cols = np.nonzero(truth.free)
    targets = np.column_stack(((cols + 0.5) * CELL_M, (rows + 0.5) * CELL_M))
    tx_dbm = model.config.tx_power_dbm if tx_power_dbm is None else float(tx_power_dbm)
    sens = model.config.sensitivity_dbm if sensitivity_dbm is None else float(sensitivity_dbm)
    values, linked = model.field(tx, targets, tx_power_dbm=tx_dbm, sensitivity_dbm=sens)
    rssi = np.full(truth.shape, np.nan)
    link = np.zeros(truth.shape, dtype=bool)
    rssi[rows, cols] = values
    link[rows, cols] = linked
    return RssiField((float(tx[0]), float(tx[1])), rssi, link, sens, tx_dbm, model.name)


def colour_ramp(values: np.ndarray, lo: float, hi: float) -> np.ndarray:
    """uint8[..., 3] viridis-like colours for ``values`` scaled from ``lo`` (dark) to ``hi`` (bright).

    Scaled in halves (exact: halving a float is), so that any finite ``lo`` and ``hi`` work: ``hi - lo`` of
    ``--tx-power 1e308 --sensitivity -1e308`` would overflow to inf and make every position NaN."""
    span = hi * 0.5 - lo * 0.5 if hi > lo else 0.5
    with np.errstate(over="ignore"):  # a value far outside [lo, hi] goes to +-inf, then to the ramp's end
        x = np.clip((np.nan_to_num(values, nan=lo, neginf=lo, posinf=hi) * 0.5 - lo * 0.5) / span, 0.0, 1.0)
    pos = x * (len(_RAMP) - 1)
    i = np.minimum(pos.astype(int), len(_RAMP) - 2)
    w = (pos - i)[..., None]
    return np.round(_RAMP[i] * (1 - w) + _RAMP[i + 1] * w).astype(np.uint8)


def contour_mask(link: np.ndarray, free: np.ndarray) -> np.ndarray:
    """Linked free cells with an unlinked free 4-neighbour: the sensitivity contour, one cell wide."""
    edge = np.zeros_like(link)
    for axis in (0, 1):
        for shift in (1, -1):
            other_link = np.roll(link, shift, axis=axis)
            other_free = np.roll(free, shift, axis=axis)
            edge |= link & free & other_free & ~other_link
    return edge


def field_range(field: RssiField) -> tuple[float, float]:
    """Colour range: 20 dB below the sensitivity up to the strongest finite RSSI (at least 1 dB wide)."""
    finite = field.rssi[np.isfinite(field.rssi)]
    lo = field.sensitivity_dbm - 20.0
    hi = float(finite.max()) if finite.size else field.tx_power_dbm
    return lo, max(hi, lo + 1.0)


def render_heatmap(truth: Map, field: RssiField, scale: int | None = None, title: str | None = None) -> Image.Image:
    """The RSSI field over the map as a PIL image (north up) with a colour-bar legend underneath."""
    scale = check_scale(truth, scale)
    lo, hi = field_range(field)
    free = truth.free
    rgb = colour_ramp(field.rssi, lo, hi).astype(np.float64)
    dim = free & ~field.link
    rgb[dim] = rgb[dim] * DIM_BELOW_SENSITIVITY + 128.0 * (1.0 - DIM_BELOW_SENSITIVITY)
    rgb = rgb.astype(np.uint8)
    rgb[~free] = palette(truth)[truth.material[~free]]
    rgb[contour_mask(field.link, free)] = CONTOUR_RGB
    image = upscale(rgb, scale)
    draw = ImageDraw.Draw(image)
    px = field.tx[0] / CELL_M * scale
    py = image.height - field.tx[1] / CELL_M * scale
    radius = max(3, 2 * scale)
    draw.ellipse([px - radius, py - radius, px + radius, py + radius], fill=(255, 255, 255), outline=(0, 0, 0))
    return _with_legend(image, lo, hi, field, title)


def _with_legend(image: Image.Image, lo: float, hi: float, field: RssiField, title: str | None) -> Image.Image:
    font = ImageFont.load_default()
    strip_h = 56 if title else 40
    out = Image.new("RGB", (image.width, image.height + strip_h), (255, 255, 255))
    out.paste(image, (0, 0))
    draw = ImageDraw.Draw(out)
    y = image.height + 6
    bar_w = max(60, min(300, image.width - 12))
    ramp = (colour_ramp(np.linspace(lo, hi, bar_w), lo, hi) if math.isfinite(hi - lo)
            else colour_ramp(np.linspace(0.0, 1.0, bar_w), 0.0, 1.0))  # the same ramp, for ranges beyond floats
    out.paste(Image.fromarray(np.repeat(ramp[None, :, :], 10, axis=0), "RGB"), (6, y))
    draw.text((6, y + 12), f"{lo:.0f} dBm", fill=(0, 0, 0), font=font)
    hi_text = f"{hi:.0f} dBm"
    draw.text((6 + bar_w - draw.textlength(hi_text, font=font), y + 12), hi_text, fill=(0, 0, 0), font=font)
    note = (f"magenta: sensitivity {field.sensitivity_dbm:g} dBm ({field.model}, tx {field.tx_power_dbm:g} dBm, "
            f"{100 * field.linked_share:.0f}% of free space linked)")
    x_note = 12 + bar_w
    if x_note + draw.textlength(note, font=font) > out.width:
        x_note = 6
        y += 14
    draw.text((x_note, y), note, fill=(0, 0, 0), font=font)
    if title:
        draw.text((6, image.height + strip_h - 16), title, fill=(0, 0, 0), font=font)
    return out


def save_heatmap(truth: Map, field: RssiField, path: str | Path, scale: int | None = None,
                 title: str | None = None) -> Path:
    """Render and write a PNG atomically."""
    buf = io.BytesIO()
    render_heatmap(truth, field, scale=scale, title=title).save(buf, format="PNG")
    return atomic_write_bytes(Path(path), buf.getvalue())
