"""TNF, The Next Frontier: frontier utility = information gain + distance term - coordination penalty.

Sources: Colares and Chaimowicz, "The Next Frontier: combining information gain and distance cost for
decentralized multi-robot exploration", ACM SAC 2016 (its full text was not available to us; the public
descriptions are the two below); the Minotaur paper (docs/papers.md) section 2.2:
TNF scores frontiers by information gain and the cost of getting there, and "each robot stores the newest
destination received from each other robot. When the robot decides upon the next frontier to explore, a
wavefront will be created from each stored destination, reducing the score of each frontier near it";
and how MAES implements TNF and FF-TNF (docs/maes.md section 7.3), whose structure and constants we
keep. The utility terms are in :mod:`algorithms.tnf_utility`.

**Behaviour.** A robot decides when it has no destination, reached it, its destination was seen (no
unseen cell left in view reach of it), the navigator reports it ``unreachable`` or ``blocked``, or it
made no progress for ``deadlock_ticks`` (the last three exclude that destination for ``exclude_ticks``;
``variant = "maes"`` does not decide when its destination is seen, and stops to communicate, see below).
To decide it clusters the frontier cells of its own map (:func:`swarm.grid.frontier_clusters`), scores
each reachable cluster with ``U = I + D - C`` and drives to the best one's target. It broadcasts the
chosen destination (:class:`Destination`) at once and every ``announce_every`` ticks while it pursues it;
each receiver keeps the newest destination of each sender. A robot that has heard nothing from others has
no penalty. After a collision it backs off, then steps to a random free cell about 1 m away (MAES's
collision mitigation; the draw uses the ``rng`` given to ``reset``) and decides again. Maps are shared
by the runtime's map-sharing service, as for every algorithm.

**Departures** from MAES's implementation (its bugs, docs/maes.md section 2.1, and its shortcuts)
and, where marked, from the paper's description:

1. *Distance term well defined.* MAES uses ``w = sqrt(sum_c |robot - c| / Dmax)`` summed over the
   frontier's cells, so ``w > 1`` for any frontier of a few cells and ``(1 - w)^(beta-1)`` becomes large and
   negative (beta = 10) or flips sign with the parity of beta. Here ``w = d / d_max`` with ``d`` the
   robot's **path length** to the frontier's target on its own configuration space (MAES: straight
   lines) and ``d_max`` the largest over the candidates, so ``w`` is in [0, 1], and the Beta kernel is
   divided by its maximum so D is in [0, 1] (unscaled, alpha = beta = 8 peaks at 6e-5 and would never
   matter).
2. *Information gain on the same scale.* MAES divides the Gaussian sum by the number of frontiers, a
   per-decision constant that leaves I anywhere from below 1 to above 100 and lets it swamp D. We divide
   by the largest candidate's sum instead (also a per-decision constant, so the ranking by I alone is
   unchanged), which puts I in (0, 1]. The Gaussian and its constants (A = 5, B = 0.5, C = 0.1; a cell's
   value is 0.5 when unseen, 0 otherwise) are MAES's.
3. *Coordination penalty with the right sign, from destinations, for every frontier.* MAES's plain TNF
   subtracts ``sum over sensed robots of sqrt(sum_c |p_r - c| / Dmax_r)``, which grows with distance and so
   penalises frontiers *far* from the others (and computes p_r from a relative bearing as if it were
   global); its FF-TNF subtracts a wavefront from the announced destinations but clears the destination
   list after scoring the *first* frontier. Here, following the paper, one wavefront (a geodesic distance
   field through non-solid cells, bounded at ``penalty_radius_m``) from all stored destinations lowers
   every frontier by ``max(0, 1 - d / penalty_radius_m)``.
4. *Destinations travel over the radio.* MAES broadcasts (map, id, destination) every 20 ticks only when
   another robot is sensed, stops the robot for that tick and merges maps by reference on the highest id.
   Here the destination is broadcast when chosen and every ``announce_every`` ticks; whoever the radio
   reaches hears it; maps go through the runtime's map-sharing service.
5. *Conflicts are resolved at once* (``yield_on_conflict``; an addition to the paper). Robots that start together all choose the
   same frontier in the same tick, before anyone has heard anyone; the paper and MAES use destinations
   only at a robot's next decision, so they would travel together to the first frontier. A robot that
   hears a lower-id robot announce a *new* destination within ``penalty_radius_m / 2`` of its own decides
   again, with the penalty. Re-announcements of a destination it already stored do not count (its last
   decision included them), and a robot yields at most once between two decisions of its own (reached,
   seen, unreachable...), which bounds the cascade of 16 robots spawned together yielding to each
   other's every new choice (150 x 150 building, first 3000 ticks: ~1100 yields without the two rules,
   ~800 with them, against ~1000 decisions of their own).
6. *Frontiers and targets.* Frontier cells are FREE 0.5 m cells with an UNSEEN 4-neighbour (the
   runtime's rule; MAES: 1 m tiles with an unseen 8-neighbour). The target is the reachable view cell
   nearest the cluster's representative cell (MAES: the integer mean of the first, middle and last cells,
   which can fall inside a wall), and the runtime's navigator drives there.
7. *Recovery.* MAES's HardReset after 5 (cumulative, not consecutive) colliding ticks is replaced by the
   no-progress watchdog and time-limited exclusions shared with Greed (:mod:`algorithms.recovery`); MAES
   TNF drops an unreachable frontier only for the current decision.
8. ``forget_ticks`` (default 0 = never, as the paper) can make stored destinations expire (an addition).

**``variant = "maes"``** puts back departures 1-3, MAES's utility with its bugs, for parity and ablation
runs (the default ``"swarm"`` is all of the above). Line numbers are those of
``Assets/Scripts/ExplorationAlgorithm/TheNextFrontier/TnfExplorationAlgorithm.cs`` in DEIS-Tools/MAES
(commit 1bb0312, 2024-10-14) unless another file is named; the terms are in :mod:`algorithms.tnf_utility`
(``maes_*``). It reproduces:

- *U* = I + D - C, the best frontier first, the next best when there is no path to it (lines 159-161,
  295-321: we score only frontiers with a reachable target, which picks the same one).
- *I* (bug 2): the Gaussian ``exp(alpha x^2 + beta x + gamma)`` with A = 5, B = 0.5, C = 0.1 (lines
  35-51) of cell values Unseen = 0.5, else 0 (``Utilities/ExtensionUtils.cs`` lines 39-46; a frontier
  cell is explored, so 0, line 410), summed over each frontier cell and its 8 neighbours and divided by
  the number of frontiers (lines 104-127), every frontier found counting, reachable or not (lines 109,
  296). No normalisation: I is about ``2.5 x`` (unseen neighbour slots) / F.
- *D* (bug 1): ``w^(alpha-1) (1-w)^(beta-1)`` with ``w = sqrt(sum_c |p - c| / Dmax)``, straight-line
  distances from the robot's position ``p`` to every cell of the frontier (``Wavefront``, lines 129-142),
  ``Dmax`` the largest robot-to-cell distance over all frontiers (line 301), ``w`` unclamped, so
  ``(1 - w)^(beta-1)`` is large and negative for odd ``beta - 1`` and large and positive for even. MAES's
  alpha and beta are ``int`` (lines 64-65, 97): the variant refuses non-integer values.
- *C* (bug 3): ``sum over sensed robots r of sqrt(sum_c |p_r - c| / Dmax_r)``, ``Dmax_r`` from ``p_r``
  over all frontiers, subtracted (lines 144-157, 160), so frontiers far from the others are penalised;
  ``p_r = p + distance (cos b, sin b)`` with ``b`` the bearing relative to the robot's heading used as a
  global angle (line 152; ``Robot/Robot2DController.cs`` lines 438-448 make the angle relative to the
  robot's forward; ``Utilities/Geometry.cs`` lines 78-82). swarm's :class:`~swarm.api.Neighbour` bearing is
  relative to the heading too, so ``p_r`` is placed exactly as MAES places it (right only when the robot
  heads along +x). The sensed robots are the observation's ``neighbours``, read at the decision, as MAES
  senses them while scoring (line 145); no sensed robot, no penalty (line 146).
- *Destinations*: MAES's plain TNF stores the received ``(map, id, destination)`` tuples'
  destinations in ``_currentDestinations`` (lines 83, 277-282) and never reads them. So the variant
  neither uses nor **broadcasts** :class:`Destination` (and never yields, departure 5, which needs them):
  sending them would change nothing the robots do, only add bytes to the message metrics and, under a
  per-link byte budget, compete with the map updates. The map part of MAES's broadcast is the runtime's
  map sharing, as for ``swarm`` (departure 4).

It does not reproduce, keeping swarm's way:

- *Resolution.* Frontiers are swarm's (0.5 m cells, FREE with an UNSEEN 4-neighbour, on the robot's own
  map; departure 6), not MAES's 1 m tiles with an unseen 8-neighbour (lines 392-444). So that a frontier
  ``L`` metres long weighs what its ``L`` tiles weigh in MAES, each cell counts for
  ``MAES_CELL_WEIGHT = 0.5`` in the three per-cell sums (I, and the sums under the square roots of D and
  C); the scale of each term and the sign flip then match MAES's up to the different cell rules.
- *Geometry details.* Distances are to cell centres; MAES measures to a tile's integer corner (line 141
  converts the ``Vector2Int`` tile, whose centre is at +0.5, ``Map/CoarseGrainedMap.cs`` line 87), a
  constant (0.5, 0.5) m shift. ``p`` is the observation's pose, not MAES's SLAM position with its
  random-walk error. Arithmetic is float64 (MAES: float32). When every frontier cell is at ``p``
  (``Dmax = 0``, MAES: 0/0 = NaN) w is 0. Ties go to the lower target row, then column (MAES: its list
  order).
- *Who is sensed*: swarm's neighbours (within ``comm.neighbour_range_m``, default the lidar range, in line
  of sight), not ``SenseNearbyRobots``'s range / wall / material-link rules
  (``Robot/CommunicationManager.cs`` lines 313-331), nor its 45-degree angle nudge (lines 152-159).
- *Everything around the utility*: targets, the navigator, the exclusions and the watchdog (departure 7;
  excluded cells and ``min_frontier_cells`` also leave F), the collision mitigation, and the radio
  (departure 4). ``penalty_radius_m``, ``announce_every``, ``forget_ticks`` and ``yield_on_conflict`` do
  nothing under ``maes``.

It also reproduces **when MAES's TNF decides and when it stops** (issue 49 row 11):

- *Decisions only at the end of the path or after a collision.* MAES picks a frontier in state
  AwaitNextFrontier (lines 206-212) and then only follows its path (213-216, ``DoMovement`` 347-371) until
  the path is used up (357-361, 367-368), a collision starts the mitigation (186-190, 217-219, 238-266;
  the random step clears the path, 263) or ``HardReset`` (196-198, 225-236); and an OutOfFrontiers robot
  looks again after a message (289-291). It does not look at its destination on the way: seeing it
  changes nothing. Here the ``maes`` robot keeps its destination when it is seen (the ``swarm`` rule
  above) and decides when the navigator reports it reached, after the collision back-off and random step,
  and -- where the runtime's navigator has no MAES counterpart -- when it reports the destination
  unreachable or blocked or the watchdog fires (departure 7).
- *The communication tick.* Every ``MAES_COMM_EVERY`` (20) ticks (the counter, 167, 180, 183-184, starts
  at 0, so ticks 0, 20, 40...) MAES senses its neighbours, and if there are any stops its current task
  (170) and broadcasts; that tick it does nothing else (181). Here a ``maes`` robot that senses a
  neighbour on such a tick commands (0, 0) for the tick, which is when the runtime's ``maes_sync`` merge
  (``comm.map_sharing = "maes"``) broadcasts too; an idle robot decides on the next tick (289-291).
  With no neighbour the tick is still spent without logic (181): the robot carries on, decides nothing,
  and, as in MAES, where the controller clears the collision flag after the algorithm's tick
  (``Robot/MonaRobot.cs`` 54-57), a collision reported then is not handled.

Not reproduced (issue 49 row 3, MAES's motion): MAES's stop ends the current ``Move`` or ``Rotate`` task
and the robot then brakes under Unity's drag (about one tick from 3 m/s) and carries on with the *next*
path step, turning in place first when it is more than 0.5 degrees off (``DoMovement`` 347-371,
``StartMoving`` 373-390); here the runtime's motion model brakes within its acceleration limit and the
navigator resumes the same path.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from swarm.api import (CELL_M, OMIT_DEFAULT, Action, InvalidInput, Observation, RobotInfo, cell_centre, cell_of,
                       check_bool, check_choice, check_float, check_int)
from swarm.api.grid import DEFAULT_MARGIN_M, configuration_space, default_view_reach_cells
from swarm.api.messages import MessageError, message

from .recovery import Backoff, Exclusions, Watchdog, check_recovery_params, gave_up, unseen_near
from .tnf_utility import VARIANTS, FrontierScore, best_frontier, maes_sensed_position


@message("tnf.destination")
@dataclass(frozen=True)
class Destination:
    """Where ``sender`` is heading: the target of the frontier it chose, metres."""

    sender: int
    x: float
    y: float

    def validate(self) -> None:
        for v in (self.x, self.y):
            if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v):
                raise MessageError("tnf.destination: x and y must be finite numbers")


def _destination_cell(msg: Destination, h: int, w: int) -> tuple[int, int]:
    """The map cell of an announced destination, clamped onto an ``h`` x ``w`` map. Computed once per
    message object: in-process one announcement reaches every robot in range, and a swarm's robots each
    computing the same cell made reading the inbox grow with robots x robots (issue 47). The message is
    frozen, so the memo cannot go stale; each receiver gets exactly what it would have computed."""
    memo = msg.__dict__.get("_cell")
    if memo is not None and memo[0] == h and memo[1] == w:
        return memo[2]
    r, c = cell_of(msg.x, msg.y)
    cell = (min(max(r, 0), h - 1), min(max(c, 0), w - 1))
    msg.__dict__["_cell"] = (h, w, cell)
    return cell


@dataclass(frozen=True)
class TNFParams:
    # "swarm" (the departures below) | "maes" (MAES's utility, bugs included); left out of the canonical spec
    # at its default, so TNF runs specified before the variant existed keep their keys
    variant: str = field(default="swarm", metadata={OMIT_DEFAULT: True})
    alpha: float = 1.0               # Beta-kernel shape of the distance term (MAES 2024 campaign: 1, 10;
    beta: float = 10.0               # the 2022 MAES paper: 8, 8)
    penalty_radius_m: float = 0.0    # coordination wavefront reach; 0 = the lidar range
    announce_every: int = 20         # re-broadcast the destination this often (MAES: 20 ticks)
    forget_ticks: int = 0            # drop a destination not refreshed for this long; 0 = keep the newest
    yield_on_conflict: bool = True   # decide again when a lower-id robot announces a nearby destination
    min_frontier_cells: int = 1      # smaller frontier clusters are ignored
    deadlock_ticks: int = 50         # no progress this long -> exclude the destination; 0 disables
    progress_m: float = 0.5
    exclude_ticks: int = 300
    exclude_radius_m: float = 1.0
    backoff_ticks: int = 15          # reverse this long after a collision; 0 disables collision mitigation
    backoff_speed: float = 0.3
    sidestep_ticks: int = 30         # give the random sidestep after a collision at most this long
    idle_recheck_ticks: int = 20     # with no frontier left, look again this often

    def __post_init__(self) -> None:
        check_float("alpha", self.alpha, 1.0, 100.0)
        check_float("beta", self.beta, 1.0, 100.0)
        check_choice("variant", self.variant, VARIANTS)
        if self.variant == "maes":
            for name in ("alpha", "beta"):
                value = getattr(self, name)
                if value != int(value):
                    raise InvalidInput(name, value, "a whole number with variant = 'maes' (MAES's alpha and beta "
                                                    "are int; (1 - w)^(beta - 1) of a negative 1 - w needs one)")
        check_float("penalty_radius_m", self.penalty_radius_m, 0.0, 1000.0)
        check_int("announce_every", self.announce_every, 1, 1_000_000)
        check_int("forget_ticks", self.forget_ticks, 0, 10_000_000)
        check_bool("yield_on_conflict", self.yield_on_conflict)
        check_int("min_frontier_cells", self.min_frontier_cells, 1, 1_000_000)
        check_recovery_params(self)
        check_int("sidestep_ticks", self.sidestep_ticks, 1, 10_000)
        check_int("idle_recheck_ticks", self.idle_recheck_ticks, 1, 1_000_000)


MAES_COMM_EVERY = 20
"""MAES's TNF communicates every 20 ticks (``TnfExplorationAlgorithm.cs`` 167, 183-184)."""

