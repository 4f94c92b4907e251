"""The simulation loop: ``Simulation(spec).run() -> RunResult``.

One logic tick (0.1 s, docs/design.md section 4):

1. ``world.step``: pymunk moves the robots under last tick's commands (sub-stepped), reports collisions;
2. ``lidar.scan``: every robot's lidar writes what it sees into its own knowledge map; truth tracker;
3. the radio picture for this tick's positions (distances, walls, RSSI, links, groups), evaluated when
   first used (sending, metrics, an observer): a pure function of the positions. Neighbours (robots in
   sensing range and line of sight) walk only the pairs within range (``LinkModel.in_sight``);
4. inboxes: messages sent last tick arrive; map updates are merged into the receiver's map;
5. the transport hands each live robot its observation and gets its action (goal or velocity, messages);
6. this tick's broadcasts (and, with ``comm.relay = "flood"``, the copies robots forward) are judged by
   this tick's links and queued for next tick;
7. navigation turns goals into (v, omega) commands on each robot's own map (every moving robot's step in
   one compiled call, :class:`swarm.navigation.navigator.NavigationFleet`);
8. metrics: explored thresholds every tick, a time-series row every ``record_every`` ticks, and with it a
   row of communication metrics (``RunResult.comm``, docs/comm-metrics.md).

Everything random comes from :func:`swarm.sim.spec.seed_streams`; nothing reads the clock except the
``*_time_s`` fields, so the same spec gives the same result bit for bit, whatever the transport.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Callable, Mapping, Sequence

import numpy as np

from maps import CELL_M, Map, generate
from radio import build_link_model
from radio.models import groups_of
from swarm.base.errors import InvalidInput
from swarm.base.types import Action, Pose, RobotInfo
from swarm.comm.maes_merge import MaesMerge
from swarm.comm.maes_merge import resolve as resolve_maes_merge
from swarm.comm.medium import Envelope, Inboxes, Medium
from swarm.comm.messages import MapUpdate
from swarm.comm.sharing import MapSharing
from swarm.grid._validate import vouch_known
from swarm.knowledge.journal import KnowledgeJournal
from swarm.knowledge.maps import sync_boxes_flat, sync_changes
from swarm.knowledge.planes import KnowledgePlanes
from swarm.knowledge.planes import wanted as planes_wanted
from swarm.knowledge.tiles import TiledKnowledge, TiledLayout
from swarm.navigation.avoidance import Avoidance
from swarm.navigation.maes_drive import MaesDriveFleet
from swarm.navigation.navigator import NavigationFleet
from swarm.plugins import explorers as registry
from swarm.results.mapquality import CorrectlyExplored
from swarm.results.metrics import CommMetrics, FreeCounts, InfoAges, Metrics
from swarm.results.result import RunResult
from swarm.transport import AgentHost, PhaseTimes, TickBatch, make_host
from swarm.transport.auth import RunSecret
from swarm.transport.base import ACT_COUNTS
from swarm.transport.wire import ResetPacket
from swarm.util.memory import lazy_zeros, release_freed_memory
from swarm.world.localization import Localizer
from swarm.world.motion import TICK_S
from swarm.world.physics import World
from swarm.world.sensing import ExplorationTracker, Lidar
from swarm.world.spawn import spawn

from .spec import ROBOT_STREAM, RunSpec, planner_rng, seed_streams

MAX_DROP_EVENTS = 100
"""Malformed messages get an event each up to this many per run (a flooding agent must not grow the result)."""
_pose = tuple.__new__  # _pose(Pose, row) is Pose(*row) without NamedTuple's argument handling (16 a tick)


def build_map(spec: RunSpec, map_seed: int) -> Map:
    """The run's ground truth: generated from (kind, size, seed, params) or read from a file."""
    if spec.map.kind == "file":
        from maps.io import load_map

        return load_map(Path(spec.map.path), **spec.map.params)  # params: only a .json plan's scale
    return generate(spec.map.kind, spec.map.size if isinstance(spec.map.size, int) else tuple(spec.map.size),
                    map_seed, spec.map.params)


@dataclass(frozen=True)
class TransportOptions:
    """How to reach agents in other processes (not part of the spec: they never change a result)."""

    listen: tuple[str, ...] = ()
    remote: tuple[int, ...] = ()
    timeout_s: float = 10.0
    run_id: str | None = None
    times: PhaseTimes | None = field(default=None, compare=False)  # benchmarks: where the ticks go
    secret: RunSecret | None = field(default=None, repr=False)  # remote agents' tokens derive from it (a fresh one if None)
    share_maps: bool = True  # zenoh: local agents read the runtime's maps in place (False: ship them the changes)
    on_listening: Callable[[], None] | None = field(default=None, compare=False, repr=False)
    """Called once the ``listen`` endpoints are open, before the run waits for remote agents: ``swarm run``
    prints the agents' commands then, not before a bind that may fail."""
    wrap: Callable[[AgentHost], AgentHost] | None = field(default=None, compare=False, repr=False)
    """A host around the transport's (closed with it), e.g. :class:`swarm.ros2.external.RosHost`, which
    publishes each tick on ROS 2 and drives some robots from there."""


