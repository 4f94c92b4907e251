"""The simulation loop: ``Simulation(spec).run() -> RunResult``.

One logic tick (0.1 s, DESIGN.md section 4):

1. ``world.step``: pymunk moves the robots under last tick's commands (sub-stepped), reports collisions;
2. ``lidar.scan``: every robot's lidar writes what it sees into its own knowledge map; truth tracker;
3. inboxes: messages sent last tick, filtered by the radio (the transport issue fills this in);
4. ``act``: each algorithm sees its observation and returns an action (goal or velocity, messages);
5. navigation turns goals into (v, omega) commands on each robot's own map;
6. metrics: explored/coverage thresholds every tick, a time-series row every ``record_every`` ticks.

Everything random comes from :func:`swarm.spec.seed_streams`; nothing reads the clock except the
``*_time_s`` fields, so the same spec gives the same result bit for bit.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Callable, Mapping

import numpy as np

from maps import Map, generate
from maps.params import from_mapping

from radio import build_link_model, config_from_mapping

from . import registry
from .api import Action, NavStatus, Neighbour, Observation, Pose, RobotInfo
from .comm import CommSpec, Envelope, MapSharing, Medium
from .metrics import Metrics
from .navigation import Navigator
from .result import RunResult
from .sensing import ExplorationTracker, Lidar, LidarParams
from .spawn import spawn
from .spec import RunSpec, seed_streams
from .world import MotionParams, World


def build_map(spec: RunSpec, map_seed: int) -> Map:
    """The run's ground truth: generated from (kind, size, seed, params) or read from a file."""
    if spec.map.kind == "file":
        from maps.io import load_map

        return load_map(Path(spec.map.path))
    return generate(spec.map.kind, spec.map.size if isinstance(spec.map.size, int) else tuple(spec.map.size),
                    map_seed, spec.map.params)


@dataclass
class TickView:
    """What per-tick observers (GIF renderer, recorder) get after each tick's sensing."""

    tick: int
    poses: np.ndarray
    known: np.ndarray
    tracker: ExplorationTracker
    actions: list[Action] = field(default_factory=list)


