"""Transport and map-sharing costs on the issue-3 workload (16 robots, 150 x 150 building, frontier).

    python benchmarks/speed/bench_transport.py [--ticks 3000] [--robots 16] [--split] [--no-sharing] [--pairs N]

Prints, for the same spec: ticks per wall and CPU second with the in-process and the zenoh transport
(agents in the runtime's process, so every observation and action goes through a real zenoh session),
and map-sharing bytes per tick with delta updates versus full maps (every 10 ticks). Each configuration
runs twice and the faster run is reported (the machine may be shared).

``--split`` adds one run per transport with phase timers on (:mod:`swarm.transport.timing`; the timers
slow those runs a little, so their ticks/s are printed apart) and splits the zenoh transport's extra time
per tick into zenoh's own share (the obs and act ``put``: delivery and the callbacks that keep the
packets; remote replies awaited), our encoding and decoding on both sides, and the algorithm's own
difference. Agents in the runtime's process are served by one batch each way per tick
(:mod:`swarm.transport.batch`), so each phase is one call a tick.

``--pairs N`` is the figure to quote: N in-process and N zenoh runs of the same spec alternated in this one
process (the machine's speed drifts within minutes, so only neighbouring runs compare), and the zenoh
transport's extra time per tick, pair by pair, in wall and in CPU time: median, quartiles and range.
"""

from __future__ import annotations

import argparse
import statistics
import time

from swarm.sim.loop import Simulation, TransportOptions
from swarm.transport import PhaseTimes

SHOWN = ("host: inputs", "host: batch", "host: changed cells", "host: neighbours", "host: obs encode",
         "zenoh: obs put", "agent: observe", "agent: algorithm", "agent: act encode", "zenoh: act put",
         "host: act decode")


def measure(spec: dict) -> tuple[float, float, dict]:
    best = None
    for _ in range(2):
        sim = Simulation(spec)
        cpu0 = time.process_time()
        r = sim.run()
        cpu = time.process_time() - cpu0
        row = (r.summary["ticks"] / r.summary["wall_time_s"], r.summary["ticks"] / cpu, r.summary)
        best = row if best is None or row[0] > best[0] else best
    return best  # type: ignore[return-value]


def timed_run(spec: dict) -> tuple[PhaseTimes, float, int]:
    """One run with phase timers on: the timers, seconds per tick and ticks."""
    times = PhaseTimes()
    summary = Simulation(spec, transport=TransportOptions(times=times)).run().summary
    return times, summary["wall_time_s"] / summary["ticks"], summary["ticks"]


def timer_cost() -> float:
    """Seconds a timed call adds to a plain one (best of five, hot)."""
    timed_noop, calls = PhaseTimes().wrap("noop", int), 100_000
    best = float("inf")
    for _ in range(5):
        t0 = time.perf_counter()
        for _ in range(calls):
            timed_noop()
        t1 = time.perf_counter()
        for _ in range(calls):
            int()
        best = min(best, (t1 - t0) - (time.perf_counter() - t1))
    return best / calls


def split(base: dict) -> None:
    """Print where the zenoh transport's extra time per tick goes (see the module docstring)."""
    runs = {t: timed_run({**base, "transport": t}) for t in ("inprocess", "zenoh")}
    (ti, si, ni), (tz, sz, nz) = runs["inprocess"], runs["zenoh"]
    print(f"with phase timers: in-process {1e3 * si:.3f} ms/tick, zenoh {1e3 * sz:.3f} ms/tick")
    print(f"{'ms per tick':28s} {'in-process':>10s} {'zenoh':>8s}")
    for phase in SHOWN:
        a, b = ti.seconds[phase] if ti.calls.get(phase) else None, tz.seconds[phase] if tz.calls.get(phase) else None
        print(f"  {phase:26s} {'' if a is None else f'{1e3 * a / ni:10.3f}':>10s} "
              f"{'' if b is None else f'{1e3 * b / nz:8.3f}':>8s}")
    zenoh_own = tz.get("zenoh: obs put") + tz.get("zenoh: act put") + tz.get("zenoh: wait for remote replies")
    ours = (tz.get("host: batch") + tz.get("host: changed cells") + tz.get("host: neighbours")
            + tz.get("host: obs encode") + tz.get("agent: observe") + tz.get("agent: act encode")
            + tz.get("host: act decode"))
    ours = ours / nz - (ti.get("host: batch") + ti.get("host: inputs")) / ni
    algorithm = tz.get("agent: algorithm") / nz - ti.get("agent: algorithm") / ni
    total = sz - si
    per_call = timer_cost()
    timers = per_call * (sum(tz.calls.values()) / nz - sum(ti.calls.values()) / ni)
    print(f"zenoh overhead {1e3 * total:.3f} ms/tick = zenoh's own (obs and act puts, deliveries) "
          f"{1e3 * zenoh_own / nz:.3f} + our encoding/decoding (batch, changed cells, neighbours, obs encode, "
          f"agent observe, act encode and decode, less in-process batch and inputs) {1e3 * ours:.3f} + algorithm "
          f"{1e3 * algorithm:+.3f} + rest of the loop {1e3 * (total - zenoh_own / nz - ours - algorithm):+.3f} "
          f"(of which the extra phase timers, {1e6 * per_call:.2f} us a call, about {1e3 * timers:.3f})")


