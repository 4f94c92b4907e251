"""Radio cost: ``python benchmarks/speed/bench_radio.py [--size 150] [--robots 16] [--seeds 5] [--calls 2000]``.

Prints, for building maps of the given size:

- build: ``build_link_model`` (material table + per-quadrant uniform squares), numba compile excluded;
- evaluate: one all-pairs ``LinkModel.evaluate`` (distance, walls, RSSI, link matrices) for R robots at
  fresh positions every call (robots random-walk 0.3 m per call, so the per-tick cache never hits);
- kernel: the grid walk alone, with and without empty-space skipping (the numba cell-by-cell walk);
- heatmap: ``rssi_field`` to every free cell from one transmitter.

Figures are CPU time of this process per call (``time.process_time``, so time spent descheduled by other
jobs on a shared machine does not count): the median over ``--repeats`` batches, and the best batch. The
goal is <= 0.1 ms per evaluate for 16 robots on 150 x 150 m on one core.
"""

from __future__ import annotations

import argparse
import statistics
import time

import numpy as np

from maps import generate
from radio import build_link_model
from radio.crossings import WallRaster
from radio.heatmap import rssi_field


def robot_tracks(m, robots: int, calls: int, rng: np.random.Generator) -> list[np.ndarray]:
    """Position arrays for ``calls`` ticks: random free cells, then a 0.3 m random walk kept inside free space."""
    free = np.argwhere(m.free)
    xy = (free[rng.choice(len(free), robots, replace=False)][:, ::-1] + 0.5) * 0.5
    out = []
    for _ in range(calls):
        step = rng.normal(0.0, 0.3, xy.shape)
        moved = xy + step
        ok = np.array([m.is_free_at(x, y) for x, y in moved])
        xy = np.where(ok[:, None], moved, xy)
        out.append(np.ascontiguousarray(xy))
    return out


def per_call_us(fn, inputs: list, repeats: int) -> tuple[float, float]:
    """(median, best) CPU microseconds per call over ``repeats`` batches, each calling ``fn`` on every input."""
    batches = []
    for _ in range(repeats):
        t0 = time.process_time()
        for x in inputs:
            fn(x)
        batches.append((time.process_time() - t0) / len(inputs) * 1e6)
    return statistics.median(batches), min(batches)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--size", type=int, default=150)
    ap.add_argument("--robots", type=int, default=16)
    ap.add_argument("--seeds", type=int, default=5)
    ap.add_argument("--calls", type=int, default=500)
    ap.add_argument("--repeats", type=int, default=15)
    args = ap.parse_args()

    warm = generate("building", 30, 0)  # compile / load the numba cache once
    t0 = time.perf_counter()
    model = build_link_model(warm)
    model.evaluate(np.array([[2.0, 2.0], [20.0, 20.0]]))
    rssi_field(model, (2.0, 2.0))
    print(f"first build + evaluate + field (numba cache load or compile): {(time.perf_counter() - t0) * 1000:.0f} ms")

    pairs = args.robots * (args.robots - 1) // 2
    rows = []
    for seed in range(args.seeds):
        m = generate("building", args.size, seed)
        t0 = time.perf_counter()
        model = build_link_model(m)
        build_ms = (time.perf_counter() - t0) * 1000
        tracks = robot_tracks(m, args.robots, args.calls, np.random.default_rng(seed))
        evaluate = per_call_us(model.evaluate, tracks, args.repeats)
        walls = float(np.mean([model.evaluate(x).walls.sum() / 2 / pairs for x in tracks[:50]]))
        plain = WallRaster.from_map(m, skip_empty_space=False)
        c, t = model.cross_db, model.tol
        kernel = per_call_us(lambda x: model.raster.all_pairs(x, t, c, c, False), tracks, args.repeats)
        kernel_plain = per_call_us(lambda x: plain.all_pairs(x, t, c, c, False), tracks[: args.calls // 4],
                                   args.repeats)
        t0 = time.perf_counter()
        rssi_field(model, tuple(tracks[0][0]))
        field_ms = (time.perf_counter() - t0) * 1000
        rows.append((build_ms, evaluate, kernel, kernel_plain, field_ms))
        print(f"building {args.size} seed {seed}: build {build_ms:5.1f} ms | evaluate {evaluate[0]:6.1f} us "
              f"(best {evaluate[1]:6.1f}) | kernel {kernel[0]:6.1f} us, cell-by-cell {kernel_plain[0]:6.1f} us | "
              f"heatmap {field_ms:5.0f} ms | {walls:.1f} walls per pair")
    print(f"mean over {args.seeds} maps, {args.robots} robots ({pairs} pairs): "
          f"evaluate {statistics.mean(r[1][0] for r in rows):.1f} us per call "
          f"(best {min(r[1][1] for r in rows):.1f}), kernel {statistics.mean(r[2][0] for r in rows):.1f} us, "
          f"build {statistics.mean(r[0] for r in rows):.1f} ms")


if __name__ == "__main__":
    main()
