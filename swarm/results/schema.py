"""The shape of results, defined once: a run's summary, its time series, and a campaign's runs table.

Used by the metrics (time-series columns, thresholds), the simulation (the summary it builds), the
campaign runner and results store (runs rows, Parquet schemas) and the report loader (which columns it
reads). A result is plain JSON-able data (``swarm run --json``, Parquet parts); these types say what it
holds.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any, Literal, Mapping, TypedDict

if TYPE_CHECKING:  # pyarrow is imported only where a table is built: a run does not need its ~25 MB
    import pyarrow as pa

ArrowType = Literal["int64", "float64", "bool_", "string"]
"""A column's Arrow type by the name of its ``pyarrow`` factory (``"int64"`` ...): :func:`arrow_type`."""


def arrow_type(name: ArrowType) -> "pa.DataType":
    """The ``pyarrow`` type a column's type name stands for (imports pyarrow)."""
    import pyarrow as pa

    return getattr(pa, name)()

# ------------------------------------------------------------------------------------- thresholds ----
THRESHOLDS: tuple[float, ...] = (0.5, 0.75, 0.9, 0.95, 0.98, 0.99)
"""Explored fractions whose first tick every run records exactly (``summary["ticks_to"]``)."""


def threshold_key(threshold: float) -> str:
    """``"0.5"``, ``"0.99"``: how a threshold is written in ``ticks_to``."""
    return f"{threshold:g}"


THRESHOLD_COLUMNS: dict[str, str] = {threshold_key(t): f"t{round(t * 100)}" for t in THRESHOLDS}
"""``ticks_to`` key -> runs-table column (``"0.5" -> "t50"``)."""

# -------------------------------------------------------------------------------------- messages ----
DROP_CAUSES = ("dropped_link", "dropped_loss", "dropped_bandwidth")
"""Why a message did not reach a receiver: out of radio reach, lost (``comm.loss``), over the link's byte
budget (``comm.bandwidth``). "Dropped" always means their sum. Packet errors (``radio.per``) count as
``dropped_loss`` when the receiver was within the sensitivity and ``dropped_link`` when it was below it
(where a short message may still get through): the same split as without them (docs/radio.md)."""


def dropped(counts: Mapping[str, int]) -> int:
    """Messages dropped on the way, all causes (a summary's ``messages`` table or a time-series row)."""
    return sum(int(counts[cause]) for cause in DROP_CAUSES)


class RelayCounts(TypedDict, total=False):
    """The part of ``summary["messages"]`` present only when ``comm.relay = "flood"`` (docs/radio.md)."""

    relayed: int                    # relayed copies (counted in sent too)
    bytes_relayed: int              # their bytes (in bytes_sent too)
    duplicates: int                 # copies a robot received of a message it already had


class MessageCounts(RelayCounts):
    """``summary["messages"]``: what the radio carried over the run (counts are per receiver for delivered
    and dropped messages, per broadcast for sent ones)."""

    sent: int
    bytes_sent: int
    delivered: int
    bytes_delivered: int
    dropped_link: int
    dropped_loss: int
    dropped_bandwidth: int
    malformed: int                  # messages an algorithm tried to send that were not fit to (dropped)
    malformed_by_robot: list[int]
    map_bytes_sent: int
    last_contact: list[int]         # per robot: the last tick it received anything (-1: never)


class ActCounts(TypedDict):
    """``summary["acts"]``: per robot, act packets a remote agent's host did not take."""

    malformed: list[int]
    refused: list[int]
    late: list[int]
    duplicate: list[int]