SIDESTEP_CELLS = 2   # MAES steps to a neighbouring 1 m tile: 2 cells here
_SIDESTEPS = tuple((dr * SIDESTEP_CELLS, dc * SIDESTEP_CELLS)
                   for dr in (-1, 0, 1) for dc in (-1, 0, 1) if (dr, dc) != (0, 0))


class TNF:
    """The Next Frontier (see the module docstring)."""

    name = "tnf"
    Params = TNFParams
    maes_map_merge = ("maes_sync", MAES_COMM_EVERY)  # comm.map_sharing = "maes": MAES's TNF syncs maps every 20 ticks

    def reset(self, robot: RobotInfo, params: TNFParams, rng: np.random.Generator) -> None:
        self.robot = robot
        self.params = params
        self.rng = rng
        self.reach = default_view_reach_cells(robot.radius, DEFAULT_MARGIN_M)
        self.penalty_radius = params.penalty_radius_m or robot.lidar_range
        self.maes = params.variant == "maes"   # MAES's utility; no destinations sent or used (module docstring)
        # MAES drives TNF's path run by run (TnfExplorationAlgorithm.cs 347-389; under motion.model = "maes")
        self.drive = "runs" if self.maes else "path"
        self.destinations: dict[int, tuple[tuple[int, int], int]] = {}   # sender -> (cell, tick heard)
        self.target: tuple[int, int] | None = None
        self.goal: tuple[float, float] | None = None
        self.last_choice: FrontierScore | None = None
        self.may_yield = True        # at most one yield between two decisions of its own
        self.yield_now = False
        self.announced_at = -1
        self.next_look = 0
        self.decide = True
        self.sidestep_pending = False
        self.sidestep: tuple[tuple[float, float], int] | None = None
        self.backoff = Backoff(params.backoff_ticks, params.backoff_speed)
        self.watchdog = Watchdog(params.deadlock_ticks, params.progress_m)
        self.exclusions = Exclusions(params.exclude_radius_m, params.exclude_ticks)

    # ------------------------------------------------------------------------------------------ act ----
    def act(self, obs: Observation) -> Action:
        self._read_inbox(obs)
        if self.maes and obs.tick % MAES_COMM_EVERY == 0:
            return self._maes_communication_tick(obs)
        if self.backoff.active(obs.tick) or self.backoff.start_if_collided(obs):
            self.sidestep_pending = True   # once backed off, sidestep (MAES collision mitigation)
            return Action(velocity=self.backoff.command())
        if self.sidestep_pending:
            self.sidestep_pending = False
            self.sidestep = self._sidestep(obs)
            if self.sidestep is not None:
                return Action(drive=self.drive, goal=self.sidestep[0])
        if self.sidestep is not None:
            goal, until = self.sidestep
            done = obs.nav.goal == goal and obs.nav.state in ("reached", "unreachable", "blocked")
            if obs.tick < until and not done:
                return Action(drive=self.drive, goal=goal)
            self.sidestep = None
            self.decide = True
        why = self._must_decide(obs)
        if why is not None:
            self.may_yield = self.may_yield or why == "own"
            self._decide(obs)
        if self.target is None:
            return Action(velocity=(0.0, 0.0), clear_goal=True)
        return Action(drive=self.drive, goal=self.goal, messages=self._announce(obs.tick))

    def _maes_communication_tick(self, obs: Observation) -> Action:
        """MAES's tick of communication (``TnfExplorationAlgorithm.cs`` 167-182): with a sensed neighbour,
        stop (170) for the tick; without, carry on. Either way no decision and no collision handling (181)."""
        if obs.neighbours:
            if self.target is None and self.sidestep is None:
                self.decide = True   # OutOfFrontiers looks again after the exchange (289-291)
            return Action(velocity=(0.0, 0.0))
        if self.backoff.active(obs.tick):
            return Action(velocity=self.backoff.command())
        if self.sidestep is not None:
            return Action(drive=self.drive, goal=self.sidestep[0])
        if self.target is None:
            return Action(velocity=(0.0, 0.0), clear_goal=True)
        return Action(drive=self.drive, goal=self.goal)

    # ------------------------------------------------------------------------------------- messages ----
    def _read_inbox(self, obs: Observation) -> None:
        h, w = obs.known.shape
        me = self.robot.id
        for msg in obs.inbox:
            if not isinstance(msg, Destination) or msg.sender == me:
                continue
            cell = _destination_cell(msg, h, w)
            known_before = self.destinations.get(msg.sender)
            self.destinations[msg.sender] = (cell, obs.tick)
            news = known_before is None or known_before[0] != cell   # a re-announcement changes nothing
            if (self.params.yield_on_conflict and not self.maes and news and self.may_yield
                    and msg.sender < self.robot.id
                    and self.target is not None
                    and CELL_M * math.dist(cell, self.target) < self.penalty_radius / 2):
                self.may_yield = False
                self.yield_now = True
        if self.params.forget_ticks:
            horizon = obs.tick - self.params.forget_ticks
            self.destinations = {s: v for s, v in self.destinations.items() if v[1] > horizon}

    def _announce(self, tick: int) -> tuple[Destination, ...]:
        if self.robot.n_robots < 2 or self.goal is None or self.maes:
            return ()
        if self.announced_at >= 0 and tick - self.announced_at < self.params.announce_every:
            return ()
        self.announced_at = tick
        return (Destination(sender=self.robot.id, x=self.goal[0], y=self.goal[1]),)

    # ------------------------------------------------------------------------------------- deciding ----
    def _must_decide(self, obs: Observation) -> str | None:
        """Why the robot must decide now ("own" or "yield"), or None."""
        if self.target is None:
            return "own" if self.decide or obs.tick >= self.next_look else None
        nav = obs.nav if obs.nav.goal == self.goal else None  # a status about an older goal says nothing
        if gave_up(obs, nav, self.target, self.exclusions, self.watchdog):
            return "own"
        if self.decide or (nav is not None and nav.state == "reached"):
            return "own"
        if not self.maes and not unseen_near(obs.known, self.target, self.reach + 1):
            return "own"   # MAES follows its path to the end, seen or not (module docstring, row 11)
        return "yield" if self.yield_now else None

    def _decide(self, obs: Observation) -> None:
        self.decide = self.yield_now = False
        previous = self.target
        reached = obs.nav.state == "reached" and obs.nav.goal == self.goal
        best = self._best(obs)
        if best is not None and best.target == previous and reached:
            # Standing on the target while unseen cells in view reach stay hidden: give it up.
            self.exclusions.add(best.target, obs.tick)
            best = self._best(obs)
        self.last_choice = best
        if best is None:
            self.target = self.goal = None
            self.next_look = obs.tick + self.params.idle_recheck_ticks
            return
        self.target = best.target
        self.goal = cell_centre(*best.target)
        if self.target != previous:
            self.watchdog.restart(obs)
            self.announced_at = -1    # announce the new destination at once

    def _best(self, obs: Observation) -> FrontierScore | None:
        p = self.params
        start = _clip(cell_of(obs.pose.x, obs.pose.y), obs.known.shape)
        exclude = self.exclusions.mask(obs.known.shape, obs.tick)
        if self.maes:
            # MAES's sensed robots, placed with their relative bearing as a global angle (its line 152).
            sensed = [maes_sensed_position(obs.pose.x, obs.pose.y, n.distance, n.bearing) for n in obs.neighbours]
            return best_frontier(obs.known, start, np.zeros((0, 2), dtype=np.int64), alpha=p.alpha, beta=p.beta,
                                 robot_radius_m=self.robot.radius, penalty_radius_m=0.0, reach=self.reach,
                                 exclude=exclude, min_size=p.min_frontier_cells, variant="maes",
                                 position_m=(obs.pose.x, obs.pose.y),
                                 sensed_m=np.array(sensed, dtype=np.float64).reshape(-1, 2))
        dest = [cell for cell, _ in self.destinations.values()]
        return best_frontier(obs.known, start, np.array(dest, dtype=np.int64).reshape(-1, 2), alpha=p.alpha,
                             beta=p.beta, robot_radius_m=self.robot.radius, penalty_radius_m=self.penalty_radius,
                             reach=self.reach, exclude=exclude, min_size=p.min_frontier_cells)

    # ------------------------------------------------------------------------------------ collisions ----
    def _sidestep(self, obs: Observation) -> tuple[tuple[float, float], int] | None:
        """MAES TNF's collision mitigation: a random free spot about 1 m away that no sensed robot is
        near, as (goal, give-up tick); None when there is none."""
        space = configuration_space(obs.known, self.robot.radius)
        r, c = cell_of(obs.pose.x, obs.pose.y)
        h, w = space.shape
        taken = [cell_of(n.x, n.y) for n in obs.neighbours]
        options = []
        for dr, dc in _SIDESTEPS:
            rr, cc = r + dr, c + dc
            if 0 <= rr < h and 0 <= cc < w and space[rr, cc] and all(
                    max(abs(rr - tr), abs(cc - tc)) > SIDESTEP_CELLS for tr, tc in taken):
                options.append((rr, cc))
        if not options:
            return None
        pick = options[int(self.rng.integers(len(options)))]
        return cell_centre(*pick), obs.tick + self.params.sidestep_ticks


def _clip(cell: tuple[int, int], shape: tuple[int, ...]) -> tuple[int, int]:
    return min(max(cell[0], 0), shape[0] - 1), min(max(cell[1], 0), shape[1] - 1)
