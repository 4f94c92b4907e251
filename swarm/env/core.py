"""One run driven step by step for learning: the engine under both environments (no Gymnasium needed).

The run is an ordinary :class:`~swarm.sim.loop.Simulation` (pymunk world, lidar, radio-gated messaging
and map sharing, knowledge maps) advanced with the same ``sense`` / ``observe`` / ``apply`` steps its
:meth:`~swarm.sim.loop.Simulation.run` loop uses, so a tick here is a tick there. Learning robots take
their action from the caller; every other robot (and a learner that delegates) runs the spec's explorer
exactly as the in-process transport would run it. With every robot scripted, stepping reproduces
:func:`swarm.run` of the same spec bit for bit (tested).

Observation of learner ``i`` (arrays, :meth:`observation`): ``map`` the egocentric crop of its own
knowledge map, ``pose``, ``neighbours``, ``inbox`` and in goal mode ``choices``; their layout is in
docs/python-api.md ("Learning").
"""

from __future__ import annotations

import math
from typing import Any, Mapping

import numpy as np

from swarm.base.errors import InvalidInput

from swarm.api import Action, cell_centre
from swarm.comm.messages import MapUpdate
from swarm.results.result import RunResult
from swarm.sim.loop import Simulation
from swarm.sim.spec import RunSpec
from swarm.transport.inprocess import InProcessHost, check_action, observations
from swarm.world.motion import TICK_S
from ._kernels import NAV_FAILED, NAV_MOVING, _env_after, _env_before, _env_features
from .config import SECTORS, EnvConfig

CELL_AREA_M2 = 0.25
"""A 0.5 m knowledge cell."""
POSE_FIELDS = ("x", "y", "cos_theta", "sin_theta", "collided", "moving", "goal_failed", "known_fraction", "time")
"""The ``pose`` vector: position scaled to [-1, 1] over the map, heading, whether a contact began during the
step, whether the navigator drives to a goal, whether the last goal proved unreachable or blocked, the
share of the map's cells the robot's own map knows, and the run's time as a share of ``stop.max_ticks``."""
NEIGHBOUR_FIELDS = ("linked", "dx", "dy", "margin")
"""Per other robot (in id order): 1 if its messages reach this robot this tick, its relative position (m,
scaled by the map's longer side), and the link margin (RSSI minus this robot's sensitivity, dB, clipped to
+-``margin_db`` and scaled to [-1, 1]); all 0 for an unlinked robot unless ``observe_all``."""
INBOX_FIELDS = ("messages", "map_updates", "bytes", "since_contact")
"""Messages received during the step per other robot, map updates among them per other robot, log of the
bytes received (1 = 64 KiB), ticks since anything was last received (1 = a minute or never); each in [0, 1]."""
KEEP = Action()
"""Keep driving to the current goal (if any)."""
DELEGATE_INDEX = 1 + SECTORS
"""Goal mode with ``delegate``: the action that lets the robot's explorer decide."""
_LOG_BYTES = math.log1p(65536.0)
_NAV_CODE = {"moving": NAV_MOVING, "planning": NAV_MOVING, "unreachable": NAV_FAILED, "blocked": NAV_FAILED}
_CONTACT_TICKS = 600.0


def _velocity(a: Any) -> np.ndarray | None:
    """A velocity-mode action as two finite floats, or None when it is not one (strings, mappings, None,
    another shape): the caller turns that into a one-line error."""
    if isinstance(a, (str, bytes, Mapping)) or a is None:
        return None
    try:
        v = np.asarray(a, dtype=np.float64).reshape(-1)
    except (TypeError, ValueError, OverflowError):
        return None
    return v if v.shape == (2,) and np.isfinite(v).all() else None


class _NoLinks:
    """The radio picture of a one-robot run, for the features kernel (never read)."""

    link = np.zeros((1, 1), dtype=np.bool_)
    rssi = np.zeros((1, 1))