class Summary(TypedDict):
    """``RunResult.summary``: everything a run computed, deterministic except the ``*_time_s`` fields."""

    ticks: int
    stop_reason: str                # explored | max_ticks | stalled | all_failed
    explored: float                 # fraction of the free cells some robot has seen
    coverage: float                 # fraction of the free cells some robot's disc has covered
    ticks_to: dict[str, int | None]  # threshold_key -> first tick explored reached it
    distance_m: list[float]         # per robot
    collisions: int                 # contacts begun: a robot starting to touch anything, once per robot
    collisions_wall: int            # a robot starting to touch a wall (counted per robot)
    collisions_robot: int           # a robot starting to touch another robot (counted for each of the two)
    seen_cells: int                 # cells (free or solid) some robot's own lidar saw
    own_seen_cells: list[int]       # per robot: cells (free or solid) its own lidar saw
    overlap_rate: float             # cells seen by 2+ robots' own lidars / cells seen (docs/benchmark-metrics.md)
    coverage_spread: float          # population std over robots of own-seen cells / cells seen
    plans: list[int]                # per robot: path plans made
    messages: MessageCounts
    acts: ActCounts
    failed_robots: list[int]
    final_poses: list[list[float]]
    map_seed: int | None
    wall_time_s: float
    setup_time_s: float


# ------------------------------------------------------------------------------------ time series ----
TIMESERIES: dict[str, tuple[ArrowType, str]] = {
    "tick": ("int64", "the tick of the row (every record_every ticks, and the last)"),
    "explored": ("float64", "fraction of free cells seen by some robot"),
    "coverage": ("float64", "fraction of free cells covered by some robot's disc"),
    "distance_m": ("float64", "metres driven by all robots so far"),
    "collisions": ("int64", "contacts begun so far"),
    "msgs_sent": ("int64", "messages broadcast so far"),
    "bytes_sent": ("int64", "their bytes"),
    "msgs_delivered": ("int64", "deliveries so far (one per receiver)"),
    "bytes_delivered": ("int64", "their bytes"),
    "msgs_dropped": ("int64", "messages dropped on the way so far, all causes (DROP_CAUSES)"),
    "comm_groups": ("int64", "communication groups (strongly connected) at this tick"),
    "biggest_group": ("float64", "the biggest group's share of the robots"),
    "all_connected": ("bool_", "one group holds every robot"),
    "mean_pair_distance_m": ("float64", "mean distance between robots"),
    "explored_correct": ("float64", "with a localisation model only: fraction of free cells some robot's map holds "
                                    "free where they are (docs/localization.md)"),
}
"""Time-series columns (``RunResult.timeseries``, ``*.timeseries.parquet`` with a ``key`` column first)."""
TIMESERIES_COLUMNS: tuple[str, ...] = tuple(TIMESERIES)
OPTIONAL_TIMESERIES: tuple[str, ...] = ("explored_correct",)
"""Time-series columns a run records only when they mean something (the last columns of the schema); without
them a run's series is what it was before they existed."""

# ---------------------------------------------------------------------------- communication ----
# ``RunResult.comm`` (docs/comm-metrics.md defines every quantity): its own summary and series, so the run's
# ``summary``, ``timeseries`` and ``events`` (what benchmarks/result_digests.py hashes) stay as they were.
COMM_SERIES: dict[str, tuple[ArrowType, str]] = {
    "tick": ("int64", "the tick of the row (the time series' ticks)"),
    **{f"msgs_{cause}": ("int64", f"deliveries failed so far for cause '{cause}' (one per receiver)")
       for cause in DROP_CAUSES},
    "bytes_dropped": ("int64", "bytes of the deliveries that failed so far, all causes"),
    "map_merges": ("int64", "map merges so far that left the receiver holding the sender's whole map"),
    "since_contact_mean": ("float64", "ticks since each robot last received a message, mean over robots"),
    "since_contact_max": ("int64", "the same, the longest"),
    "missing_free_mean": ("float64", "share of the team's known free cells a robot does not know, mean over "
                                        "robots"),
    "missing_free_max": ("float64", "the same, the robot missing most"),
    "aoi_age_mean": ("float64", "age of a robot's information about the others (ticks), mean over robots"),
    "aoi_age_max": ("float64", "the same, the robot with the oldest"),
}
"""Per-row communication columns (``RunResult.comm["series"]``; in a campaign, extra columns of
``*.timeseries.parquet``). The drop columns follow :data:`DROP_CAUSES`."""
COMM_SERIES_COLUMNS: tuple[str, ...] = tuple(COMM_SERIES)