@dataclass
class TickView:
    """What per-tick observers (GIF renderer, recorder) get after each tick's decisions. ``links`` reads
    like the tick's :class:`radio.LinkState` (its attributes and ``groups()``), evaluated on first use."""

    tick: int
    poses: np.ndarray
    known: np.ndarray
    tracker: ExplorationTracker
    actions: list[Action | None] = field(default_factory=list)
    links: Any = None
    sent: list[list[Envelope]] = field(default_factory=list)


@dataclass(eq=False)
class LoopState:
    """Where a run stands inside its loop: the counters carried from tick to tick and, between
    :meth:`Simulation.sense` and :meth:`Simulation.apply`, what the current tick sensed."""

    commands: np.ndarray                    # float64[R, 2]: last tick's (v, omega), applied by the next move
    was_colliding: np.ndarray               # bool[R]: in contact at the last tick
    tick: int = 0
    collisions: int = 0                     # contacts begun so far (a robot touching anything)
    collisions_with: Any = None             # int64[2]: contacts begun with a wall [0] / a robot [1]
    was_colliding_with: Any = None          # bool[2, R]: in contact with a wall / robot at the last tick
    stalled_for: int = 0
    stop_reason: str = ""
    poses: Any = None                       # float64[R, 3] of this tick (the world's array: moved in place)
    collided: Any = None                    # bool[R]: in contact now
    began: Any = None                       # bool[R]: contacts that began this tick
    believed: Any = None                    # float64[R, 3]: where the robots believe they are (``poses`` when
                                            # there is no localisation error)
    active: Any = None                      # bool[R]: robots not failed
    links: Any = None                       # the tick's radio picture (evaluated on first use)
    inboxes: list = field(default_factory=list)
    merged: list = field(default_factory=list)
    pose_tuples: list = field(default_factory=list)


TILED_FROM_CELLS = 1 << 35
"""Dense maps of this many robot-cells or more (32 GB, more than this machine's memory were they to fill) are
kept by tiles when the run allows (``Simulation(tiled=None)``): 10,000 robots on a 2,000-tile building (160
billion), not 1,000 robots on 600 tiles (2.2 billion)."""


