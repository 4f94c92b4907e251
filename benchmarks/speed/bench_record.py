"""Cost of recording a run (issue 10): file size and extra run time of ``--record``.

Runs the same spec without and with a :class:`swarm.record.Recorder` (alternating, ``--repeats`` pairs) and
reports wall and CPU time (the machine is shared: CPU time is the steadier figure), the time spent inside
the recorder itself (summed per tick, the least noisy measure of its cost), the ``.swr`` size with a
per-stream breakdown, the viewer page size, and how long loading and reconstructing take.

    python benchmarks/speed/bench_record.py                      # 150 x 150 building, 16 robots, seed 1, to 99 %
    python benchmarks/speed/bench_record.py --size 50 --robots 4 # a quick check
"""

from __future__ import annotations

import argparse
import json
import statistics
import tempfile
import time
import zlib
from pathlib import Path
from typing import Any

import msgpack

from swarm.record import Recorder, load_recording
from swarm.record.container import BLOCK, iter_chunks
from swarm.sim.loop import Simulation
from swarm.viewer import build_html


def timed_run(spec: dict[str, Any], record: bool) -> dict[str, Any]:
    sim = Simulation(spec)
    inside = [0.0]
    recorder = None
    if record:
        recorder = Recorder(sim)

        def observe(view: Any) -> None:
            t = time.process_time()   # CPU time: the wall clock also counts other engineers' jobs
            recorder(view)
            inside[0] += time.process_time() - t

        sim.observers = (observe,)
    w0, c0 = time.perf_counter(), time.process_time()
    result = sim.run()
    out: dict[str, Any] = {"ticks": result.summary["ticks"], "explored": result.summary["explored"]}
    if recorder is not None:
        t = time.process_time()
        recorder.finish(sim, result)
        data = recorder.to_bytes()
        out["finish_s"] = time.process_time() - t
        out["data"] = data
        out["recorder_s"] = inside[0] + out["finish_s"]
    out["wall_s"] = time.perf_counter() - w0
    out["cpu_s"] = time.process_time() - c0
    return out


def stream_sizes(data: bytes) -> dict[str, int]:
    """Bytes per field after compressing each field on its own (an approximation of its share)."""
    sizes: dict[str, int] = {}
    for kind, body in iter_chunks(data, "<bench>"):
        if kind != BLOCK:
            key = kind.decode()
            sizes[key] = sizes.get(key, 0) + len(zlib.compress(msgpack.packb(body, use_bin_type=True), 6))
            continue
        for name, value in body.items():
            sizes[name] = sizes.get(name, 0) + len(zlib.compress(msgpack.packb(value, use_bin_type=True), 6))
    return dict(sorted(sizes.items(), key=lambda kv: -kv[1]))


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--kind", default="building")
    ap.add_argument("--size", type=int, default=150)
    ap.add_argument("--robots", type=int, default=16)
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--max-ticks", type=int, default=None, help="stop early (quick checks; not the issue's figure)")
    ap.add_argument("--repeats", type=int, default=1, help="pairs of (plain, recorded) runs")
    ap.add_argument("--json", type=Path, help="also write the figures here")
    args = ap.parse_args()
    spec: dict[str, Any] = {"map": {"kind": args.kind, "size": args.size}, "robots": {"count": args.robots},
                            "seed": args.seed}
    if args.max_ticks:
        spec["stop"] = {"max_ticks": args.max_ticks}

    Simulation({"map": {"kind": "building", "size": 20}, "robots": {"count": 2}, "stop": {"max_ticks": 20}}).run()
    plain, recorded = [], []
    for _ in range(args.repeats):
        plain.append(timed_run(spec, record=False))
        recorded.append(timed_run(spec, record=True))
    data = recorded[-1].pop("data")
    for r in recorded[:-1]:
        r.pop("data")
    assert all(r["ticks"] == plain[0]["ticks"] for r in plain + recorded), "runs differ: not deterministic"

    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "run.swr"
        path.write_bytes(data)
        t = time.perf_counter()
        rec = load_recording(path)
        load_s = time.perf_counter() - t
        t = time.perf_counter()
        rec.state_at(rec.last_tick)
        state_s = time.perf_counter() - t
        t = time.perf_counter()
        page = build_html(data, str(path))
        html_s = time.perf_counter() - t

    def med(rows: list[dict[str, Any]], key: str) -> float:
        return statistics.median(r[key] for r in rows)

    figures = {
        "spec": spec, "ticks": plain[0]["ticks"], "explored": plain[0]["explored"],
        "plain_wall_s": med(plain, "wall_s"), "plain_cpu_s": med(plain, "cpu_s"),
        "recorded_wall_s": med(recorded, "wall_s"), "recorded_cpu_s": med(recorded, "cpu_s"),
        "recorder_s": med(recorded, "recorder_s"), "finish_s": med(recorded, "finish_s"),
        "swr_bytes": len(data), "html_bytes": len(page.encode()),
        "load_s": load_s, "state_at_last_tick_s": state_s, "build_html_s": html_s,
        "stream_bytes": stream_sizes(data),
        "runs": {"plain": plain, "recorded": recorded},
    }
    figures["extra_wall_pct"] = 100 * (figures["recorded_wall_s"] / figures["plain_wall_s"] - 1)
    figures["extra_cpu_pct"] = 100 * (figures["recorded_cpu_s"] / figures["plain_cpu_s"] - 1)
    figures["recorder_pct_of_plain_cpu"] = 100 * figures["recorder_s"] / figures["plain_cpu_s"]
    figures["recorder_us_per_tick"] = 1e6 * figures["recorder_s"] / max(1, figures["ticks"])

    print(f"{args.kind} {args.size}, {args.robots} robots, seed {args.seed}: {figures['ticks']} ticks, "
          f"explored {figures['explored']:.3f}, {args.repeats} pair(s)")
    print(f"  plain     wall {figures['plain_wall_s']:7.1f} s   cpu {figures['plain_cpu_s']:7.1f} s")
    print(f"  recorded  wall {figures['recorded_wall_s']:7.1f} s   cpu {figures['recorded_cpu_s']:7.1f} s   "
          f"(+{figures['extra_wall_pct']:.1f} % wall, +{figures['extra_cpu_pct']:.1f} % cpu)")
    print(f"  inside the recorder (CPU): {figures['recorder_s']:.2f} s = {figures['recorder_us_per_tick']:.0f} us/tick = "
          f"{figures['recorder_pct_of_plain_cpu']:.1f} % of the plain run's CPU time "
          f"(finish + compress tail {figures['finish_s']:.2f} s)")
    print(f"  .swr {figures['swr_bytes'] / 1e6:.2f} MB, viewer page {figures['html_bytes'] / 1e6:.2f} MB "
          f"({figures['html_bytes'] / figures['swr_bytes']:.2f}x)")
    print(f"  load {load_s:.2f} s, state at the last tick {state_s:.2f} s, build page {html_s:.2f} s")
    print("  bytes per field (each compressed alone):")
    for name, size in list(figures["stream_bytes"].items())[:12]:
        print(f"    {name:12s} {size / 1e6:8.3f} MB")
    if args.json:
        args.json.write_text(json.dumps(figures, indent=1))


if __name__ == "__main__":
    main()