COMM_ROBOT_SERIES: dict[str, tuple[ArrowType, str]] = {
    "missing_free": ("float64", "share of the team's known free cells this robot does not know"),
    "aoi_age": ("float64", "mean over the other robots of the ticks since this robot last merged their map"),
    "since_contact": ("int64", "ticks since this robot last received a message (since the start if never)"),
    "group": ("int64", "its communication group at this tick (groups numbered by their lowest robot id)"),
}
"""Per robot and row (``RunResult.comm["robots"][name][row][robot]``; in a campaign the long table
``*.robots.parquet``: key, tick, robot and these columns)."""


class CommSummary(TypedDict):
    """``RunResult.comm["summary"]``: means over the run's recorded rows (and robots, for per-robot
    quantities); a lone robot has nothing to miss or wait for (0)."""

    rows: int                       # recorded rows the means cover
    bytes_dropped: int
    map_merges: int
    comm_groups_mean: float
    biggest_group_mean: float
    all_connected_share: float      # share of recorded rows with every robot in one group
    since_contact_mean: float
    since_contact_max: int
    missing_free_mean: float
    missing_free_max: float
    aoi_age_mean: float
    aoi_age_max: float
    per_robot: dict[str, list[float]]  # missing_free_mean, aoi_age_mean, since_contact_mean: per robot


COMM_RUN_COLUMNS: dict[str, ArrowType] = {
    **{f"msgs_{cause}": "int64" for cause in DROP_CAUSES}, "msgs_relayed": "int64",
    "msgs_duplicates": "int64", "bytes_dropped": "int64",
    "map_merges": "int64", "comm_groups_mean": "float64", "biggest_group_mean": "float64",
    "all_connected_share": "float64", "since_contact_mean": "float64", "since_contact_max": "int64",
    "missing_free_mean": "float64", "missing_free_max": "float64", "aoi_age_mean": "float64",
    "aoi_age_max": "float64",
}
"""Runs-table columns from a run's messages and :class:`CommSummary` (None for failed runs and for results
of versions that did not record them)."""


def comm_columns(summary: Summary | Mapping[str, Any] | None, comm: Mapping[str, Any] | None) -> dict[str, Any]:
    """The runs-table columns of :data:`COMM_RUN_COLUMNS` for a run's summary and ``RunResult.comm``."""
    out: dict[str, Any] = {col: None for col in COMM_RUN_COLUMNS}
    if summary is not None:
        msgs = summary["messages"]
        for cause in DROP_CAUSES:
            out[f"msgs_{cause}"] = int(msgs[cause])
        out["msgs_relayed"], out["msgs_duplicates"] = int(msgs.get("relayed", 0)), int(msgs.get("duplicates", 0))
    if comm:
        for col in COMM_RUN_COLUMNS:
            if col in comm["summary"]:
                out[col] = comm["summary"][col]
    return out


# ------------------------------------------------------------------------------------- runs table ----
BENCHMARK_RUN_COLUMNS: dict[str, tuple[ArrowType, str]] = {
    "path_length_mean_m": ("float64", "mean over robots of the distance each drove (m; Explore-Bench)"),
    "path_length_cv": ("float64", "population standard deviation over robots of the distance driven, over its mean "
                                  "(0 when nobody moved)"),
    "overlap_rate": ("float64", "cells seen by the own lidars of two or more robots over the cells seen "
                                "(Explore-Bench)"),
    "coverage_spread": ("float64", "population standard deviation over robots of each robot's own-seen cells over "
                                   "the cells the team saw (Explore-Bench's coverage std)"),
}
"""Runs-table columns of the benchmark metrics (docs/benchmark-metrics.md); null for results of versions without
them (overlap and spread) and for failed runs. MAES's all-connected share and largest-cluster share are the
communication columns ``all_connected_share`` and ``biggest_group_mean``."""