class Simulation:
    """One run. Construct from a :class:`RunSpec` or a mapping; :meth:`run` once."""

    def __init__(self, spec: RunSpec | Mapping[str, Any], truth: Map | None = None,
                 observers: tuple[Callable[[TickView], None], ...] = (),
                 start_poses: np.ndarray | None = None) -> None:
        """``truth`` replaces the spec's map and ``start_poses`` (float64[R, 3]) its spawn: for hand-made
        test fixtures; a run's identity (``spec.key``) does not cover them."""
        t0 = time.perf_counter()
        self.spec = RunSpec.from_mapping(spec) if not isinstance(spec, RunSpec) else spec
        self.streams = seed_streams(self.spec)
        self.truth = truth if truth is not None else build_map(self.spec, self.streams.map_seed)
        n = self.spec.robots.count
        self.motion = from_mapping(MotionParams, self.spec.motion)
        self.lidar_params = from_mapping(LidarParams, self.spec.lidar)
        self.start_poses = (np.array(start_poses, dtype=np.float64) if start_poses is not None
                            else spawn(self.truth, self.spec.robots.spawn, n, self.streams.spawn))
        self.world = World(self.truth, self.start_poses, self.motion)
        self.lidar = Lidar(self.truth, self.lidar_params)
        self.tracker = ExplorationTracker(self.truth)
        self.known = np.zeros((n, *self.truth.shape), dtype=np.uint8)
        self._views = [self._read_only(i) for i in range(n)]
        self.navigators = [Navigator(self.spec.navigation, self.motion) for _ in range(n)]
        params = registry.build_params(self.spec.algorithm.name, self.spec.algorithm.params)
        self.agents = [registry.create(self.spec.algorithm.name) for _ in range(n)]
        for i, agent in enumerate(self.agents):
            agent.reset(self._robot_info(i), params, self.streams.robots[i])
        self.links = build_link_model(self.truth, config_from_mapping(self.spec.radio))
        self.comm = from_mapping(CommSpec, self.spec.comm)
        self.medium = Medium(n, self.comm, self.streams.radio)
        self.sharing = MapSharing(n, self.truth.shape, self.comm)
        self.inboxes: list[list[Any]] = [[] for _ in range(n)]
        self.neighbour_range = self.comm.neighbour_range_m or self.lidar_params.range_m
        self.observers = observers
        self.metrics = Metrics(self.spec.record_every)
        self.events: list[dict[str, Any]] = []
        self.setup_time_s = time.perf_counter() - t0

    def _read_only(self, i: int) -> np.ndarray:
        view = self.known[i].view()
        view.flags.writeable = False
        return view

    def _robot_info(self, i: int) -> RobotInfo:
        return RobotInfo(id=i, n_robots=self.spec.robots.count, map_shape=self.truth.shape,
                         radius=self.motion.radius, lidar_range=self.lidar_params.range_m,
                         max_speed=self.motion.max_speed, max_turn_rate=self.motion.max_turn_rate)

    # ------------------------------------------------------------------------------------------ run ----
    def run(self) -> RunResult:
        t0 = time.perf_counter()
        spec = self.spec
        n = spec.robots.count
        commands = np.zeros((n, 2), dtype=np.float64)
        collisions = 0
        was_colliding = np.zeros(n, dtype=bool)
        stalled_for = 0
        tick = 0
        stop_reason = ""
        while True:
            if tick > 0:
                self.world.step(commands)
            poses = self.world.poses
            collided = self.world.collided.copy()
            collisions += int((collided & ~was_colliding).sum())
            was_colliding = collided
            self.lidar.scan(poses, self.known, self.streams.sensor, tracker=self.tracker)
            self.tracker.update_coverage(poses[:, :2])
            links = self.links.evaluate(poses[:, :2])
            inboxes = self._receive()
            explored = self.tracker.explored
            self.metrics.check_thresholds(tick, explored)
            if explored >= spec.stop.explored:
                stop_reason = "explored"
            elif tick >= spec.stop.max_ticks:
                stop_reason = "max_ticks"
            elif stalled_for >= spec.stop.stall_ticks:
                stop_reason = "stalled"
            if stop_reason or self.metrics.due(tick):
                self._record(tick, explored, collisions, links)
            if stop_reason:
                break
            actions = self._act(tick, poses, collided, inboxes, links)
            self._send(tick, poses, actions, links)
            moving = False
            pose_rows = poses.tolist()
            for i, action in enumerate(actions):
                nav = self.navigators[i]
                if action.clear_goal:
                    nav.set_goal(None)
                if action.goal is not None:
                    nav.set_goal(action.goal)
                pose = Pose(*pose_rows[i])
                if action.velocity is not None:
                    v, w = action.velocity
                else:
                    v, w = nav.command(pose, self.known[i])
                commands[i] = (v, w)
                moving = moving or v != 0.0 or w != 0.0 or nav.state in ("moving", "planning")
            stalled_for = 0 if moving else stalled_for + 1
            for observer in self.observers:
                observer(TickView(tick, poses, self.known, self.tracker, actions))
            tick += 1
        wall = time.perf_counter() - t0
        return self._result(tick, stop_reason, collisions, wall)

    def _receive(self) -> list[tuple[Any, ...]]:
        """This tick's inboxes (sent last tick); map-sharing messages are merged into the receiver's map."""
        inboxes, self.inboxes = self.inboxes, [[] for _ in range(self.spec.robots.count)]
        for i, inbox in enumerate(inboxes):
            for msg in inbox:
                self.sharing.receive(i, msg, self.known[i])
        return [tuple(inbox) for inbox in inboxes]

    def _neighbours(self, poses: np.ndarray, links: Any) -> list[tuple[Neighbour, ...]]:
        """Robots within ``neighbour_range`` and in line of sight (no wall crossed), per robot."""
        n = len(poses)
        if n == 1:
            return [()]
        near = (links.distance <= self.neighbour_range) & (links.walls == 0)
        np.fill_diagonal(near, False)
        out: list[tuple[Neighbour, ...]] = []
        for i in range(n):
            row = []
            for j in np.flatnonzero(near[i]).tolist():
                dx, dy = poses[j, 0] - poses[i, 0], poses[j, 1] - poses[i, 1]
                bearing = float(np.arctan2(dy, dx) - poses[i, 2])
                bearing = (bearing + np.pi) % (2 * np.pi) - np.pi
                row.append(Neighbour(id=j, distance=float(links.distance[i, j]), bearing=bearing,
                                     x=float(poses[j, 0]), y=float(poses[j, 1])))
            out.append(tuple(row))
        return out

    def _act(self, tick: int, poses: np.ndarray, collided: np.ndarray, inboxes: list[tuple[Any, ...]],
             links: Any) -> list[Action]:
        actions = []
        distance = self.world.distance.tolist()
        energy = (self.world.distance + self.world.rotation).tolist()
        pose_rows = poses.tolist()
        neighbours = self._neighbours(poses, links)
        for i, agent in enumerate(self.agents):
            obs = Observation(tick=tick, robot_id=i, pose=Pose(*pose_rows[i]), known=self._views[i],
                              inbox=inboxes[i], neighbours=neighbours[i], collided=bool(collided[i]),
                              nav=self.navigators[i].status(), distance_travelled=distance[i],
                              energy_used=energy[i])
            actions.append(_check_action(agent.act(obs), i))
        return actions

    def _send(self, tick: int, poses: np.ndarray, actions: list[Action], links: Any) -> None:
        """Collect this tick's broadcasts (map sharing + algorithms) and deliver them for next tick."""
        service = self.sharing.outgoing(tick, self.known, poses)
        outboxes: list[list[Envelope]] = []
        for i, action in enumerate(actions):
            outboxes.append([self.medium.envelope(i, m) for m in (*service[i], *action.messages)])
        if any(outboxes):
            self.inboxes = self.medium.deliver(tick, outboxes, links.link)

    def _record(self, tick: int, explored: float, collisions: int, links: Any) -> None:
        stats = self.medium.stats
        groups = links.groups() if self.spec.robots.count > 1 else [frozenset({0})]
        self.metrics.record(tick, explored=explored, coverage=self.tracker.coverage,
                            distance_m=float(self.world.distance.sum()), collisions=collisions,
                            msgs_sent=stats.sent, bytes_sent=stats.bytes_sent, msgs_delivered=stats.delivered,
                            bytes_delivered=stats.bytes_delivered,
                            msgs_dropped=stats.dropped_link + stats.dropped_loss + stats.dropped_bandwidth,
                            comm_groups=len(groups),
                            biggest_group=max(len(g) for g in groups) / self.spec.robots.count,
                            all_connected=len(groups) == 1)

    def _result(self, tick: int, stop_reason: str, collisions: int, wall: float) -> RunResult:
        summary = {
            "ticks": tick,
            "stop_reason": stop_reason,
            "explored": float(self.tracker.explored),
            "coverage": float(self.tracker.coverage),
            "ticks_to": dict(self.metrics.ticks_to),
            "distance_m": [float(d) for d in self.world.distance],
            "collisions": collisions,
            "plans": [nav.plans for nav in self.navigators],
            "messages": self.medium.stats.as_dict(),
            "final_poses": [[float(v) for v in p] for p in self.world.poses],
            "map_seed": int(self.streams.map_seed) if self.spec.map.kind != "file" else None,
            "wall_time_s": wall,
            "setup_time_s": self.setup_time_s,
        }
        return RunResult(spec=self.spec.canonical(), key=self.spec.key, summary=summary,
                         timeseries=self.metrics.series, events=self.events)


def _check_action(action: Any, robot: int) -> Action:
    if not isinstance(action, Action):
        raise TypeError(f"robot {robot}: act() returned {type(action).__name__}, expected swarm.api.Action")
    return action


def run(spec: RunSpec | Mapping[str, Any]) -> RunResult:
    """Convenience: ``Simulation(spec).run()``."""
    return Simulation(spec).run()


__all__ = ["NavStatus", "Simulation", "TickView", "build_map", "run"]