def pairs(spec: dict, n: int) -> None:
    """Alternate in-process and zenoh runs of ``spec`` ``n`` times each (the order flips every pair, so neither
    side always runs on the warmer caches) and print zenoh's extra wall and CPU time per tick, pair by pair."""
    extra: dict[str, list[float]] = {"wall": [], "cpu": []}
    per_tick = {}
    for k in range(n):
        order = ("inprocess", "zenoh") if k % 2 == 0 else ("zenoh", "inprocess")
        for transport in order:
            sim = Simulation({**spec, "transport": transport})
            cpu0 = time.process_time()
            s = sim.run().summary
            per_tick[transport] = (s["wall_time_s"] / s["ticks"], (time.process_time() - cpu0) / s["ticks"], s)
        (wi, ci, si), (wz, cz, sz) = per_tick["inprocess"], per_tick["zenoh"]
        if si["final_poses"] != sz["final_poses"]:
            raise SystemExit("the transports gave different runs")
        extra["wall"].append(wz - wi)
        extra["cpu"].append(cz - ci)
        print(f"pair {k + 1}: in-process {1e3 * wi:.3f} ms/tick ({1e3 * ci:.3f} CPU), zenoh {1e3 * wz:.3f} "
              f"({1e3 * cz:.3f} CPU): +{1e3 * (wz - wi):.3f} ms wall, +{1e3 * (cz - ci):.3f} ms CPU", flush=True)
    for what, values in extra.items():
        ms = sorted(1e3 * v for v in values)
        q = statistics.quantiles(ms, n=4) if len(ms) > 1 else [ms[0]] * 3
        print(f"zenoh extra {what:4s} per tick over {len(ms)} pairs: median {statistics.median(ms):.3f} ms "
              f"(quartiles {q[0]:.3f}-{q[2]:.3f}, range {ms[0]:.3f}-{ms[-1]:.3f})")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--ticks", type=int, default=3000)
    ap.add_argument("--robots", type=int, default=16)
    ap.add_argument("--size", type=int, default=150)
    ap.add_argument("--split", action="store_true", help="also split the zenoh overhead per tick (timed runs)")
    ap.add_argument("--no-sharing", action="store_true", help="skip the map-sharing comparison")
    ap.add_argument("--pairs", type=int, default=0, metavar="N",
                    help="only the interleaved comparison: N in-process and N zenoh runs, alternated")
    args = ap.parse_args()
    base = {"seed": 1, "map": {"kind": "building", "size": args.size}, "robots": {"count": args.robots},
            "stop": {"max_ticks": args.ticks}}
    if args.pairs < 0:
        ap.error(f"--pairs: {args.pairs} is not allowed; give a whole number >= 1")
    if args.pairs:
        Simulation({**base, "transport": "zenoh", "stop": {"max_ticks": 50}}).run()  # load every kernel first
        pairs(base, args.pairs)
        return
    results = {}
    for transport in ("inprocess", "zenoh"):
        wall, cpu, summary = measure({**base, "transport": transport})
        results[transport] = summary
        print(f"{transport:9s}: {wall:7.0f} ticks/s wall, {cpu:7.0f} ticks per CPU-second")
    print(f"identical results: {results['inprocess']['final_poses'] == results['zenoh']['final_poses']}")
    if args.split:
        split(base)
    for mode in () if args.no_sharing else ("delta", "full"):
        _, _, s = measure({**base, "comm": {"map_sharing": mode}})
        m = s["messages"]
        print(f"map sharing {mode:5s}: {m['map_bytes_sent'] / s['ticks']:9.0f} bytes/tick sent "
              f"({m['map_bytes_sent'] / 1e6:.1f} MB over {s['ticks']} ticks), all messages "
              f"{m['bytes_sent'] / s['ticks']:.0f} bytes/tick, explored {100 * s['explored']:.1f}%")


if __name__ == "__main__":
    main()