def benchmark_columns(summary: Summary | Mapping[str, Any] | None) -> dict[str, Any]:
    """The runs-table columns of :data:`BENCHMARK_RUN_COLUMNS` for a run's summary."""
    if summary is None:
        return {c: None for c in BENCHMARK_RUN_COLUMNS}
    dist = [float(d) for d in summary["distance_m"]]
    mean = sum(dist) / len(dist) if dist else 0.0
    std = (sum((d - mean) ** 2 for d in dist) / len(dist)) ** 0.5 if dist else 0.0
    return {"path_length_mean_m": mean, "path_length_cv": std / mean if mean > 0 else 0.0,
            "overlap_rate": summary.get("overlap_rate"), "coverage_spread": summary.get("coverage_spread")}


LOCALIZATION_RUN_COLUMNS: dict[str, tuple[ArrowType, str]] = {
    "pose_error_m": ("float64", "mean over robots of the final position error of the pose estimate (m)"),
    "false_free_share": ("float64", "share of the cells the robots know that their maps say free where the truth "
                                    "is solid"),
    "false_occupied_share": ("float64", "share of the cells the robots know that their maps say solid where the "
                                        "truth is free"),
    "wall_offset_m": ("float64", "mean over robots of the mean distance from a wall cell of the map to the nearest "
                                 "true wall (m): a map-alignment error"),
    "explored_correct": ("float64", "share of the free cells some robot's map holds free where they are (the "
                                    "explored fraction counting only correctly known cells)"),
    **{f"{col}_correct": ("int64", f"first recorded tick at which explored_correct reached {t}")
       for t, col in THRESHOLD_COLUMNS.items()},
    "explored_measure": ("string", "'correct' when the run recorded explored_correct over time: reports count its "
                                   "explored fraction and ticks to thresholds on correctly known cells"),
}
"""Runs-table columns of a run with a localisation model (``[localization]``; null without one)."""
RUNS: dict[str, ArrowType] = {
    "key": "string", "campaign": "string", "index": "int64", "replicate": "int64",
    "map": "string", "size": "string", "robots": "int64", "spawn": "string", "algorithm": "string",
    "radio": "string", "comm": "string", "transport": "string", "map_kind": "string",
    "algorithm_name": "string", "radio_model": "string", "map_seed": "int64", "spawn_seed": "int64",
    "run_seed": "int64", "status": "string", "error": "string", "explored_target": "float64",
    "max_ticks": "int64", "ticks": "int64", "stop_reason": "string", "explored": "float64",
    "coverage": "float64", **{col: "int64" for col in THRESHOLD_COLUMNS.values()}, "distance_m": "float64",
    "collisions": "int64", "collisions_wall": "int64", "collisions_robot": "int64",
    **{c: t for c, (t, _) in BENCHMARK_RUN_COLUMNS.items()}, "msgs_sent": "int64", "bytes_sent": "int64", "msgs_delivered": "int64",
    "bytes_delivered": "int64", "msgs_dropped": "int64", "failed_robots": "int64", "spec_json": "string",
    "wall_time_s": "float64", "cpu_time_s": "float64", "jit_time_s": "float64", "worker_pid": "int64",
    "worker_rss_mb": "float64", "swarm_version": "string", "algorithm_dist": "string",
    "algorithm_version": "string", **COMM_RUN_COLUMNS, **{c: t for c, (t, _) in LOCALIZATION_RUN_COLUMNS.items()},
}
"""One row per run (``*.runs.parquet``); the store adds ``part`` (the file a row came from) when reading.
``wall_time_s`` and ``cpu_time_s`` time the whole run in its worker, ``jit_time_s`` the part of it in numba's
compiler (compiling or loading cached kernels: non-zero in a worker's first runs)."""
NONDETERMINISTIC_COLUMNS = ("wall_time_s", "cpu_time_s", "jit_time_s", "worker_pid", "worker_rss_mb", "part",
                            "swarm_version")
