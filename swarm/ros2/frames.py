"""Where :class:`~swarm.ros2.topics.TickFrame` s come from: a recording replayed once from tick 0
(:func:`recording_frames`), or a live simulation observed tick by tick (:class:`FrameObserver`).

Both give the same frames for the same run (poses, knowledge maps, links and exact RSSI, groups, failed
deliveries, actions and the explored shares are all exact in a recording), so an export of a recording and a
live export agree message for message. The radio picture of a recorded tick is recomputed from the exact
poses with the run's own radio (:attr:`swarm.record.Recording.link_model`), bit for bit what the run had;
the recording's RSSI stream is quantised. Actions are read leniently, as the viewer reads them: a goal that
is not two finite numbers is no goal, a doorway entry that is not ``(x, y, axis, width, explored)`` is
skipped. One difference remains: a recording replaces a debug payload over 256 KiB by a note, so a robot
whose debug grows that large shows its doorways live but not in an export.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Iterator, Mapping, Sequence
from typing import TYPE_CHECKING, Any

import numpy as np

from swarm.world.motion import TICK_S

from .topics import Doorway, Loss, RobotAction, RunInfo, TickFrame

if TYPE_CHECKING:
    from swarm.record.reader import Recording
    from swarm.sim.loop import Simulation, TickView


def _number(v: Any) -> bool:
    return isinstance(v, (int, float, np.integer, np.floating)) and not isinstance(v, (bool, np.bool_)) \
        and math.isfinite(v)


def _sequence(v: Any) -> list[Any] | None:
    if isinstance(v, np.ndarray):
        return v.tolist()
    return list(v) if isinstance(v, (list, tuple)) else None


def _doorways(debug: Any) -> tuple[Doorway, ...] | None:
    """The doorways a debug payload lists (Minotaur's ``debug["doorways"]``), None if it lists none."""
    if not isinstance(debug, Mapping):
        return None
    entries = _sequence(debug.get("doorways"))
    if entries is None:
        return None
    out: list[Doorway] = []
    for entry in entries:
        e = _sequence(entry)
        if (e is not None and len(e) >= 5 and all(_number(v) for v in e[:4]) and e[2] in (0, 1) and e[3] >= 0
                and isinstance(e[4], (bool, np.bool_))):
            out.append((float(e[0]), float(e[1]), int(e[2]), float(e[3]), bool(e[4])))
    return tuple(out)


def robot_action(goal: Any, clear_goal: Any, debug: Any) -> RobotAction:
    """The part of an action the topics show, from a live :class:`swarm.base.types.Action`'s fields or a
    recorded action's (the same values after msgpack)."""
    g = _sequence(goal)
    point = (float(g[0]), float(g[1])) if g is not None and 2 <= len(g) <= 6 and _number(g[0]) and _number(g[1]) \
        else None
    return RobotAction(point, bool(clear_goal), _doorways(debug))


def _groups(links: Any, n: int) -> list[frozenset[int]]:
    return links.groups() if n > 1 else [frozenset({0})]


# -------------------------------------------------------------------------------------- recordings ----
def recording_info(rec: Recording) -> RunInfo:
    """A recorded run's fixed facts: its map, robots, lidar (from the spec) and radios (from HEAD); a file
    whose HEAD cannot be a run's raises :class:`swarm.base.errors.InvalidInput` naming the file."""
    from swarm.record.container import bad

    spec = rec.run_spec
    sensitivity = rec.header["sensitivity_dbm"]
    if not all(_number(v) for v in sensitivity):
        raise bad(rec.path, "HEAD sensitivity_dbm is not a list of numbers")
    if rec.truth.shape != rec.shape:
        raise bad(rec.path, f"HEAD map is {rec.truth.shape}, its shape says {rec.shape}")
    return RunInfo(truth=rec.truth, n_robots=rec.n_robots, lidar=spec.lidar, robot_radius_m=rec.header["robot_radius_m"],
                   sensitivity_dbm=np.array(sensitivity, dtype=np.float64), tick_s=TICK_S)


def recording_frames(rec: Recording) -> Iterator[TickFrame]:
    """Every tick of ``rec`` as a frame, replaying the knowledge maps once from tick 0 (each frame's
    ``known`` is one array, updated in place: use a frame before taking the next)."""
    n = rec.n_robots
    known = np.zeros((n, *rec.shape), dtype=np.uint8)
    flat = known.reshape(-1)
    model = rec.link_model
    for t in range(rec.ticks):
        idx, val = rec.known_changes(t)
        flat[idx] = val   # each cell at most once per tick
        poses = rec.poses[t]
        state = model.evaluate(poses[:, :2])
        losses = [Loss(m.transmitter, robot, cause) for m in rec.messages_at(t - 1) for robot, cause in m.lost] \
            if t > 0 else []
        actions = {i: None if a is None else robot_action(a["goal"], a["clear_goal"], a["debug"])
                   for i, a in rec.actions_changed(t).items()}
        yield TickFrame(t, poses, known, state.link, state.rssi, _groups(state, n), losses, actions,
                        float(rec.explored[t]), float(rec.coverage[t]), final=t == rec.ticks - 1)


# ------------------------------------------------------------------------------------- live runs ----
def simulation_info(sim: Simulation) -> RunInfo:
    """A live run's fixed facts, as a recording of it would hold them."""
    n = sim.spec.robots.count
    return RunInfo(truth=sim.truth, n_robots=n, lidar=sim.lidar_params, robot_radius_m=float(sim.motion.radius),
                   sensitivity_dbm=np.asarray(sim.links.config.sensitivity_array(n), dtype=np.float64), tick_s=TICK_S)


class FrameObserver:
    """Per-tick observer of a :class:`~swarm.sim.loop.Simulation` handing ``sink`` a frame of every tick;
    :meth:`finish` after the run gives the last tick's (the loop stops after sensing it, before observers).

    A tick's failed deliveries are known once the medium has judged its messages, at that tick or (with
    ``comm.link_at = "receive"``) at the next: each frame carries those of the previous tick's messages. It
    asks the medium to list them (:attr:`swarm.comm.medium.Medium.note_losses`, which changes no result)."""

    def __init__(self, sim: Simulation, sink: Callable[[TickFrame], None]) -> None:
        self.n = sim.spec.robots.count
        self.sink = sink
        self._pending: Sequence[Sequence[Any]] = ()   # the last observed tick's outboxes
        self._next_tick = 0
        self._finished = False
        sim.medium.note_losses = True

    @classmethod
    def attach(cls, sim: Simulation, sink: Callable[[TickFrame], None]) -> FrameObserver:
        """An observer for ``sim`` feeding ``sink``, appended to its observers."""
        observer = cls(sim, sink)
        sim.observers = (*sim.observers, observer)
        return observer

    def _losses(self) -> list[Loss]:
        from swarm.comm.medium import LOSS_CAUSES

        return [Loss(env.transmitter, robot, LOSS_CAUSES[cause])
                for outbox in self._pending for env in outbox for robot, cause in (env.lost or ())]

    def __call__(self, view: TickView) -> None:
        links = view.links
        actions = {i: None if a is None else robot_action(a.goal, a.clear_goal, a.debug)
                   for i, a in enumerate(view.actions)}
        self.sink(TickFrame(view.tick, view.poses, view.known, links.link, links.rssi, _groups(links, self.n),
                            self._losses(), actions, float(view.tracker.explored), float(view.tracker.coverage)))
        self._pending = view.sent
        self._next_tick = view.tick + 1

    def finish(self, sim: Simulation) -> None:
        """The last tick's frame. Call once, after ``sim.run()``."""
        if self._finished:
            raise RuntimeError("FrameObserver.finish called twice")
        self._finished = True
        poses = sim.world.poses
        links = sim.links.evaluate(poses[:, :2])   # a pure function of the positions: the run's own picture
        self.sink(TickFrame(self._next_tick, poses, sim.known, links.link, links.rssi, _groups(links, self.n),
                            self._losses(), {}, float(sim.tracker.explored), float(sim.tracker.coverage), final=True))


__all__ = ["FrameObserver", "recording_frames", "recording_info", "robot_action", "simulation_info"]
