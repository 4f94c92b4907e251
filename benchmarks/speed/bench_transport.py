"""Transport and map-sharing costs on the issue-3 workload (16 robots, 150 x 150 building, frontier).

    python benchmarks/speed/bench_transport.py [--ticks 3000] [--robots 16] [--split] [--no-sharing]

Prints, for the same spec: ticks per wall and CPU second with the in-process and the zenoh transport
(agents in the runtime's process, so every observation and action goes through a real zenoh session),
and map-sharing bytes per tick with delta updates versus full maps (every 10 ticks). Each configuration
runs twice and the faster run is reported (the machine may be shared).

``--split`` adds one run per transport with phase timers on (:mod:`swarm.transport.timing`; the timers
slow those runs a little, so their ticks/s are printed apart) and splits the zenoh transport's extra time
per tick into zenoh's own share (inside the obs and act ``put``: delivery and callbacks, minus the
agents' decoding that runs inside the obs callbacks; remote replies awaited), our encoding and decoding on both sides, and the algorithm's own difference.
"""

from __future__ import annotations

import argparse
import time

from swarm.simulation import Simulation, TransportOptions
from swarm.transport import PhaseTimes

SHOWN = ("host: inputs", "host: batch", "host: changed cells", "host: neighbours", "host: obs encode",
         "zenoh: obs put", "agent: observe", "agent: obs decode", "agent: inbox decode", "agent: answer",
         "agent: algorithm", "agent: act encode", "zenoh: act put", "host: act decode")


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
    zenoh_own = (tz.own("zenoh: obs put", "agent: observe") + tz.get("zenoh: act put")
                 + tz.get("zenoh: wait for remote replies"))
    ours = (tz.get("host: batch") + tz.get("host: obs encode") + tz.get("agent: observe")
            + tz.own("agent: answer", "agent: algorithm") + tz.get("host: act decode") - ti.get("host: inputs"))
    algorithm = tz.get("agent: algorithm") / nz - ti.get("agent: algorithm") / ni
    total = sz - si
    per_call = timer_cost()
    timers = per_call * (sum(tz.calls.values()) / nz - sum(ti.calls.values()) / ni)
    print(f"zenoh overhead {1e3 * total:.3f} ms/tick = zenoh's own (obs and act puts, deliveries, "
          f"minus the agents' work inside them) "
          f"{1e3 * zenoh_own / nz:.3f} + our encoding/decoding (batch + obs encode + agent decode/encode "
          f"+ act decode - in-process inputs) {1e3 * ours / nz:.3f} + algorithm {1e3 * algorithm:+.3f} "
          f"+ rest of the loop {1e3 * (total - zenoh_own / nz - ours / nz - algorithm):+.3f} (of which the "
          f"extra phase timers, {1e6 * per_call:.2f} us a call, about {1e3 * timers:.3f})")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--ticks", type=int, default=3000)
    ap.add_argument("--robots", type=int, default=16)
    ap.add_argument("--size", type=int, default=150)
    ap.add_argument("--split", action="store_true", help="also split the zenoh overhead per tick (timed runs)")
    ap.add_argument("--no-sharing", action="store_true", help="skip the map-sharing comparison")
    args = ap.parse_args()
    base = {"seed": 1, "map": {"kind": "building", "size": args.size}, "robots": {"count": args.robots},
            "stop": {"max_ticks": args.ticks}}
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