"""Columns that may differ between two executions of the same run."""


def summary_columns(summary: Summary | Mapping[str, Any] | None) -> dict[str, Any]:
    """The runs-table columns a run's summary fills (all None for a run that failed)."""
    if summary is None:
        return {"ticks": None, "stop_reason": "error", "explored": None, "coverage": None,
                **{col: None for col in THRESHOLD_COLUMNS.values()}, "distance_m": None, "collisions": None,
                "collisions_wall": None, "collisions_robot": None, **benchmark_columns(None), "msgs_sent": None, "bytes_sent": None, "msgs_delivered": None, "bytes_delivered": None,
                "msgs_dropped": None, "failed_robots": None, **{c: None for c in LOCALIZATION_RUN_COLUMNS}}
    msgs = summary["messages"]
    loc = summary.get("localization")   # only with a localisation model (Simulation._localization_summary)
    return {"ticks": summary["ticks"], "stop_reason": summary["stop_reason"], "explored": summary["explored"],
            "coverage": summary["coverage"],
            **{col: summary["ticks_to"].get(t) for t, col in THRESHOLD_COLUMNS.items()},
            "distance_m": float(sum(summary["distance_m"])), "collisions": summary["collisions"],
            "collisions_wall": summary.get("collisions_wall"), "collisions_robot": summary.get("collisions_robot"),
            **benchmark_columns(summary),
            "msgs_sent": msgs["sent"], "bytes_sent": msgs["bytes_sent"], "msgs_delivered": msgs["delivered"],
            "bytes_delivered": msgs["bytes_delivered"], "msgs_dropped": dropped(msgs),
            "failed_robots": len(summary["failed_robots"]),
            "pose_error_m": (sum(loc["final_position_error_m"]) / len(loc["final_position_error_m"])) if loc else None,
            "false_free_share": loc["false_free_share"] if loc else None,
            "false_occupied_share": loc["false_occupied_share"] if loc else None,
            "wall_offset_m": loc["wall_offset_mean_m"] if loc else None,
            "explored_correct": loc["explored_correct"] if loc else None,
            **{f"{col}_correct": loc.get("ticks_to_correct", {}).get(t) if loc else None
               for t, col in THRESHOLD_COLUMNS.items()},
            "explored_measure": "correct" if loc and "ticks_to_correct" in loc else None}


def timeseries_table(rows: list[dict[str, Any]]) -> "pa.Table":
    """Time-series rows (``key`` first, the communication columns after the others) as a table of the
    schema's types (extra columns inferred)."""
    import pyarrow as pa

    table = pa.Table.from_pylist(rows)
    return _cast_known(table, {"key": "string", **{c: t for c, (t, _) in TIMESERIES.items()},
                               **{c: t for c, (t, _) in COMM_SERIES.items()}})


def robots_table(rows: list[dict[str, Any]]) -> "pa.Table":
    """Per-robot rows (key, tick, robot, :data:`COMM_ROBOT_SERIES`) as a table of the schema's types."""
    import pyarrow as pa

    table = pa.Table.from_pylist(rows)
    return _cast_known(table, {"key": "string", "tick": "int64", "robot": "int64",
                               **{c: t for c, (t, _) in COMM_ROBOT_SERIES.items()}})


def runs_table(rows: list[dict[str, Any]]) -> "pa.Table":
    """Runs rows as a table of :data:`RUNS`'s types, so a column that is None in every row of a part still
    has its type (extra columns inferred)."""
    import pyarrow as pa

    return _cast_known(pa.Table.from_pylist(rows), RUNS)


def _cast_known(table: "pa.Table", types: Mapping[str, ArrowType]) -> "pa.Table":
    import pyarrow as pa

    fields = [pa.field(f.name, arrow_type(types[f.name]) if f.name in types else f.type) for f in table.schema]
    return table.cast(pa.schema(fields))