class Simulation:
    """One run. Construct from a :class:`RunSpec` or a mapping; :meth:`run` once."""

    def __init__(self, spec: RunSpec | Mapping[str, Any], truth: Map | None = None,
                 observers: Sequence[Callable[[TickView], None]] = (), start_poses: np.ndarray | None = None,
                 transport: TransportOptions | None = None, tiled: bool | None = None) -> None:
        """``truth`` replaces the spec's map and ``start_poses`` (float64[R, 3]) its spawn: for hand-made
        test fixtures; a run's identity (``spec.key``) does not cover them. ``tiled``: keep the knowledge maps
        by tiles (:mod:`swarm.knowledge.tiles`: memory in proportion to what each robot knows; the same
        results), for swarms (64 robots or more) with the ternary lidar, swarm map sharing, the in-process
        transport and no observer; None (default): tiles when the run allows them and its dense maps would
        span :data:`TILED_FROM_CELLS` cells or more."""
        t0 = time.perf_counter()
        self.spec = RunSpec.from_mapping(spec) if not isinstance(spec, RunSpec) else spec
        self.streams = seed_streams(self.spec)
        self.truth = truth if truth is not None else build_map(self.spec, self.streams.map_seed)
        n = self.spec.robots.count
        self.motion = self.spec.motion
        self.lidar_params = self.spec.lidar
        self.start_poses = (np.array(start_poses, dtype=np.float64) if start_poses is not None
                            else spawn(self.truth, self.spec.robots.spawn, n, self.streams.spawn,
                                  self.spec.robots.heading))
        self.world = World(self.truth, self.start_poses, self.motion)
        self.lidar = Lidar(self.truth, self.lidar_params)
        self.tracker = ExplorationTracker(self.truth)
        self.tracker.track_robots(n)   # who saw what by its own lidar: overlap and coverage spread
        fleet = MaesDriveFleet if self.motion.model == "maes" else NavigationFleet
        self.fleet = fleet(self.spec.navigation, self.motion, [planner_rng(self.spec.seed, i) for i in range(n)])
        nav = self.spec.navigation
        self.avoidance = (Avoidance(nav.avoidance, self.motion, n, nav.avoidance_range_m)
                          if nav.avoidance != "none" else None)
        self.navigators = self.fleet.navigators
        self.links = build_link_model(self.truth, self.spec.radio, field_seed=self.streams.map_seed)
        self.comm = self.spec.comm
        self.medium = Medium(n, self.comm, self.streams.radio, map_shape=self.truth.shape,
                             packet_errors=self.links.packet_errors, error_rng=self.streams.channel)
        self._reach = int(np.ceil(self.lidar_params.range_m / CELL_M)) + 2  # cells the lidar may change, around a robot
        # who last merged whose map, when (age of information); snapshots kept as long as updates travel
        self.ages = InfoAges(n, self.comm.longest_delivery_ticks + 1)
        # With a localisation error robots map from where they believe they are (swarm.world.localization),
        # so a cell may turn from FREE to SOLID: maps are then not monotone, as under the log-odds lidar.
        loc = self.spec.localization
        self.localizer = (Localizer(loc, self.spec.seed, self.start_poses, TICK_S, (self.truth.width_m,
                                                                                    self.truth.height_m))
                          if loc.on else None)
        self.off_map_scans = 0   # robot-ticks whose lidar wrote nothing for believing itself off the map
        self._pose_errors: dict[str, list[Any]] = {"tick": [], "position_m": [], "heading_rad": []}
        self._correct = CorrectlyExplored(self.truth.solid) if self.localizer else None
        self.occlude = self.lidar_params.robots_occlude   # robots hide what is behind them from each other's lidar
        monotone = self.lidar_params.mode == "ternary" and self.localizer is None and not self.occlude
        self.free = FreeCounts(n, exact=monotone)  # each map's FREE cells
        merge = resolve_maes_merge(self.comm.map_sharing, self.comm.share_every, registry.load(self.spec.algorithm.name))
        self.planes = (KnowledgePlanes(n, self.truth.shape[0] * self.truth.shape[1])  # who knows which cell
                       if planes_wanted(n, monotone, merge is None and self.comm.map_sharing in ("delta", "full"))
                       else None)
        refused = self._tiled_refused(monotone, merge, observers)
        if tiled is None:
            tiled = refused is None and n * self.truth.shape[0] * self.truth.shape[1] >= TILED_FROM_CELLS
        elif tiled and refused is not None:
            raise InvalidInput("tiled", True, f"a run with {refused}")
        self.maps: TiledKnowledge | None = TiledKnowledge(TiledLayout(self.truth.shape), n) if tiled else None
        if self.maps is not None:
            self.known = self.maps.stack  # uint8[n, tiles * 4096]: memory where the tiles hold something
            self._views: Any = _TiledViews(self.maps)
        else:
            self.known = lazy_zeros((n, *self.truth.shape), np.uint8)  # memory where the maps hold something
            self._views = [self._read_only(i) for i in range(n)]
        self.sharing = MapSharing(n, self.truth.shape, self.comm, lidar_reach=self._reach,  # told of every scan
                                  monotone=monotone, ages=self.ages, free=self.free, planes=self.planes,
                                  layout=None if self.maps is None else self.maps.layout,
                                  written=None if self.maps is None else self.maps.note_cells,
                                  dense=None if self.maps is None else self.maps.dense)
        self.maes_merge = MaesMerge(n, *merge, ages=self.ages) if merge is not None else None
        self._in_flight: list[list[Envelope]] | None = None  # link_at = "receive": last tick's outboxes
        self.inboxes = Inboxes.empty(n)
        self._deliveries: list[tuple[Any, list[int]]] = []  # last tick's messages and who got each, in inbox order
        self.neighbour_range = self.comm.neighbour_range_m or self.lidar_params.range_m
        self.transport = transport or TransportOptions()
        self.observers = tuple(observers)
        self.metrics = Metrics(self.spec.record_every)
        self.comm_metrics = CommMetrics(n, self.free)
        self.events: list[dict[str, Any]] = []
        self.failed = np.zeros(n, dtype=bool)
        self._drop_events = 0
        self._mirror: np.ndarray | None = None
        self.journals: list[KnowledgeJournal] = []  # where maps were written, one per reader that asked
        self.setup_time_s = time.perf_counter() - t0

    def _tiled_refused(self, monotone: bool, merge: Any, observers: Sequence[Any]) -> str | None:
        """What a run would need for tiled maps to serve it (see ``tiled`` in :meth:`__init__`), or None."""
        reasons = [(not monotone, "maps that only rise (the ternary lidar; no localisation error or occluding robots)"),
                   (merge is not None, "swarm map sharing, not MAES's merges"),
                   (bool(observers), "no observers (recorder, viewer, ROS 2 bridge)"),
                   (self.spec.transport != "inprocess", "the in-process transport"),
                   (self.motion.model == "maes", "swarm's motion model"),
                   (self.planes is None, "64 robots or more and swarm map sharing (delta or full)")]
        return next((allowed for bad, allowed in reasons if bad), None)

    def _read_only(self, i: int) -> np.ndarray:
        """Robot i's map as its algorithm sees it: read-only, and vouched for (values 0..2 by construction),
        so the grid helpers the algorithm calls on it every few ticks do not rescan it. Called on the new
        all-zero maps only (set-up)."""
        view = self.known[i].view()
        view.flags.writeable = False
        return vouch_known(view, trusted=True)

    def knowledge_journal(self) -> KnowledgeJournal:
        """A new journal of where each robot's map is written from now on (:mod:`swarm.knowledge.journal`),
        every robot flagged whole to start. For a reader that diffs the maps every tick (the recorder): it
        then compares only the places written. Each reader takes its own."""
        journal = KnowledgeJournal(self.spec.robots.count, self.truth.shape, self._reach)
        self.journals.append(journal)
        return journal

    def robot_info(self, i: int) -> RobotInfo:
        return RobotInfo(id=i, n_robots=self.spec.robots.count, map_shape=self.truth.shape,
                         radius=self.motion.radius, lidar_range=self.lidar_params.range_m,
                         max_speed=self.motion.max_speed, max_turn_rate=self.motion.max_turn_rate)

    def resets(self) -> list[ResetPacket]:
        """What each agent starts from; its generator is ``SeedSequence(seed, spawn_key=(3, i))``, the same
        stream :func:`swarm.sim.spec.seed_streams` gives, whichever side of a transport builds it."""
        return [ResetPacket(robot=self.robot_info(i), algorithm=self.spec.algorithm.name,
                            params=dict(self.spec.algorithm.params), seed_entropy=self.spec.seed,
                            seed_spawn_key=(ROBOT_STREAM, i)) for i in range(self.spec.robots.count)]

    # ------------------------------------------------------------------------------------------ run ----
    def run(self) -> RunResult:
        opts = self.transport
        host = make_host(self.spec.transport, self.spec.key, listen=opts.listen, remote=opts.remote,
                         timeout_s=opts.timeout_s, run_id=opts.run_id, times=opts.times, secret=opts.secret,
                         share_maps=opts.share_maps)
        if opts.times is not None:
            self._time_phases(opts.times)
        try:
            if opts.wrap is not None:
                host = opts.wrap(host)
            if opts.on_listening is not None:
                opts.on_listening()
            host.start(self.resets())
            if host.mirrors and self.maps is not None:
                raise InvalidInput("tiled", True, "a host without map mirrors (the in-process host)")
            if host.mirrors:
                self._mirror = np.zeros_like(self.known)
            return self._loop(host)
        finally:
            host.close()

    def _time_phases(self, times: PhaseTimes) -> None:
        """Time the steps that build observations for the transport into ``times``: instance attributes
        that shadow the methods, so an unmeasured run calls the methods directly."""
        for name, phase in (("_batch", "host: batch"), ("_changed_cells", "host: changed cells"),
                            ("_sight", "host: neighbours")):
            setattr(self, name, times.wrap(phase, getattr(self, name)))

    def _loop(self, host: AgentHost) -> RunResult:
        t0 = time.perf_counter()
        state = self.start_state()
        while not self.sense(state):
            actions = host.act(self.observe(state))
            self._note_failures(state.tick, host)
            self.apply(state, actions)
        return self._result(state, time.perf_counter() - t0, host)

    # The loop's body in three steps, so that a stepping driver (:mod:`swarm.env`) runs exactly the ticks
    # :meth:`run` runs: ``sense`` (steps 1-4 and 8), ``observe`` (the batch for step 5), ``apply`` (6-7).
    def start_state(self) -> LoopState:
        """The state before tick 0 (no command yet)."""
        n = self.spec.robots.count
        return LoopState(commands=np.zeros((n, 2), dtype=np.float64), was_colliding=np.zeros(n, dtype=bool),
                         collisions_with=np.zeros(2, dtype=np.int64), was_colliding_with=np.zeros((2, n), dtype=bool))

    def sense(self, state: LoopState) -> bool:
        """Steps 1-4 and 8 of tick ``state.tick``: move (after tick 0), scan, receive, metrics; True when the
        run stops here (``state.stop_reason`` says why; the tick is recorded, nobody acts)."""
        self.move_and_scan(state)
        return self.communicate(state)

    def move_and_scan(self, state: LoopState) -> None:
        """Steps 1-2: the world moves under last tick's commands (not before tick 0), the lidars write the
        knowledge maps; contacts begun this tick are counted (``state.began`` per robot)."""
        if state.tick > 0:
            self.world.step(state.commands)
        poses = self.world.poses
        collided = self.world.collided.copy()
        began = collided > state.was_colliding  # contacts that began this tick
        state.collisions += int(np.count_nonzero(began))
        state.began = began
        state.was_colliding = collided
        with_kind = self.world.collided_with.copy()
        state.collisions_with += np.count_nonzero(with_kind > state.was_colliding_with, axis=1)
        state.was_colliding_with = with_kind
        active = ~self.failed
        believed = poses
        if self.localizer is not None:
            if state.tick > 0:
                self.localizer.update(poses, active)
            believed = self.localizer.estimates.copy()
        if self.localizer is None and not self.occlude:
            self.lidar.scan(poses, self.known, self.streams.sensor, active=active, tracker=self.tracker,
                            measure=False, freed=self.free.freed, planes=self.planes)
            if self.maps is not None:  # the tiles each cast robot's lidar may have written
                cast = np.flatnonzero(self.lidar.cast)
                self.maps.note_boxes(cast, self._lidar_boxes(poses[cast]))
        else:   # the lidar measures from the true pose and writes from the believed one
            if self.lidar_params.mode == "ternary":
                limits = self.lidar.occlusion(poses, self.motion.radius, active) if self.occlude else None
                ranges = self.lidar.scan(poses, self.known, self.streams.sensor, active=active, tracker=self.tracker,
                                         write=False, limits=limits)
                self.off_map_scans += self.lidar.write_from(believed, ranges, self.known, limits)
            else:   # log-odds: evidence from where it believes it is, so later scans can undo a misplaced wall
                self.lidar.scan(poses, self.known, self.streams.sensor, active=active, tracker=self.tracker,
                                measure=False, write_poses=believed)
        self.sharing.scanned(believed)
        for journal in self.journals:
            journal.scanned(believed, self.lidar.cast)
        self.tracker.update_coverage(poses[:, :2], active=active)
        state.poses, state.collided, state.active, state.believed = poses, collided, active, believed

    def communicate(self, state: LoopState) -> bool:
        """Steps 3-4 and 8: the tick's radio picture, inboxes and merges, thresholds, the stop test and the
        time-series row; True when the run stops at this tick."""
        spec = self.spec
        tick = state.tick
        links = _TickLinks(self.links, state.poses[:, :2])
        state.links = links
        state.inboxes, state.merged = self._receive(tick, links)
        explored = self.tracker.explored
        self.metrics.check_thresholds(tick, explored)
        stop_reason = ""
        if explored >= spec.stop.explored:
            stop_reason = "explored"
        elif tick >= spec.stop.max_ticks:
            stop_reason = "max_ticks"
        elif state.stalled_for >= spec.stop.stall_ticks:
            stop_reason = "stalled"
        elif np.count_nonzero(state.active) == 0:  # (ndarray.any() costs ~1 us on 16 flags, this 0.3)
            stop_reason = "all_failed"
        if stop_reason or self.metrics.due(tick):
            self._record(tick, explored, state.collisions, links)
        state.stop_reason = stop_reason
        return bool(stop_reason)

    def observe(self, state: LoopState) -> TickBatch:
        """Step 5's input: the tick's observations for a host."""
        state.pose_tuples = [_pose(Pose, row) for row in state.believed.tolist()]  # shared by observations and navigation
        return self._batch(state.tick, state.believed, state.pose_tuples, state.collided, state.inboxes, state.merged,
                           state.poses)

    def apply(self, state: LoopState, actions: list[Action | None]) -> None:
        """Steps 6-7 of tick ``state.tick`` for the robots' ``actions`` (None: no action), then on to the
        next tick: send, navigate, stall count, observers."""
        poses = state.poses
        sent = self._send(state.tick, state.believed, actions, state.links, poses)
        commands = self._commands(actions, state.believed, state.pose_tuples, state.began, poses)
        moving = np.count_nonzero(commands) > 0 or any(nav.state in ("moving", "planning") for nav, action
                                                       in zip(self.navigators, actions) if action is not None)
        state.stalled_for = 0 if moving else state.stalled_for + 1
        for observer in self.observers:
            observer(TickView(state.tick, poses, self.known, self.tracker, actions, state.links, sent))
        state.commands = commands
        state.tick += 1

    def _commands(self, actions: list[Action | None], poses: np.ndarray, pose_tuples: list[Pose],
                  began: np.ndarray | None = None, true_poses: np.ndarray | None = None) -> np.ndarray:
        """The tick's (v, omega) per robot: an action's velocity, else its navigator's command toward the
        goal the action set (all navigators at once, :class:`NavigationFleet`, or MAES's controllers,
        which a contact begun this tick, ``began``, interrupts); (0, 0) without an action."""
        commands = np.zeros((len(actions), 2), dtype=np.float64)
        steered: list[int] = []
        for i, action in enumerate(actions):
            if action is None:
                continue
            nav = self.navigators[i]
            if action.clear_goal:
                nav.set_goal(None)
            if action.goal is not None:
                nav.set_goal(action.goal, action.drive)
            if action.velocity is not None:
                v, w = action.velocity
                commands[i] = v, w
            else:
                steered.append(i)
        if self.maps is None:
            self.fleet.command(steered, poses, pose_tuples, self.known, commands, began)
        else:
            self.fleet.command(steered, poses, pose_tuples, self.known, commands, began, maps=self.maps)
        if self.avoidance is not None:   # among the robots as they are, not as they believe they are
            self.avoidance.adjust(commands, steered, poses if true_poses is None else true_poses)
        return commands

    # ---------------------------------------------------------------------------------- messaging ----
    def _receive(self, tick: int, links: Any) -> tuple[Inboxes, list[list[np.ndarray | None]]]:
        """This tick's inboxes (sent last tick); map updates are merged into the receivers' maps, each into
        all its receivers at once (:meth:`MapSharing.receive_tick`), or MAES's merges done. The merged cells
        per robot are listed only for a host with mirrors, which ships them (None: the whole map may have
        changed). With ``comm.link_at = "receive"`` last tick's broadcasts are judged now, by this tick's
        links."""
        if self._in_flight is not None:
            self._deliver(tick - 1, self._in_flight, links)
            self._in_flight = None
        inboxes, self.inboxes = self.inboxes, Inboxes.empty(self.spec.robots.count)
        deliveries, self._deliveries = self._deliveries, []
        if not deliveries:  # most ticks
            return inboxes, [[] for _ in range(len(inboxes))]
        merged = self.sharing.receive_tick(deliveries, self.known, ~self.failed, cells=self._mirror is not None,
                                           tick=tick)
        if self.maes_merge is not None:
            for robot in sorted(self.maes_merge.receive(deliveries, self.known, ~self.failed, tick)):
                merged[robot].append(None)
                self.free.dirty[robot] = True
                for journal in self.journals:
                    journal.rewritten([robot])
        if self.journals:
            for msg, receivers in deliveries:
                if isinstance(msg, MapUpdate):  # (checked by the merge above)
                    cells = None if msg.full else msg.cells()[0]
                    for journal in self.journals:
                        journal.merged(receivers, cells)
        if self.maps is not None:  # a swarm's merges free a gigabyte of decoded cells: give the pages back
            release_freed_memory()
        return inboxes, merged

    def _send(self, tick: int, poses: np.ndarray, actions: list[Action | None], links: Any,
              true_poses: np.ndarray | None = None) -> list[list[Envelope]]:
        """Collect this tick's broadcasts (map sharing + algorithms) and deliver them for next tick. ``poses``:
        where the robots believe they are (their map updates say so); ``true_poses`` (default: the same) decide
        who senses whom."""
        truth = poses if true_poses is None else true_poses
        service = self.sharing.outgoing(tick, self.known, poses)
        if self.maes_merge is not None:
            service = self.maes_merge.outgoing(tick, lambda: self._sight(truth)[1])
        outboxes: list[list[Envelope]] = []
        for i, action in enumerate(actions):
            if self.failed[i]:
                outboxes.append([])
                continue
            extra = action.messages if action is not None else ()
            if not service[i] and not extra:  # most ticks: nothing to send
                outboxes.append([])
                continue
            box = [self.medium.service_envelope(i, m) for m in service[i]]
            if extra:
                box += self.medium.outbox(i, extra)  # within the robot's per-tick budget
            outboxes.append(box)
        if self.medium.dropped:
            self._note_drops(tick)
        if self.medium.relaying:
            self.medium.add_relays(outboxes, self.failed)
        if any(outboxes):
            if self.comm.link_at == "send":
                self._deliver(tick, outboxes, links)
            else:
                self._in_flight = outboxes
            if self.maps is not None:  # (and the updates' building, their dense copies of full maps)
                release_freed_memory()
        return outboxes

    def _deliver(self, tick: int, outboxes: list[list[Envelope]], links: Any) -> None:
        """Judge the broadcasts of ``tick`` by ``links`` (the positions of send or of receipt) into next tick's
        inboxes; failed robots receive nothing. With packet errors the medium also reads the pairs' margins."""
        senders = [i for i, out in enumerate(outboxes) if out]
        margin = None
        if self.medium.packet_errors is None:
            link = links.senders_link(senders)
        else:
            link, margin = links.senders_margin(senders)
        if np.count_nonzero(self.failed):
            link = link & ~self.failed[:, None]
            if margin is not None:
                margin = np.where(self.failed[:, None], -np.inf, margin)
        self.inboxes = self.medium.deliver(tick, outboxes, link, margin)
        self._deliveries = self.medium.deliveries(outboxes)

    # ------------------------------------------------------------------------------- observations ----
    def _sight(self, poses: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """``(distance, near)``: the radio's pair distances and who is within ``neighbour_range`` with no wall
        crossed, walking only the pairs in range (the tick's all-pairs radio picture is not needed)."""
        return self.links.in_sight(poses[:, :2], self.neighbour_range)

    def _batch(self, tick: int, poses: np.ndarray, pose_tuples: list[Pose], collided: np.ndarray,
               inboxes: list[list[Envelope]], merged: list[list[np.ndarray | None]],
               true_poses: np.ndarray | None = None) -> TickBatch:
        """The tick's observations as arrays, for any host: neighbours (and, for a host with mirrors, the
        knowledge cells changed since each robot's last observation) are computed when first read. ``poses``:
        where the robots believe they are (what they observe, and where their lidars wrote); ``true_poses``
        (default: the same) decide who senses whom and how far apart they are."""
        live = ~self.failed
        navs = [nav.status() if ok else None for nav, ok in zip(self.navigators, live.tolist())]
        at = poses.copy()  # the world moves these in place next tick; a late read must see this tick's
        seen_from = at if true_poses is None else true_poses.copy()
        changed = None
        if self._mirror is not None:
            cast = self.lidar.cast.copy()  # whose lidar may have written this tick (the next scan overwrites it)
            changed = lambda: self._changed_cells(at, cast, merged)  # noqa: E731
        index = getattr(self.links, "sight_index", None)
        near = None if index is None else (lambda: index(seen_from[:, :2], self.neighbour_range))  # noqa: E731
        return TickBatch(tick, live, poses, pose_tuples, collided, self.world.distance, self.world.rotation, navs,
                         self.known, self._views, inboxes, lambda: self._sight(seen_from), changed, near)

    def _changed_cells(self, poses: np.ndarray, cast: np.ndarray,
                       merged: list[list[np.ndarray | None]]) -> tuple[np.ndarray, np.ndarray]:
        """``(cells, ends)``: per robot, flat indices (ascending) of its knowledge cells changed since its last
        observation, robot i's at ``cells[ends[i-1]:ends[i]]`` (none for failed robots): the lidar only writes
        within range of the robots it ``cast`` this tick, delta merges report their cells, so only those
        places are compared, all robots in one compiled call; after a full-map merge the whole map is."""
        assert self._mirror is not None
        windowed = ~self.failed
        full = []
        if any(merged):  # most ticks no map update arrives
            full = [i for i, cells in enumerate(merged) if cells and any(m is None for m in cells) and windowed[i]]
            windowed[full] = False
        boxes = self._lidar_boxes(poses)
        boxes[~cast, 1] = boxes[~cast, 0]  # a robot its lidar did not cast wrote nothing: an empty window
        cells, ends = sync_boxes_flat(self.known, self._mirror, boxes, merged, windowed)
        if not full:
            return cells, ends
        bounds = ends.tolist()
        pieces = [cells[start:end] for start, end in zip([0, *bounds[:-1]], bounds)]
        for i in full:
            pieces[i] = sync_changes(self.known[i], self._mirror[i])
        return np.concatenate(pieces), np.cumsum([len(piece) for piece in pieces], dtype=np.int64)

    def _lidar_boxes(self, poses: np.ndarray) -> np.ndarray:
        """Per pose, the cells a lidar scan from it may write: int64 rows [r0, r1) and columns [c0, c1) within
        :attr:`_reach` of the pose's cell (unclipped)."""
        centres = (poses[:, 1::-1] / CELL_M).astype(np.int64)  # (row, col); truncation, as int() did
        reach = self._reach
        return np.column_stack((centres[:, 0] - reach, centres[:, 0] + reach + 1,
                                centres[:, 1] - reach, centres[:, 1] + reach + 1))

    def _note_drops(self, tick: int, dropped: list[tuple[int, str]] | None = None) -> None:
        """Events for the messages the medium (or, given ``dropped``, the transport: a remote agent's that do
        not decode) dropped as malformed this tick (the first ``MAX_DROP_EVENTS`` of a run; all of them are
        counted in ``summary.messages``); ``dropped`` is emptied."""
        dropped = self.medium.dropped if dropped is None else dropped
        room = MAX_DROP_EVENTS - self._drop_events
        for robot, reason in dropped[:max(room, 0)]:
            self.events.append({"tick": tick, "robot": robot, "event": "message_dropped", "reason": reason})
        self._drop_events += min(len(dropped), max(room, 0))
        dropped.clear()

    def _note_failures(self, tick: int, host: AgentHost) -> None:
        if host.stats.dropped:
            self._note_drops(tick, host.stats.dropped)
        for i, (at, reason) in sorted(host.stats.failures.items()):
            if not self.failed[i]:
                self.failed[i] = True
                self.world.disable(i)
                self.navigators[i].set_goal(None)
                self.events.append({"tick": at, "robot": i, "event": "agent_failed", "reason": reason})

    # ------------------------------------------------------------------------------------ results ----
    def _record(self, tick: int, explored: float, collisions: int, links: Any) -> None:
        stats = self.medium.stats
        n = self.spec.robots.count
        if self.observers:
            links.state()  # observers read the whole radio picture: evaluate it once, for the groups too
        if self.localizer is not None:   # each robot's pose error at every recorded tick
            err = self.localizer.errors(self.world.poses)
            self._pose_errors["tick"].append(tick)
            self._pose_errors["position_m"].append([round(float(e), 4) for e in err[:, 0]])
            self._pose_errors["heading_rad"].append([round(float(e), 5) for e in err[:, 1]])
        correct = {} if self._correct is None else {"explored_correct": self._correct.record(tick, self.known)}
        groups = links.groups() if n > 1 else [frozenset({0})]
        self.metrics.record(tick, explored=explored, coverage=self.tracker.coverage,
                            distance_m=float(self.world.distance.sum()), collisions=collisions,
                            msgs_sent=stats.sent, bytes_sent=stats.bytes_sent, msgs_delivered=stats.delivered,
                            bytes_delivered=stats.bytes_delivered,
                            msgs_dropped=stats.dropped,
                            comm_groups=len(groups), biggest_group=max(len(g) for g in groups) / n,
                            all_connected=len(groups) == 1,
                            mean_pair_distance_m=links.mean_distance() if n > 1 else 0.0, **correct)
        self.comm_metrics.record(tick, stats, self.known, self.tracker.seen_free_cells, groups, self.ages)

    def _localization_summary(self) -> dict[str, Any]:
        """With a localisation model: each robot's final pose error and the quality of the maps it built
        (:func:`swarm.results.mapquality.map_quality`); nothing without one, so summaries stay as they were."""
        if self.localizer is None:
            return {}
        from swarm.results.mapquality import map_quality

        err = self.localizer.errors(self.world.poses)
        return {"localization": {"model": self.spec.localization.model,
                                 "final_position_error_m": [float(e) for e in err[:, 0]],
                                 "final_heading_error_rad": [float(e) for e in err[:, 1]],
                                 "off_map_scans": self.off_map_scans,
                                 "pose_error_series": self._pose_errors,
                                 "ticks_to_correct": dict(self._correct.ticks_to),
                                 **map_quality(self.known, self.truth.solid)}}

    def _sight_summary(self) -> dict[str, Any]:
        """Who saw what by its own lidar (docs/benchmark-metrics.md): the cells the team saw (free or solid),
        each robot's own-seen cells, the overlap rate and the coverage spread (Explore-Bench's collaboration
        metrics)."""
        trk = self.tracker
        return {"seen_cells": int(np.count_nonzero(trk.seers)),
                "own_seen_cells": [int(c) for c in trk.own_seen_cells], "overlap_rate": trk.overlap_rate(),
                "coverage_spread": trk.coverage_spread()}

    def _message_counts(self, host: AgentHost) -> dict[str, Any]:
        """The medium's counts, with the messages a remote agent sent that did not decode counted as malformed
        like those the medium dropped."""
        counts = self.medium.stats.as_dict()
        undecodable = host.stats.per_robot("bad_messages", self.spec.robots.count)
        counts["malformed"] += sum(undecodable)
        counts["malformed_by_robot"] = [a + b for a, b in zip(counts["malformed_by_robot"], undecodable)]
        return counts

    def _result(self, state: LoopState, wall: float, host: AgentHost) -> RunResult:
        n = self.spec.robots.count
        summary = {
            "ticks": state.tick,
            "stop_reason": state.stop_reason,
            "explored": float(self.tracker.explored),
            "coverage": float(self.tracker.coverage),
            "ticks_to": dict(self.metrics.ticks_to),
            "distance_m": [float(d) for d in self.world.distance],
            "collisions": state.collisions,
            "collisions_wall": int(state.collisions_with[0]),
            "collisions_robot": int(state.collisions_with[1]),
            **self._sight_summary(),
            "plans": [nav.plans for nav in self.navigators],
            "messages": self._message_counts(host),
            "acts": {kind: host.stats.per_robot(kind, n) for kind in ACT_COUNTS},
            "failed_robots": [int(i) for i in np.flatnonzero(self.failed)],
            "final_poses": [[float(v) for v in p] for p in self.world.poses],
            **self._localization_summary(),
            "map_seed": int(self.streams.map_seed) if self.spec.map.kind != "file" else None,
            "wall_time_s": wall,
            "setup_time_s": self.setup_time_s,
        }
        return RunResult(spec=self.spec.canonical(), key=self.spec.key, summary=summary,
                         timeseries=self.metrics.series, events=self.events, provenance=provenance(self.spec),
                         comm=self.comm_metrics.result())


def provenance(spec: RunSpec) -> dict[str, Any]:
    """What computes runs of ``spec``: this swarm's version, its commit when it runs from a git checkout
    (:mod:`swarm.util.source`), and the algorithm's distribution and version."""
    from swarm.plugins.explorers import distribution
    from swarm.util.source import package_version, source_commit

    dist = distribution(spec.algorithm.name)
    return {"swarm": package_version(), "source": source_commit(),
            "algorithm": {"name": spec.algorithm.name, "distribution": dist and dist[0], "version": dist and dist[1]}}


def run(spec: RunSpec | Mapping[str, Any]) -> RunResult:
    """Convenience: ``Simulation(spec).run()``."""
    return Simulation(spec).run()


__all__ = ["LoopState", "Simulation", "TickView", "TransportOptions", "build_map", "run"]


class _TickLinks:
    """The tick's :class:`radio.LinkState`, evaluated on first use. On most ticks nobody sends, no metrics
    are recorded (13 % of the benchmark's ticks carry messages), so the all-pairs radio walk is skipped
    (neighbours use the cheaper in-range walk); it is a pure function of the positions, kept here, so evaluating
    later gives the same state. Delivery alone needs only the senders' columns (:meth:`senders_link`)."""

    __slots__ = ("_model", "_xy", "_state", "_link")

    def __init__(self, model: Any, xy: np.ndarray) -> None:
        self._model = model
        self._xy = np.array(xy, dtype=np.float64)
        self._state: Any = None
        self._link: np.ndarray | None = None

    def state(self) -> Any:
        if self._state is None:
            self._state = self._model.evaluate(self._xy)
        return self._state

    def link_matrix(self) -> np.ndarray:
        """The tick's all-pairs link matrix, from the state if evaluated, else alone
        (:meth:`radio.LinkModel.link_matrix`: the same bits, none of the other matrices)."""
        if self._state is not None:
            return self._state.link
        if self._link is None:
            self._link = self._model.link_matrix(self._xy)
        return self._link

    def groups(self) -> list[frozenset[int]]:
        """The tick's communication groups (:meth:`radio.LinkState.groups`)."""
        if self._state is not None:
            return self._state.groups()
        if self._link is not None:
            return groups_of(self._link)
        return self._model.groups(self._xy)  # no link matrix needed: pairs judged only until joined

    def mean_distance(self) -> float:
        """The mean of the tick's all-pairs distance matrix (:attr:`radio.LinkState.distance`)."""
        distance = self._state.distance if self._state is not None else self._model.distances(self._xy)
        return float(distance.mean())

    def senders_link(self, senders: list[int]) -> np.ndarray:
        """A (R, R) link matrix whose columns ``senders`` are the tick's (who hears each sender), for
        :meth:`swarm.comm.medium.Medium.deliver`, which reads no other column. Unless the whole state is already
        known, only the pairs with a sender are walked (:meth:`radio.LinkModel.link_columns`): off the
        recording ticks only a robot or two send (a map request, a full map)."""
        if self._state is not None or self._link is not None or 2 * len(senders) > len(self._xy):
            return self.link_matrix()  # many senders: each pair walked once, not once per sender in it
        link = np.zeros((len(self._xy), len(self._xy)), dtype=np.bool_)
        link[:, senders] = self._model.link_columns(self._xy, senders)
        return link

    def senders_margin(self, senders: list[int]) -> tuple[np.ndarray, np.ndarray]:
        """:meth:`senders_link` and the same columns of the margins (RSSI minus the receiver's sensitivity,
        dB; NaN elsewhere), for packet errors."""
        r = len(self._xy)
        link = np.zeros((r, r), dtype=np.bool_)
        margin = np.full((r, r), np.nan)
        link[:, senders], margin[:, senders] = self._model.margin_columns(self._xy, senders)
        return link, margin

    def __getattr__(self, name: str) -> Any:  # only for names not in __slots__: the LinkState's fields
        return getattr(self.state(), name)


class _TiledViews:
    """The robots' maps as their algorithms see them, from tiled maps: robot i's map copied out of its tiles
    when read (:meth:`swarm.knowledge.tiles.TiledKnowledge.dense`), read-only and vouched for."""

    __slots__ = ("_maps",)

    def __init__(self, maps: TiledKnowledge) -> None:
        self._maps = maps

    def __len__(self) -> int:
        return self._maps.stack.shape[0]

    def __getitem__(self, i: int) -> np.ndarray:
        view = self._maps.dense(i)
        view.flags.writeable = False
        return vouch_known(view, trusted=True)  # (values copied from the runtime's maps: 0..2 by construction)