class ExplorationCore:
    """A run of ``spec`` stepped by :meth:`step`; :meth:`reset` starts it (again) from a seed."""

    def __init__(self, spec: RunSpec, config: EnvConfig) -> None:
        self.base = spec
        self.config = config
        n = spec.robots.count
        self.n = n
        self.learners = config.learner_ids(n)
        self._learners = np.array(self.learners, dtype=np.int64)
        self._slot = {robot: l for l, robot in enumerate(self.learners)}
        self.scripted = tuple(i for i in range(n) if i not in self._slot)
        self.half = config.crop_cells // 2
        self._n_actions = config.n_actions
        self._goal_mode = config.action == "goal"
        self._others = max(n - 1, 1)
        self._no_links = _NoLinks()
        lcount = len(self.learners)
        side = config.crop_cells
        self.crop = np.zeros((lcount, side, side), dtype=np.uint8)
        self.choices = np.zeros((lcount, SECTORS, 3), dtype=np.float32)
        self.goals = np.full((lcount, SECTORS, 2), -1, dtype=np.int64)
        self.pose = np.zeros((lcount, len(POSE_FIELDS)), dtype=np.float32)
        self.neighbours = np.zeros((lcount, max(n - 1, 1), len(NEIGHBOUR_FIELDS)), dtype=np.float32)
        self.inbox = np.zeros((lcount, len(INBOX_FIELDS)), dtype=np.float32)
        self.rewards = np.zeros(lcount, dtype=np.float64)
        self._counters = np.zeros((4, lcount), dtype=np.int64)  # zeroed at once at every step
        self._own_new, self._msgs, self._updates, self._bytes = self._counters
        self._began = np.zeros(lcount, dtype=np.bool_)
        self._before = np.zeros(lcount, dtype=np.int64)
        self._after = np.zeros(lcount, dtype=np.int64)
        self._cells = np.zeros((lcount, 2), dtype=np.int64)
        self._valid = np.zeros(lcount, dtype=np.bool_)
        self.sim: Simulation | None = None
        self.done = True

    # ------------------------------------------------------------------------------ episode ----
    def reset(self, seed: int) -> None:
        """A new run of the spec with master seed ``seed`` (map unless ``map.seed`` pins it, spawn, noise,
        radio loss, the explorers' generators), sensed at tick 0."""
        spec = self.base.replace(seed=seed)
        self.close()
        sim = Simulation(spec, tiled=False)  # the features read dense maps
        host = InProcessHost()
        host.start(sim.resets())
        self.sim, self.host, self.state = sim, host, sim.start_state()
        reach = sim._reach + int(math.ceil(sim.motion.max_speed * TICK_S / 0.5)) + 1
        self._window = reach  # the lidar writes within sim._reach of the moved robot
        self._map_cells = float(sim.truth.shape[0] * sim.truth.shape[1])
        self._scale = 1.0 / max(sim.truth.width_m, sim.truth.height_m)
        self._sensitivity = sim.links.config.sensitivity_array(self.n)
        self._navs = sim.navigators
        self._width, self._height = float(sim.truth.width_m), float(sim.truth.height_m)
        self._per_tick = 1.0 / spec.stop.max_ticks
        self._known = np.zeros(len(self.learners), dtype=np.int64)
        self._last_contact = np.full(len(self.learners), -1, dtype=np.int64)
        self._valid[:] = False
        self._start_accumulators()
        self.done = self._sense()
        self._known[:] = np.count_nonzero(sim.known[self._learners].reshape(len(self.learners), -1), axis=1)
        self._last_contact[:] = -1
        self._start_accumulators()  # tick 0's scan is the start, not a reward
        self._features()

    def close(self) -> None:
        if self.sim is not None:
            self.host.close()
            self.sim = None

    # --------------------------------------------------------------------------------- step ----
    def step(self, actions: Mapping[int, Any]) -> None:
        """Advance ``ticks_per_step`` ticks (fewer if the run stops) with ``actions`` (learner robot id ->
        its action: a goal-mode index or a velocity pair in [-1, 1]); then :attr:`rewards` and the
        observation arrays hold the step's outcome."""
        if self.sim is None or self.done:
            raise RuntimeError("step() after the episode ended: call reset()")
        first, later, asked = self._learner_actions(actions)
        self._start_accumulators()
        for k in range(self.config.ticks_per_step):
            self.sim.apply(self.state, self._tick_actions(first if k == 0 else later, asked))
            if self._sense():
                self.done = True
                break
        self._features()

    def _learner_actions(self, actions: Mapping[int, Any]) -> tuple[list[Action | None], list[Action | None], list[int]]:
        """The step's actions checked and turned into the runtime's: per robot, the action of the step's first
        tick and of the later ones (a goal is set once, then kept; a velocity is held), and the robots whose
        explorer decides (scripted teammates and delegating learners, in id order)."""
        first: list[Action | None] = [None] * self.n
        later: list[Action | None] = [None] * self.n
        asked = list(self.scripted)
        goal_mode = self.config.action == "goal"
        n_actions = self._n_actions
        for l, robot in enumerate(self.learners):
            if robot not in actions:
                raise InvalidInput("actions", list(actions)[:8], f"an action for every learning robot ({list(self.learners)})")
            a = actions[robot]
            if goal_mode:
                if not (type(a) is int and 0 <= a < n_actions):  # the common case is checked cheaply
                    a = self._index(robot, a)
                if a == DELEGATE_INDEX:
                    asked.append(robot)
                    continue
                later[robot] = KEEP
                row = self.goals[l, a - 1, 0] if a else -1
                first[robot] = Action(goal=cell_centre(int(row), int(self.goals[l, a - 1, 1]))) if row >= 0 else KEEP
            else:
                v = _velocity(a)
                if v is None:
                    raise InvalidInput(f"actions[{robot}]", a, "two finite numbers in [-1, 1]: speed, turn rate")
                v = np.clip(v, -1.0, 1.0)
                m = self.sim.motion
                first[robot] = later[robot] = Action(velocity=(float(v[0]) * m.max_speed, float(v[1]) * m.max_turn_rate))
        asked.sort()
        return first, later, asked

    def _index(self, robot: int, a: Any) -> int:
        """A goal-mode action given as another integer type (numpy's, a 0-d array), or a one-line error; an
        array of several values, a string or a bool is refused rather than compared element-wise."""
        index = -1
        try:
            if np.ndim(a) == 0 and not isinstance(a, (bool, np.bool_, str, bytes)):
                whole = int(a)
                if bool(whole == a):
                    index = whole
        except (TypeError, ValueError, OverflowError):
            pass
        if not 0 <= index < self._n_actions:
            raise InvalidInput(f"actions[{robot}]", a, f"an integer 0..{self._n_actions - 1}")
        return index

    def _tick_actions(self, template: list[Action | None], asked: list[int]) -> list[Action | None]:
        """The tick's action per robot: ``template`` (the learners'), with the explorers' of the robots in
        ``asked`` decided on this tick's observations, as the in-process transport runs them."""
        batch = self.sim.observe(self.state)
        if not asked:
            return template
        acts = list(template)
        obs = observations(batch)
        agents = self.host.agents
        for robot in asked:
            if obs[robot] is not None:
                acts[robot] = check_action(agents[robot].act(obs[robot]), robot)
        return acts

    # ------------------------------------------------------------------------------ sensing ----
    def _start_accumulators(self) -> None:
        """Zero what a step sums over its ticks."""
        self.rewards.fill(0.0)
        self._counters.fill(0)
        self._began.fill(False)
        self._team_new = 0
        self._ticks = 0

    def _sense(self) -> bool:
        """One tick's sensing (:meth:`Simulation.sense`), measuring on the way what each learner's own lidar
        revealed to it (before maps merged from others arrive) and what it received; True when the run stops."""
        sim, state, learners = self.sim, self.state, self._learners
        reward = self.config.reward
        # the window around each robot's cell before the move covers what the moved robot's scan writes
        _env_before(sim.known, learners, sim.world.poses, self._cells, self._valid, self._window, self._before,
                    self._after)
        seen0 = sim.tracker.seen_free_cells
        sim.move_and_scan(state)
        team = sim.tracker.seen_free_cells - seen0
        self._team_new += team
        _env_after(sim.known, learners, self._cells, self._valid, self._window, sim.lidar.cast, self._before,
                   self._after, state.began, self._own_new, self._known, self._began, self.rewards,
                   reward.own * CELL_AREA_M2, reward.team * CELL_AREA_M2 * team - reward.time_penalty,
                   reward.collision_penalty)
        stop = sim.communicate(state)
        self._ticks += 1
        inboxes = state.inboxes
        if any(inboxes):
            self._received(inboxes)
        return stop

    def _received(self, inboxes: list[list[Any]]) -> None:
        """Count the learners' deliveries of the tick; merged maps: recount each receiver's whole map."""
        for l, robot in enumerate(self.learners):
            inbox = inboxes[robot]
            if inbox:
                self._msgs[l] += len(inbox)
                self._bytes[l] += sum(len(env.data) for env in inbox)
                self._updates[l] += sum(isinstance(env.message, MapUpdate) for env in inbox)
                self._last_contact[l] = self.state.tick
                self._known[l] = np.count_nonzero(self.sim.known[robot])
                self._valid[l] = False  # a merge may have filled its window

    def _features(self) -> None:
        """The observation arrays of every learner for the current tick, fresh arrays each step (handed out
        as views: an observation is never overwritten later), in one compiled call."""
        sim, state, learners = self.sim, self.state, self._learners
        lcount, side = len(self.learners), self.config.crop_cells
        self.crop = np.empty((lcount, side, side), dtype=np.uint8)
        self.choices = np.empty((lcount, SECTORS, 3), dtype=np.float32)
        self.pose = np.empty((lcount, len(POSE_FIELDS)), dtype=np.float32)
        self.inbox = np.empty((lcount, len(INBOX_FIELDS)), dtype=np.float32)
        self.neighbours = np.empty((lcount, max(self.n - 1, 1), len(NEIGHBOUR_FIELDS)), dtype=np.float32)
        self.masks = np.empty((lcount if self._goal_mode else 0, self._n_actions), dtype=np.int8)
        navs = self._navs
        nav = np.array([_NAV_CODE.get(navs[robot].state, 0) for robot in self.learners], dtype=np.int8)
        links = state.links.state() if self.n > 1 else self._no_links
        _env_features(sim.known, sim.world.poses, learners, self.half, 4.0, self._width, self._height, self._began, nav,
                      self._known, self._map_cells, min(state.tick * self._per_tick, 1.0), self._msgs, self._updates,
                      self._bytes, self._last_contact, state.tick, 1.0 / (self._others * max(self._ticks, 1)),
                      _LOG_BYTES, _CONTACT_TICKS, self.n > 1, links.link, links.rssi, self._sensitivity, self._scale,
                      self.config.margin_db, self.config.observe_all, self.crop, self.choices, self.goals, self.pose,
                      self.inbox, self.neighbours, self.masks)

    # ------------------------------------------------------------------------------ outputs ----
    def observation(self, l: int) -> dict[str, np.ndarray]:
        """Learner slot ``l``'s observation (views of this step's arrays, which no later step writes)."""
        obs = {"map": self.crop[l], "pose": self.pose[l], "neighbours": self.neighbours[l], "inbox": self.inbox[l]}
        if self.config.action == "goal":
            obs["choices"] = self.choices[l]
        return obs

    def action_mask(self, l: int) -> np.ndarray:
        """Goal mode: which actions do something now (keep, sectors with a frontier, delegate if on)."""
        return self.masks[l]

    @property
    def truncated(self) -> bool:
        """The run stopped for a limit (ticks, stall), not because the map was explored or robots failed."""
        return self.done and self.state.stop_reason in ("max_ticks", "stalled")

    def info(self) -> dict[str, Any]:
        """Shared by every agent: the tick, the team's explored fraction and, at the end, why it stopped."""
        sim = self.sim
        return {"tick": self.state.tick, "explored": sim.tracker.explored, "stop_reason": self.state.stop_reason}

    def result(self) -> RunResult:
        """The run's :class:`RunResult` so far (as :func:`swarm.run` would report it at this tick)."""
        sim = self.sim
        return sim._result(self.state, 0.0, self.host)


__all__ = ["CELL_AREA_M2", "ExplorationCore", "INBOX_FIELDS", "KEEP", "NEIGHBOUR_FIELDS", "POSE_FIELDS"]
