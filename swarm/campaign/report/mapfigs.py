"""The maps a campaign ran on, drawn for its report: per map value and size, the first few distinct maps
(a generator's first replicates, a folder's files in the order the runs met them), walls coloured by
material, in metres with a scale bar. A reader sees what "building 60" or "plans" means, and a floor plan
imported from HouseExpo is shown as the robots met it.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
from matplotlib.figure import Figure
from mpl_toolkits.axes_grid1.anchored_artists import AnchoredSizeBar

from maps import Map
from maps.materials import colour_of
from maps.render import map_rgb

from . import figures
from .load import CampaignData

MAX_PANELS = 4
"""Maps drawn per map value and size (a campaign may run on hundreds)."""


def campaign_maps(data: CampaignData) -> list[tuple[str, list[tuple[str, Map]]]]:
    """``[(title, [(panel title, map), ...]), ...]`` per map value and size, in spec order; empty when the
    stored spec cannot be read. Maps are rebuilt from the runs' specs exactly as the runs built them."""
    from swarm.sim.loop import build_map
    from swarm.sim.spec import seed_streams

    spec = data.spec
    runs = data.runs
    if spec is None or runs.empty:
        return []
    wanted = set(runs["key"].astype(str))
    index = {key: i for i, key in spec.iter_keys() if key in wanted}
    out: list[tuple[str, list[tuple[str, Map]]]] = []
    for (label, size), group in runs.groupby(["map", "size"], observed=True, sort=True):
        panels: list[tuple[str, Map]] = []
        seen: set[Any] = set()
        ordered = group.sort_values("replicate")
        for key, rep in zip(ordered["key"].astype(str), ordered["replicate"].astype(int)):
            if key not in index:
                continue
            run_spec = spec.run_at(index[key]).spec
            m = run_spec.map
            seed = seed_streams(run_spec).map_seed
            if m.kind == "file":
                ident: Any = (m.path, tuple(sorted(m.params.items())))
                name = Path(m.path).name
            else:
                ident, name = seed, f"replicate {rep}"
            if ident in seen:
                continue
            seen.add(ident)
            panels.append((name, build_map(run_spec, seed)))
            if len(panels) == MAX_PANELS:
                break
        if panels:
            out.append((f"{label} {size}", panels))
    return out


def map_figure(title: str, panels: list[tuple[str, Map]], width: float) -> Figure:
    """Small multiples of ``panels``: each map north up, axes in metres, a scale bar, a material legend."""
    cols, rows = figures._grid(len(panels), width, panel=2.2)
    side = (width - 0.3) / cols
    fig = figures._figure(width, rows * side + 0.9, left=0.45, right=0.1, bottom=0.55, top=0.55,
                          wspace=0.35, hspace=0.45)
    present: dict[str, tuple[int, int, int]] = {}
    for k, (name, m) in enumerate(panels):
        ax = fig.add_subplot(rows, cols, k + 1)
        ax.imshow(map_rgb(m), extent=(0.0, m.width_m, 0.0, m.height_m), interpolation="nearest")
        ax.set_title(name, fontsize=7)
        ax.set_xlabel("x (m)", fontsize=7)
        if k % cols == 0:
            ax.set_ylabel("y (m)", fontsize=7)
        ax.tick_params(labelsize=6)
        bar = _bar_length(m.width_m)
        ax.add_artist(AnchoredSizeBar(ax.transData, bar, f"{bar:g} m", "lower right", pad=0.3, frameon=True,
                                      size_vertical=m.width_m / 150, fontproperties={"size": 6}))
        for i in np.unique(m.material[m.solid]).tolist():
            present.setdefault(m.materials[i], colour_of(m.materials[i]))
    if present:
        from matplotlib.patches import Patch
        handles = [Patch(facecolor=np.array(c) / 255, edgecolor="black", label=n) for n, c in present.items()]
        fig.legend(handles=handles, loc="lower center", ncols=len(handles), frameon=False, fontsize=7)
    fig.suptitle(f"Maps of {title}: {len(panels)} shown, walls by material", fontsize=8)
    return fig


def _bar_length(extent_m: float) -> float:
    """A round scale-bar length, about a fifth of the map's width."""
    target = extent_m / 5
    for length in (1, 2, 5, 10, 20, 50, 100, 200, 500, 1000):
        if length >= target:
            return float(length)
    return 1000.0
