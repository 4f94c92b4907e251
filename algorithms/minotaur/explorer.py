"""Minotaur: wall following, spiralling, doorway detection and doorway auctions.

Follows Schmidt, Sørensen, Beregaard and Albano, "Spiralling Human-Inspired Exploration Algorithm with
Doorway Detection" (the Minotaur paper, docs/papers.md): section 3.1 and Alg. 1 (single robot), section
3.2 and Alg. 2 (many robots), section 3.3 and Alg. 3 (doorway detection, :mod:`.detection`), section 3.4 and Alg. 4 (doorway
auction, :mod:`.auction`), section 3.5 (the Greed fallback), section 4.2 (spiralling, :mod:`.walls`) and
4.3 (doorway detection details); and MAES's implementation (docs/maes.md section 7.2).

States (``debug["state"]``):

- ``start``: "while no walls or explored areas are in range, move forward" (direct velocity);
- ``room``: explore the room "while unexplored area is reachable without passing doorways": follow the
  wall or the edge of explored space in the spin direction (``mode`` ``follow-wall`` / ``follow-edge``,
  :func:`.walls.choose`), look at a gap that may be a doorway (``inspect``), or, with nothing in visual
  range, go to the nearest unseen cell in the room (``room-greedy``);
- ``door``: the room is done (or an auction was won): go through the nearest unexplored doorway in the
  room, else the nearest one anywhere (:func:`.rooms.choose_door`);
- ``greedy``: no doorway applies: the nearest unseen cell anywhere (Greed, section 3.5);
- ``done``: nothing unseen is reachable; stand still and look again now and then.

Every ``scan_every`` ticks the map around the robot is scanned for doorways; a new one is stored, and
with more than one robot auctioned (Alg. 2 "store and handle doorway (Alg. 4)"); doorways seen from
both sides or passed through become explored. Every ``share_every`` ticks the robot broadcasts its
doorway list with its current target (:class:`.messages.DoorwayList`), and a short
:class:`.messages.Heading` whenever its target changes in between.

Departures from the paper and from MAES, on purpose (details in each module's docstring):

1. **Map sharing** is the runtime's service (``comm.map_sharing``), which merges every update into the
   receiver's map: MAES's heartbeat merge (only with two heartbeats in one tick, senders' maps only,
   docs/maes.md section 2 item 4) is not reproduced. Doorway lists travel in their own message at the same
   cadence (the map message type is the runtime's); the parameter ``share_every`` should match
   ``comm.share_every`` (both 10 by default), the algorithm cannot read the run's comm section.
2. **Spiral** (section 4.2) exists here; MAES has none. It is not a separate state: the wall-following
   sweep keeps following the edge of explored space once no wall end is left (:mod:`.walls`).
3. **Targets are planned** by the runtime's navigator on the robot's own map; MAES drives straight.
   Because the navigator plans on seen cells only, a doorway is passed in two steps: to a point 1 m in
   front of it (from where the lidar sees through), then to ``pass_through_m`` beyond it.
4. **Doorway detection** works on axis-aligned walls of the grid and accepts a gap as soon as the map
   shows it (:mod:`.detection`); partially seen gaps become ``inspect`` targets instead of the paper's
   "move forward the door width" / "move to the intersection" manoeuvres (``variant = "maes"`` makes
   them: see below). Cave walls pass the test now and then (``wall_continue_m`` in :mod:`.params`).
5. **Doorways that lead nowhere new**: before going through a doorway the robot checks that unseen
   space is reachable behind it without passing another doorway; if not it marks it resolved (locally)
   and skips it. The paper would walk through and back.
6. **Doorway or Greed** (``greedy_if_nearer``, on by default): when the room is done and no unexplored
   doorway is in it, the robot goes to the nearest unseen cell if that is nearer than the nearest
   unexplored doorway elsewhere. Alg. 1 always takes the doorway; with many robots that sent most of
   them on long trips to far doorways (measured: half of all robot time on 100 x 100 buildings with 16
   robots, and 40 % more ticks to 99 %). ``greedy_if_nearer=false`` is the paper's rule.
7. **Spin split** (Alg. 2): a robot takes counter-clockwise if its rank by id among the robots it
   knows to be in its room (neighbours in sight and map-update poses from the last 50 ticks, inside the
   same door-bounded space) is even, clockwise if odd; it re-decides on entering a room.
8. **Auction**: the paper's rules (the auctioneer bids, floor(n/2) of the n bids win), not MAES's
   (ceil(n/2), auctioneer never bids); duplicate auctions for one doorway resolve to the lower id.
9. **Others' targets**: a robot leaves a doorway another robot announced it is going through to it
   (for 100 ticks), and keeps its greedy targets 3 m from other robots' announced targets (MAES's
   Minotaur excludes other robots' destinations when it re-targets after a deadlock). Not in the paper.
10. **Deadlocks**: a target the navigator reports unreachable or blocked is avoided for
    ``exclude_ticks`` (MAES re-targets after five unchanged coarse positions); a wall end or edge whose
    unseen cell is still unseen after the robot went to look (a corner the lidar cannot hit) is never
    chosen again.

**variant = "maes"** (issue 33; :mod:`.maes` has the details) makes the robot do what MAES's
``Assets/Scripts/ExplorationAlgorithm/Minotaur/MinotaurAlgorithm.cs`` does where that costs time, the
overhead the paper blames for Minotaur's slowness (section 5.2, Figs. 10-11). It reproduces:

- **Doorways are verified where they are, not read off the map** (departure 4 off): ``DoorwayDetection``
  (lines 786-849) makes a gap in a wall (lines 795-821) or a crossing of two walls' lines (lines
  825-847) a Door waypoint (mode ``check-door``, placed as lines 815-816 and 838-840 place it) that
  replaces the robot's current target (lines 817, 842); the gap rule runs only when exactly one wall is
  seen, the crossings otherwise (line 795); each candidate cell is tried once
  (``_previousIntersections``, lines 809-813, 830-836) and the first one already tried ends the search
  (``return``, lines 811, 832); none is looked for while a Door waypoint is active (lines 251-252), and
  otherwise every tick (lines 231-252; ``scan_every`` is ignored). Walls are what 360 rays from the robot
  hit (lines 769-784, ``EdgeDetector.cs`` lines 112-153). On arrival ``AttemptAddDoorway`` (lines
  286-289, 851-889) accepts the doorway if the crossing is seen and the jambs are ``2 doorWidth`` or ``[3, 2 doorWidth]`` cells
  apart (lines 863-864; ``maes_door_width``), and only then stores and auctions it; else it is dropped.
  A wall within VisionRadius - 2 tiles on the bearing to a Door or Corner waypoint drops it (lines
  264-283). Swarm's ``inspect`` targets are off (the Door waypoints replace them).
- **Tried candidates pooled** (issue 49 row 2): with each doorway list the robot sends its tried cells
  (:class:`.messages.Tried`, the heartbeat's ``previousIntersections``, line 169); a robot hearing two or
  more in one tick adds all but the first sender's (lines 173-181, HeartbeatMessage.cs 55).
- **Corner coverage** (``MoveToCornerCoverage``, lines 607-630, ``IsAheadExploreable`` 752-761), tried
  after wall following and before edges, as lines 341-343 order them (mode ``corner``).
- **The nearest doorway before Greed** (lines 336-338, 344-346, ``MovetoNearestDoorway`` 709-719,
  ``GetNearestUnexploredDoorway`` 916-931): when the room is done, the unexplored doorway nearest by path,
  in the room or not, always before the nearest unseen cell (``greedy_if_nearer`` is ignored; mode
  ``door-nearest``), without swarm's skips of doorways with nothing new behind them or claimed by others
  (departures 5 and 9 for doorways).
- **MAES's auction** (issue 49 row 6, :func:`.auction.maes_outcome`, ``BiddingMessage.cs`` 58-86): the
  auctioneer does not bid; with n >= 3 bids the (n + 1) / 2 lowest and the auctioneer go, with n = 2 the
  auctioneer alone (no result is sent), with n <= 1 nobody; the auctioneer marks the doorway explored as
  it goes (lines 73, 80); winners go whatever they are doing (``AuctionResultMessage.cs`` 47-52).
- **Others' destinations as MAES stores them** (issue 49 row 9): a pooled heartbeat records, for each
  later sender, the robot's *own* waypoint (``HeartbeatMessage.cs`` 54, a bug), and Greed excludes those
  1 m tiles (lines 209, 338, 346), not others' real targets; the nearest unseen cell in the room excludes
  nothing (683-707); one wall-following direction (``spin = "split"`` means ``ccw``; no Alg. 2 split).
- **Reported doorways as MAES takes them** (issue 49 row 8, ``DoorwayFoundMessage.cs`` 52-75): a report
  whose way passes a known doorway (the reported one included) is ignored, one with a clear way is
  recorded and bid on from any state, one with no way is only recorded. Doorway lists still merge into
  the receiver's own book (MAES merges them into the first sender's list, ``HeartbeatMessage.cs`` 59-74).

It does not reproduce, on purpose: the runtime's map sharing, navigator and messages stay (departures 1
and 3; MAES's heartbeat merge is the comm option ``map_sharing = "maes"``), so the Door, Corner and
doorway targets are planned, not driven to in a straight line, a Corner goal is the drivable cell next to
the unseen one; wall
following and edges stay swarm's (MAES's ``MoveAlongWall``, lines 393-461, fits segments to ray hits,
``GetWalls`` 512-584, and its edge sweep starts behind the robot, lines 645-646: docs/maes.md section
7.2), and so does the spiral (departure 2; an explicit ``spin = "cw"`` mirrors the corner arc), and
the paper's explored facts (seen from both sides or passed, not MAES's lines 290-294 and heartbeat
exit directions), which travel in doorway lists (MAES's robots share one Doorway object, issue 49 row
7); the grid cannot reproduce MAES's line fitting, so candidates are walked as described in :mod:`.maes`
(nearest first, each checked as itself), and a Door waypoint not reached in ``CHECK_TICKS`` is given up
(MAES's deadlock timer, lines 204-224, is not reproduced).
"""

from __future__ import annotations

import math
import weakref
from typing import Any

import numpy as np

from swarm.api import CELL_M, FREE, SOLID, Action, Observation, RobotInfo, cell_centre, cell_of, grid
from swarm.api.messages import MapUpdate, MessageError

from ..recovery import unseen_near
from . import maes, rooms, walls
from .auction import Auctions
from .cells import clip, line_of_sight, local, mask
from .detection import Pending, cells, scan
from .doorways import Doorway, DoorwayBook
from .messages import AuctionResult, Bid, DoorwayFound, DoorwayList, Heading, Tried, valid_heading
from .params import MinotaurParams
from .peers import Peers

MIN_HOLD_TICKS = 5
"""A greedy target whose unseen cells were seen is kept at least this long (each new target is a replan)."""
OTHERS_FRESH_TICKS = 50
"""Poses of other robots older than this do not count when splitting the spin."""
IDLE_RECHECK_TICKS = 50
APPROACH_M = 1.0
"""A doorway is approached to this far in front of its face before the robot drives through."""
APPROACH_REACH_M = 0.5
CLAIM_FRESH_TICKS = 100
"""A doorway another robot announced it is going through is left to it for this long."""
TARGET_FRESH_TICKS = 30
TARGET_AVOID_M = 3.0
"""Greedy targets keep this far from other robots' current targets (heard within TARGET_FRESH_TICKS)."""
START_MAX_TICKS = 100
VIEW_REACH = 2
"""Cells from a frontier a greedy target may be (swarm.grid's default for a 0.3 m robot)."""
ROOM_WINDOW_CELLS = 48
"""Half-width (cells, 24 m) of the first window the room step searches (``Minotaur._room_target_nearby``);
each further one is twice as wide, up to a quarter of the map."""
PASS_CHECK_M = 3.0
"""Passages through a doorway are watched while the robot is this close to it."""
GREEDY_MODES = ("room-greedy", "greedy")
CHECK_TICKS = 200
"""``variant = "maes"``: a Door waypoint not reached in this many ticks is given up (MAES re-targets a robot
whose position stops changing, its deadlock timer)."""


class Minotaur:
    name = "minotaur"
    Params = MinotaurParams

    # --------------------------------------------------------------------------------- lifecycle ----
    def reset(self, robot: RobotInfo, params: MinotaurParams, rng: np.random.Generator) -> None:
        self.robot = robot
        self.p = params
        self.rng = rng                  # Minotaur is deterministic; kept for the interface's contract
        self.id = robot.id
        self.follow_cells = cells(max(robot.lidar_range - params.follow_margin_m, CELL_M))
        self.edge_cells = round(params.edge_offset_m / CELL_M)
        self.radius_cells = cells(robot.lidar_range + params.lookahead_m)
        self.window_cells = self.radius_cells + self.follow_cells + 4
        # what the robot does
        self.state = "start"
        self.mode = "start"
        self.spin = 1                                            # +1 counter-clockwise, -1 clockwise
        self.target: tuple[float, float] | None = None
        self.anchor: tuple[int, int] | None = None               # the unseen cell(s) the target is for
        self.anchor_box = 0
        self.chosen_at = -10**9
        self.idle_until = -1
        self.travel: tuple[float, float] | None = None           # direction of the last choice (the sweep)
        self.door: Doorway | None = None                         # the doorway of the ``door`` state
        self.door_side = 0
        self.door_phase = ""                                     # approach | through
        # what it knows
        self.book = DoorwayBook()
        self.peers = Peers()
        self.auctions = Auctions(robot.id, params.auction_ticks, params.result_timeout_ticks,
                                 maes=params.variant == "maes")
        self.excluded: dict[tuple[int, int], int] = {}           # cells the navigator failed to reach
        self.inspected: set[tuple[int, int]] = set()             # jambs of gaps already looked at
        self.futile: set[tuple[int, int]] = set()                # anchors still unseen after a visit
        self.last_side: dict[int, int] = {}                      # doorway index -> side the robot was on
        self.passed_log: list[tuple[int, Doorway]] = []
        # variant = "maes" (:mod:`.maes`)
        self.maes = params.variant == "maes"
        self.vision = int(robot.lidar_range)                     # MAES's VisionRadius (tiles = m)
        self.check: maes.Candidate | None = None                 # the Door waypoint being driven to
        self.check_since = 0
        self.tried: set[tuple[int, int]] = set()                 # MAES's _previousIntersections
        self._tried_sent: Tried | None = None                    # the heartbeat's copy of it (_tried_message)
        self.maes_dest: dict[int, tuple[int, int] | None] = {}   # MAES's _otherRobotPositions' destinations
        self._shape = robot.map_shape
        self.checks: list[tuple[int, maes.Candidate, bool]] = []  # (tick, candidate, accepted) on arrival
        # per tick
        self.outbox: list[Any] = []
        self.announce_now = False
        self._tick_cache: dict[str, Any] = {}
        self._obs: Observation | None = None
        self._debug_doors: tuple[int, list[tuple[float, float, int, float, bool]]] = (-1, [])
        self._debug_open: list[int] = []                         # indices whose view says "not explored"

    def act(self, obs: Observation) -> Action:
        self._obs = obs
        self._tick_cache = {}
        self.outbox = []
        if self.travel is None:
            self.travel = (math.cos(obs.pose.theta), math.sin(obs.pose.theta))
        self._read_inbox(obs)
        if self.maes or obs.tick % self.p.scan_every == self.id % self.p.scan_every:
            self._scan(obs)            # MAES scans every tick (MinotaurAlgorithm.cs 231-252, issue 49 row 10)
        self._close_auctions(obs)
        before = self._heading()
        action = self._decide(obs)
        if self.robot.n_robots > 1:
            if obs.tick % self.p.share_every == 0:
                self.outbox.append(DoorwayList(self.id, self.book.wire(), *self._heading()))
                if self.maes:          # the heartbeat's previousIntersections (MinotaurAlgorithm.cs 169)
                    self.outbox.append(self._tried_message())
            elif self.announce_now or before != self._heading():
                self.outbox.append(Heading(self.id, *self._heading()))
        self.announce_now = False
        debug = self._debug()
        self._tick_cache = {}  # its two map-sized spaces would live until the next tick: 43 MB for 64 robots
        return Action(goal=action.goal, velocity=action.velocity, clear_goal=action.clear_goal,
                      messages=tuple(self.outbox), debug=debug, drive=self._drive())

    def _drive(self) -> str:
        """How MAES drives to the target (it matters under ``motion.model = "maes"``): waypoints with
        ``UsePathing`` (greedy targets and doorway passages) along a path, ``PathAndMoveTo``
        (MinotaurAlgorithm.cs 255-262, 701, 715, 738); wall, corner, edge and door-check waypoints in one
        straight move, ``MoveTo`` (284, 493, 625, 657, 818, 843). The default variant plans every target."""
        if not self.maes or self.state == "door" or self.mode in ("room-greedy", "greedy"):
            return "path"
        return "straight"

    # ------------------------------------------------------------------------------------- radio ----
    def _read_inbox(self, obs: Observation) -> None:
        tick = obs.tick
        tried: list[Tried] = []
        for m in obs.inbox:
            if isinstance(m, MapUpdate):
                self.peers.saw(m.sender, m.pose[0], m.pose[1], tick)
            elif not _well_formed(m):
                continue
            elif isinstance(m, (DoorwayList, Heading)):
                self.peers.heard(tick, m, self.book)
            elif isinstance(m, DoorwayFound):
                self._on_found(obs, m)
            elif isinstance(m, Bid):
                self.auctions.receive_bid(tick, m)
            elif isinstance(m, AuctionResult):
                door, _ = self.book.add(Doorway.from_wire(m.door, tick))
                if self.auctions.won(tick, m) and (self.maes or self.state != "door" and not door.explored):
                    self._go_through(door, m.side, "auction")   # MAES: winners go whatever they do
                                                                # (AuctionResultMessage.cs 47-52)
            elif isinstance(m, Tried) and self.maes:
                tried.append(m)
        self._pool_tried(tried)
        self.auctions.expire(tick)

    def _tried_message(self) -> Tried:
        """The heartbeat's tried candidates, sorted. The set only grows, so while its size is unchanged the
        last message is sent again, the same object: a team's pooled set holds thousands of cells, and
        sorting it for every heartbeat and checking it once more in every receiver (a new object) took a
        fifth of a 16-robot MAES run. Receivers get equal cells either way."""
        if self._tried_sent is None or len(self._tried_sent.cells) != len(self.tried):
            self._tried_sent = Tried(self.id, tuple(sorted(self.tried)))
        return self._tried_sent

    def _pool_tried(self, heard: list[Tried]) -> None:
        """MAES pools tried candidates through heartbeats (issue 49 row 2): only with two or more in one tick
        (``Count > 1``, MinotaurAlgorithm.cs 174), the first is combined with each later one in turn
        (176-180), and each ``Combine`` adds the *later* sender's set to the receiver's
        (``minotaur._previousIntersections.UnionWith(heartbeatMessage.previousIntersections)``,
        HeartbeatMessage.cs 55): all but the first sender's, in inbox (sender) order. MAES reads the
        sender's live set; here it is the sender's set as of its heartbeat, a tick older."""
        for m in heard[1:]:
            self.tried.update(m.cells)
            # the same Combine stores the sender's "destination" as the receiver's own waypoint (a MAES bug,
            # HeartbeatMessage.cs 54, issue 49 row 9)
            self.maes_dest[m.sender] = None if self.target is None else clip(cell_of(*self.target), self._shape)

    def _heading(self) -> tuple[tuple[float, float], tuple]:
        """(target or NaNs, the doorway being passed or ()), as heartbeats and headings carry them."""
        target = self.target if self.target is not None else (math.nan, math.nan)
        door = self.door.wire() if self.state == "door" and self.door is not None else ()
        return target, door

    def _on_found(self, obs: Observation, m: DoorwayFound) -> None:
        """Alg. 4 on the receiving side: bid if the doorway is reachable on the auctioneer's side without
        passing another doorway (``variant = "maes"``: :meth:`_on_found_maes`)."""
        if self.maes:
            self._on_found_maes(obs, m)
            return
        door, _ = self.book.add(Doorway.from_wire(m.door, obs.tick))
        mine = self.auctions.running_for(door)
        if mine is not None:
            if m.sender > self.id:
                return                           # ours goes on; the other auctioneer withdraws
            self.auctions.withdraw(obs.tick, mine)
        if door.explored or self.state == "door":
            return
        distance = self._door_distance(obs, door, m.side)
        if math.isfinite(distance):
            self.outbox.append(self.auctions.bid(obs.tick, m, distance))

    def _on_found_maes(self, obs: Observation, m: DoorwayFound) -> None:
        """MAES's ``DoorwayFoundMessage.Process`` (``DoorwayFoundMessage.cs`` 52-75, issue 49 row 8): when the
        robot has a path to the doorway, it ignores the report (no record, no bid) if the path passes a
        doorway it knows, the reported one included (its centre is the path's end, lines 58-63), and else
        records it and bids its path length (65-67); with no path it only records it (69-72). Whatever the
        robot is doing (MAES bids from any state). The path is the robot's plan to either side of the
        doorway; it passes a known doorway when only the map with every known doorway open has it."""
        door = Doorway.from_wire(m.door, obs.tick)
        space, cut = self._spaces(obs)
        here = (obs.pose.x, obs.pose.y)
        if self.book.find(door) is not None:
            return
        start_cut, start = rooms.snap(cut, here), rooms.snap(space, here)
        distance = math.inf
        if start_cut is not None:
            distance = min(rooms.door_distance(cut, start_cut, door, side) for side in (-1, 1))
        if math.isfinite(distance):
            self.book.add(door)
            self.outbox.append(self.auctions.bid(obs.tick, m, distance))
            return
        reachable = start is not None and any(
            math.isfinite(rooms.door_distance(space, start, door, side)) for side in (-1, 1))
        if not reachable:
            self.book.add(door)

    def _close_auctions(self, obs: Observation) -> None:
        for auction, result in self.auctions.close_due(obs.tick):
            if result is not None:
                self.outbox.append(result)
            if self.maes:      # BiddingMessage.cs 71-73, 78-80: the auctioneer goes and marks it explored
                if auction.go_self:
                    self._go_through(auction.door, auction.side, "auction")
                    auction.door.sides = 3
                    self.book.touch()
            elif result is not None and self.id in result.winners and self.state != "door" \
                    and not auction.door.explored:
                self._go_through(auction.door, auction.side, "auction")

    # ---------------------------------------------------------------------------------- doorways ----
    def _scan(self, obs: Observation) -> None:
        """Alg. 3: find doorways around the robot, auction new ones, mark sides seen and passages
        (``variant = "maes"``: find a candidate doorway to drive to and check, :meth:`_find_candidate`)."""
        if self.maes:
            self._find_candidate(obs)
        else:
            for door in self._detected(obs)[0]:
                door.found_tick = obs.tick
                stored, new = self.book.add(door)
                if new:
                    self._announce(obs, stored)
        x, y = obs.pose.x, obs.pose.y
        for k in self.book.near(x, y, self.robot.lidar_range):
            d = self.book.doors[k]
            side = d.side_of(x, y)
            if side == 0:
                continue
            if not d.sides & _bit(side) and line_of_sight(obs.known, (x, y), (d.x, d.y)):
                d.sides |= _bit(side)                      # seen from this side
                self.book.touch()
            if math.hypot(d.x - x, d.y - y) < PASS_CHECK_M and d.in_front(x, y, 1.0):
                if self.last_side.get(k, side) == -side:
                    self._passed(obs.tick, d)
                self.last_side[k] = side

    def _announce(self, obs: Observation, door: Doorway) -> None:
        """Alg. 2 "store & handle doorway": auction it when other robots may be around."""
        if self.robot.n_robots < 2 or self.state == "door" or door.explored:
            return
        side = door.side_of(obs.pose.x, obs.pose.y)
        if side == 0 or self.auctions.running_for(door) is not None:
            return
        own = self._door_distance(obs, door, side)
        if math.isfinite(own):
            self.outbox.append(self.auctions.start(obs.tick, door, side, own))

    def _find_candidate(self, obs: Observation) -> None:
        """MAES's ``DoorwayDetection`` (MinotaurAlgorithm.cs lines 786-849, run every tick in every state
        while no Door or NearestDoor waypoint is active, lines 231-252; here not while passing a doorway,
        the ``door`` state, nor in ``start``): the gap rule when exactly one wall is seen, the crossings
        otherwise (line 795); the candidates are walked nearest first, and the first one tried before or
        inside a known doorway ends the search (``return``, lines 809-812 and 830-833, issue 49 row 1).
        The first new one that is not SOLID (a SOLID one is remembered and passed, lines 834-836) becomes
        the Door waypoint, replacing whatever the robot was doing in its room (``StopCurrentTask``, lines
        817 and 842)."""
        if self.check is not None or self.state in ("start", "door"):
            return
        kw, origin = self._window(obs)
        space, _ = self._spaces(obs)
        for cand in maes.iter_candidates(kw, origin, (obs.pose.x, obs.pose.y), self.vision, self.p.maes_door_width,
                                         by_wall_count=True):
            if cand.key in self.tried or self._in_doorway(cand.key):
                return                                     # MAES lines 809-812, 830-833: stop here
            self.tried.add(cand.key)
            if obs.known[cand.key] == SOLID:
                continue                                   # remembered and skipped (line 834-836)
            goal = rooms.snap(space, cand.goal)
            if goal is None:
                continue                                   # nowhere to drive to (MAES drives on regardless)
            self.check = cand
            self.check_since = obs.tick
            self.state, self.mode = "room", "check-door"
            self._set_target(cell_centre(*goal), None, 0, obs)
            return

    def _in_doorway(self, cell: tuple[int, int]) -> bool:
        """The cell is inside a known doorway's opening (MAES lines 809 and 830: ``doorway.Tiles``)."""
        x, y = cell_centre(*cell)
        for k in self.book.near(x, y, 3.0):
            r0, c0, r1, c1 = self.book.doors[k].cut()
            if r0 <= cell[0] <= r1 and c0 <= cell[1] <= c1:
                return True
        return False

    def _checking(self, obs: Observation) -> Action | None:
        """Drive to the Door waypoint; on arrival ``AttemptAddDoorway`` (MAES lines 286-289, 851-884):
        accept the doorway (store it and auction it, as the default variant does with what it detects) or
        drop it. A SOLID cell ahead on the way (lines 264-283), the navigator giving up, or
        :data:`CHECK_TICKS` without arriving drops it unchecked. None once the check is over."""
        cand = self.check
        assert cand is not None
        x, y = obs.pose.x, obs.pose.y
        if self.target is None or self.mode != "check-door":
            self.check = None
            return None
        arrived = (obs.nav.state == "reached" and obs.nav.goal == self.target) or (
            math.hypot(self.target[0] - x, self.target[1] - y) < APPROACH_REACH_M)
        if arrived:
            self.check = None
            self.target = None
            door = maes.check(obs.known, cand, self.p.maes_door_width)
            self.checks.append((obs.tick, cand, door is not None))
            if door is not None:
                side = door.side_of(x, y)
                door.sides = _bit(side) if side else 0
                door.found_tick = obs.tick
                stored, new = self.book.add(door)
                if new:
                    self._announce(obs, stored)
            return None
        if maes.wall_ahead(obs.known, (x, y), self.target, self.vision) or obs.tick - self.check_since > CHECK_TICKS:
            self.check = None
            self.target = None
            return None
        return Action(goal=self.target)

    def _passed(self, tick: int, door: Doorway) -> None:
        if not door.passed:
            door.passed = True
            self.book.touch()
            self.passed_log.append((tick, door))

    def _door_distance(self, obs: Observation, door: Doorway, side: int) -> float:
        _, cut = self._spaces(obs)
        start = rooms.snap(cut, (obs.pose.x, obs.pose.y))
        if start is None:
            return math.inf
        return rooms.door_distance(cut, start, door, side)

    def _go_through(self, door: Doorway, side: int, why: str) -> None:
        """Go through ``door`` from ``side``: first to a point in front of it, from where the lidar sees
        through (the navigator plans on known cells only), then to a point beyond it."""
        self.state = "door"
        self.mode = why
        self.door = door
        self.door_side = side
        self.door_phase = "approach"
        self.announce_now = True
        self.check = None
        self._set_target(door.point(side, APPROACH_M), None, 0)

    # --------------------------------------------------------------------------------- decisions ----
    def _decide(self, obs: Observation) -> Action:
        nav = obs.nav.state
        tick = obs.tick
        if nav in ("unreachable", "blocked") and self.target is not None and obs.nav.goal == self.target:
            self._exclude(self.target, tick)
            if self.state == "door" and self.door is not None:
                self.door.failed_until = tick + self.p.exclude_ticks
                self.state = "room"
                self.announce_now = True
            self.target = None
        if self.state == "start":
            if tick < START_MAX_TICKS and not self._wall_in_range(obs) and self._ahead_clear(obs):
                return Action(velocity=(self.robot.max_speed, 0.0))
            self.state = "room"
            self._choose_spin(obs)
        if self.state == "door":
            action = self._through_door(obs)
            if action is not None:
                return action
        if self.check is not None:
            action = self._checking(obs)
            if action is not None:
                return action
        elif self.maes and self.mode == "corner" and self.target is not None and maes.wall_ahead(
                obs.known, (obs.pose.x, obs.pose.y), self.target, self.vision):
            if self.anchor is not None:
                self.futile.add(self.anchor)            # MAES drops a direct waypoint with a wall ahead
            self.target = None
        if self._needs_decision(obs):
            if self.anchor is not None and self.target is not None and self._anchor_unseen(obs.known):
                self.futile.add(self.anchor)     # went to look and it is still unseen: an occluded corner
            self._choose(obs)
        if self.target is None:
            return Action(velocity=(0.0, 0.0), clear_goal=True)
        return Action(goal=self.target)

    def _through_door(self, obs: Observation) -> Action | None:
        """The ``door`` state: approach, then pass; None once through (the robot is in a new room)."""
        assert self.door is not None
        door = self.door
        x, y = obs.pose.x, obs.pose.y
        through = door.side_of(x, y) == -self.door_side and door.in_front(x, y, 1.0)
        arrived = (obs.nav.state == "reached" and obs.nav.goal == self.target) or (
            self.target is not None and math.hypot(self.target[0] - x, self.target[1] - y) < APPROACH_REACH_M)
        if through or (arrived and self.door_phase == "through"):
            self._passed(obs.tick, door)
            door.sides |= _bit(-self.door_side)
            self.book.touch()
            self.state = "room"
            self.target = None
            self.announce_now = True
            self._choose_spin(obs)
            return None
        if arrived:
            self.door_phase = "through"
            self._set_target(door.point(-self.door_side, self.p.pass_through_m), None, 0, obs)
        return Action(goal=self.target)

    def _needs_decision(self, obs: Observation) -> bool:
        if self.target is None:
            return obs.tick >= self.idle_until
        age = obs.tick - self.chosen_at
        if obs.nav.state == "reached" and obs.nav.goal == self.target:
            return True
        if math.hypot(self.target[0] - obs.pose.x, self.target[1] - obs.pose.y) < self.p.reach_m:
            return True
        if age >= self.p.recheck_ticks:
            return True
        if self.mode not in GREEDY_MODES:
            return False        # a follow target is a place on the lane: keep going even when its anchor is seen
        return age >= MIN_HOLD_TICKS and not self._anchor_unseen(obs.known)

    def _anchor_unseen(self, known: np.ndarray) -> bool:
        if self.anchor is None:
            return True
        return unseen_near(known, self.anchor, self.anchor_box)

    def _choose(self, obs: Observation) -> None:
        """Alg. 1/2's body: follow in the room, else the nearest unseen in the room, else a doorway in the
        room, else the nearer of a doorway elsewhere and the nearest unseen cell (Greed), else nothing."""
        tick = obs.tick
        self.excluded = {c: t for c, t in self.excluded.items() if t > tick}
        if self._follow_target(obs) is not None:
            return
        here = (obs.pose.x, obs.pose.y)
        room = self._room_target_nearby(obs)
        if room is not None and room[0] is not None:
            self._set_greedy("room", "room-greedy", room[0], obs)
            return
        space, cut = self._spaces(obs)
        blocked = mask(self.excluded, obs.known.shape)
        views = rooms.view_cells(obs.known, space, VIEW_REACH)
        if blocked is not None:
            views &= ~blocked
        if self.maes:          # MAES's "other robots' destinations": its own waypoints (issue 49 row 9)
            avoid = self._own_destinations(obs.known.shape)
        else:
            avoid = self.peers.targets_mask(obs.known.shape, tick, TARGET_FRESH_TICKS, TARGET_AVOID_M)
        start = rooms.snap(cut, here)
        if start is not None and room is None:  # (room: the nearby search found the room empty)
            # MAES's MoveToNearestUnseenWithinRoom excludes door tiles only (683-707)
            room_avoid = None if self.maes else avoid
            found = rooms.nearest_in_room(cut, start, views & ~room_avoid) if room_avoid is not None else None
            if found is None:
                found = rooms.nearest_in_room(cut, start, views)
            if found is not None:
                self._set_greedy("room", "room-greedy", found[0], obs)
                return
        choice = None
        start_any = rooms.snap(space, here)
        if self.maes:          # MAES: the nearest unexplored doorway by path, always before Greed (lines 336-338)
            if start_any is not None:
                near = rooms.nearest_door(space, start_any, self.book.unexplored(tick))
                if near is not None:
                    self._go_through(near[0], near[1], "door-nearest")
                    return
        elif start_any is not None:
            claimed = self.peers.claimed(tick, CLAIM_FRESH_TICKS)
            doors = [d for d in self.book.unexplored(tick) if not any(c.matches(d) for c in claimed)]
            choice = rooms.choose_door(space, cut if start is not None else space, start or start_any, doors, views)
            if choice is not None and choice[2]:
                self._go_through(choice[0], choice[1], "door-in-room")
                return
        cell = clip(cell_of(*here), obs.known.shape)
        exclude = blocked if avoid is None else (avoid if blocked is None else blocked | avoid)
        found = grid.nearest_reachable_unseen(obs.known, cell, radius_m=self.robot.radius, exclude=exclude)
        if found is None and avoid is not None:
            found = grid.nearest_reachable_unseen(obs.known, cell, radius_m=self.robot.radius, exclude=blocked)
        if choice is not None and (found is None or not self.p.greedy_if_nearer or choice[3] <= found[1]):
            self._go_through(choice[0], choice[1], "door-anywhere")
            return
        if found is not None:
            self._set_greedy("greedy", "greedy", found[0], obs)
            return
        self.state, self.mode = "done", "done"
        self.target = None
        self.idle_until = tick + IDLE_RECHECK_TICKS

    def _room_target_nearby(self, obs: Observation) -> tuple[tuple[int, int] | None] | None:
        """The room step of :meth:`_choose` (the nearest view cell in the robot's room, avoiding others'
        targets if possible) decided on windows around the robot: ``(cell,)`` when the room has one,
        ``(None,)`` when it has none (or the robot has no start in the room), None when no window small
        enough decides it (then :meth:`_choose` does it on the whole map).

        Exact: the window's configuration space, door cuts, view cells and masks are the whole map's
        there (computed with the erosion's and the view reach's depth more), and
        ``grid.nearest_reachable_window`` answers only when no path through the rest of the map could
        change the answer. Why: at 256 robots these whole-map rasters, built for every decision, were a
        fifth of Minotaur's cost per robot-tick and grew with the map's area (issue 47); most decisions
        find the room's nearest unseen cell a few metres away."""
        known = obs.known
        h, w = known.shape
        r, c = clip(cell_of(obs.pose.x, obs.pose.y), known.shape)
        depth = grid.erosion_depth(self.robot.radius, grid.DEFAULT_MARGIN_M)
        extra = max(depth, VIEW_REACH + 2)
        half = ROOM_WINDOW_CELLS
        while True:
            r0, r1, c0, c1 = max(r - half, 0), min(r + half + 1, h), max(c - half, 0), min(c + half + 1, w)
            if (r1 - r0) * (c1 - c0) * 4 > h * w:
                return None
            e0, e1, g0, g1 = max(r0 - extra, 0), min(r1 + extra, h), max(c0 - extra, 0), min(c1 + extra, w)
            ext = known[e0:e1, g0:g1]
            inner = (slice(r0 - e0, r1 - e0), slice(c0 - g0, c1 - g0))
            space = grid.configuration_space(ext, radius_m=self.robot.radius)[inner]
            cut = rooms.cut_doors(space, self.book, (r0, c0))
            views = grid.view_cells(ext, VIEW_REACH)[inner] & space
            blocked = mask(self.excluded, space.shape, (r0, c0))
            if blocked is not None:
                views &= ~blocked
            start = grid.nearest_in(cut, (r - r0, c - c0), rooms.SNAP_CELLS)
            if start is None:
                return (None,)
            sides = (r0 > 0, r1 < h, c0 > 0, c1 < w)
            searches = [views]
            if not self.maes:
                avoid = self.peers.targets_mask(space.shape, obs.tick, TARGET_FRESH_TICKS, TARGET_AVOID_M, (r0, c0))
                if avoid is not None:
                    searches.insert(0, views & ~avoid)
            for targets in searches:
                found, decided = grid.nearest_reachable_window(cut, start, targets & cut, sides)
                if not decided:
                    break
                if found is not None:
                    return ((found[0][0] + r0, found[0][1] + c0),)
            else:
                return (None,)
            half *= 2

    def _own_destinations(self, shape: tuple[int, int]) -> np.ndarray | None:
        """MAES's ``_otherRobotDestinations`` (MinotaurAlgorithm.cs 55-58): HeartbeatMessage.cs 54 stores, for each
        later sender of a pooled heartbeat, the *receiver's own* waypoint, so the tiles Greed excludes
        (lines 209, 338, 346) are 1 m tiles where this robot was heading at those heartbeats."""
        cells = [c for c in self.maes_dest.values() if c is not None]
        if not cells:
            return None
        out = np.zeros(shape, dtype=bool)
        for r, c in cells:
            r0, c0 = r - r % 2, c - c % 2                      # the 1 m coarse tile holding the cell
            out[r0:r0 + 2, c0:c0 + 2] = True
        return out

    def _follow_target(self, obs: Observation) -> walls.FollowTarget | None:
        """Alg. 1 "if wall or explored area in visual range && unexplored area ahead: follow it"."""
        kw, origin = self._window(obs)
        cut_w = rooms.cut_doors(grid.configuration_space(kw, radius_m=self.robot.radius), self.book, origin)
        start = grid.nearest_in(cut_w, local(cell_of(obs.pose.x, obs.pose.y), origin, kw.shape), rooms.SNAP_CELLS)
        if start is None:
            return None
        room_dist = grid.distance_field(cut_w, [start])
        inspect: list[tuple[int, int, int, int]] = []
        jambs: dict[tuple[int, int], tuple[int, int]] = {}
        if self.p.inspect_doorways and not self.maes:
            for r, c, dr, dc, jamb in self._detected(obs)[1]:
                if jamb not in self.inspected:
                    inspect.append((r - origin[0], c - origin[1], dr, dc))
                    jambs[(r - origin[0], c - origin[1])] = jamb
        assert self.travel is not None
        blocked, futile = mask(self.excluded, kw.shape, origin), mask(self.futile, kw.shape, origin)
        if self.maes:          # MAES: wall, else corner coverage, else edge (MinotaurAlgorithm.cs lines 341-343)
            ft = walls.choose(kw, cut_w, room_dist, start, self.travel, self.spin, self.radius_cells,
                              self.follow_cells, self.edge_cells, [], blocked, futile, kind=0)
            if ft is None:
                ft = self._corner_target(obs, kw, origin, cut_w, room_dist, blocked)
                if ft is not None:
                    return ft
                ft = walls.choose(kw, cut_w, room_dist, start, self.travel, self.spin, self.radius_cells,
                                  self.follow_cells, self.edge_cells, [], blocked, futile, kind=1)
        else:
            ft = walls.choose(kw, cut_w, room_dist, start, self.travel, self.spin, self.radius_cells,
                              self.follow_cells, self.edge_cells, inspect, blocked, futile)
        if ft is None:
            return None
        if ft.kind == "inspect":
            self.inspected.add(jambs[ft.anchor])
        self.state, self.mode = "room", ("inspect" if ft.kind == "inspect" else "follow-" + ft.kind)
        cell = (ft.cell[0] + origin[0], ft.cell[1] + origin[1])
        self._set_target(cell_centre(*cell), (ft.anchor[0] + origin[0], ft.anchor[1] + origin[1]), 0, obs)
        return ft

    def _corner_target(self, obs: Observation, kw: np.ndarray, origin: tuple[int, int], cut_w: np.ndarray,
                       room_dist: np.ndarray, blocked: np.ndarray | None) -> walls.FollowTarget | None:
        """MAES's ``MoveToCornerCoverage`` (lines 607-630, :func:`.maes.corner`): drive towards the first
        UNSEEN cell a ray over the 30 degrees to the robot's right stops at. The navigator needs a known
        goal, so the target is the drivable cell of the robot's room nearest that cell; rays whose way
        has a wall within VisionRadius - 2 tiles are passed over (MAES would take the waypoint, drop it
        the next tick, line 264-283, and wait for its deadlock timer)."""
        here = (obs.pose.x, obs.pose.y)
        for cell in maes.corner(obs.known, here, obs.pose.theta, self.vision, self.spin):
            if cell in self.futile:
                continue
            at = grid.nearest_in(cut_w, local(cell, origin, kw.shape), rooms.SNAP_CELLS)
            if at is None or not np.isfinite(room_dist[at]) or (blocked is not None and blocked[at]):
                continue
            goal = cell_centre(at[0] + origin[0], at[1] + origin[1])
            if maes.wall_ahead(obs.known, here, goal, self.vision):
                continue
            self.state, self.mode = "room", "corner"
            self._set_target(goal, cell, 0, obs)
            return walls.FollowTarget(at, "corner", (cell[0] - origin[0], cell[1] - origin[1]))
        return None

    def _set_greedy(self, state: str, mode: str, cell: tuple[int, int], obs: Observation) -> None:
        self.state, self.mode = state, mode
        self._set_target(cell_centre(*cell), cell, VIEW_REACH + 1, obs)

    def _set_target(self, xy: tuple[float, float], anchor: tuple[int, int] | None, box: int,
                    obs: Observation | None = None) -> None:
        self.target = (float(xy[0]), float(xy[1]))
        self.anchor = anchor
        self.anchor_box = box
        obs = obs or self._obs
        if obs is not None:
            self.chosen_at = obs.tick
            dx, dy = self.target[0] - obs.pose.x, self.target[1] - obs.pose.y
            n = math.hypot(dx, dy)
            if n > 0.3:
                self.travel = (dx / n, dy / n)

    def _choose_spin(self, obs: Observation) -> None:
        """Alg. 2: half the robots in the room counter-clockwise, half clockwise (by rank of id among the
        robots known to be in the same door-bounded space around the robot)."""
        if self.p.spin != "split" or self.maes:   # MAES has one direction, no split (issue 49 row 9)
            self.spin = -1 if self.p.spin == "cw" else 1
            return
        kw, origin = self._window(obs)
        space_w = rooms.cut_doors(grid.configuration_space(kw, radius_m=self.robot.radius), self.book, origin)
        start = grid.nearest_in(space_w, local(cell_of(obs.pose.x, obs.pose.y), origin, kw.shape), rooms.SNAP_CELLS)
        for nb in obs.neighbours:          # read only here: the runtime builds them lazily
            self.peers.saw(nb.id, nb.x, nb.y, obs.tick)
        ids = [self.id]
        if start is not None:
            dist = grid.distance_field(space_w, [start])
            for j, x, y in self.peers.fresh_poses(obs.tick, OTHERS_FRESH_TICKS):
                r, c = cell_of(x, y)
                inside = 0 <= r - origin[0] < kw.shape[0] and 0 <= c - origin[1] < kw.shape[1]
                cell = grid.nearest_in(space_w, local((r, c), origin, kw.shape), 2)
                if inside and cell is not None and np.isfinite(dist[cell]):
                    ids.append(j)
        self.spin = 1 if sorted(ids).index(self.id) % 2 == 0 else -1

    # ------------------------------------------------------------------------------------- helpers ----
    def _window(self, obs: Observation) -> tuple[np.ndarray, tuple[int, int]]:
        """The knowledge map around the robot (lidar range + look-ahead + follow distance), cached per tick."""
        cached = self._tick_cache.get("window")
        if cached is None:
            r, c = cell_of(obs.pose.x, obs.pose.y)
            h, w = obs.known.shape
            k = self.window_cells
            r0, c0 = max(r - k, 0), max(c - k, 0)
            cached = (obs.known[r0:min(r + k + 1, h), c0:min(c + k + 1, w)], (r0, c0))
            self._tick_cache["window"] = cached
        return cached

    def _detected(self, obs: Observation) -> tuple[list[Doorway], list[Pending]]:
        """Doorways and pending gaps in the window around the robot (cached per tick)."""
        cached = self._tick_cache.get("detected")
        if cached is None:
            kw, origin = self._window(obs)
            cached = scan(kw, self.p.min_door_width_m, self.p.max_door_width_m, self.p.wall_continue_m, origin)
            self._tick_cache["detected"] = cached
        return cached

    def _spaces(self, obs: Observation) -> tuple[np.ndarray, np.ndarray]:
        """The robot's configuration space and the same with every known doorway closed (cached per tick)."""
        cached = self._tick_cache.get("spaces")
        if cached is None:
            space = grid.configuration_space(obs.known, radius_m=self.robot.radius)
            cached = (space, rooms.cut_doors(space, self.book))
            self._tick_cache["spaces"] = cached
        return cached

    def _exclude(self, xy: tuple[float, float], tick: int) -> None:
        r, c = cell_of(*xy)
        for dr in (-1, 0, 1):
            for dc in (-1, 0, 1):
                self.excluded[(r + dr, c + dc)] = tick + self.p.exclude_ticks

    def _wall_in_range(self, obs: Observation) -> bool:
        kw, origin = self._window(obs)
        rr, cc = np.nonzero(kw == SOLID)
        if not rr.size:
            return False
        x = (cc + origin[1] + 0.5) * CELL_M - obs.pose.x
        y = (rr + origin[0] + 0.5) * CELL_M - obs.pose.y
        return bool((x * x + y * y <= self.robot.lidar_range ** 2).any())

    def _ahead_clear(self, obs: Observation) -> bool:
        x, y, th = obs.pose
        for d in (0.5, 1.0, 1.5):
            r, c = cell_of(x + d * math.cos(th), y + d * math.sin(th))
            if not (0 <= r < obs.known.shape[0] and 0 <= c < obs.known.shape[1]) or obs.known[r, c] != FREE:
                return False
        return True

    def _doorways_view(self) -> list[tuple[float, float, int, float, bool]]:
        """Every known doorway as (x, y, axis, width, explored), a new list whenever the book changed.
        Records are only added and only become explored (sides and passed are only ever set), so only
        new records and those not explored last time are looked at again."""
        version, view = self._debug_doors
        if version != self.book.version:
            doors = self.book.doors
            view = list(view)
            still = []
            for k in self._debug_open:
                d = doors[k]
                if d.explored:
                    view[k] = (d.x, d.y, d.axis, d.width, d.explored)
                else:
                    still.append(k)
            for k in range(len(view), len(doors)):
                d = doors[k]
                view.append((d.x, d.y, d.axis, d.width, d.explored))
                if not view[k][4]:
                    still.append(k)
            self._debug_open = still
            self._debug_doors = (self.book.version, view)
        return view

    def _debug(self) -> dict[str, Any]:
        """For the viewer: state and mode, spin, target, the doorway being passed, every known doorway
        (x, y, axis, width, explored) and the auctions this robot runs."""
        out = {"state": self.state, "mode": self.mode, "spin": "ccw" if self.spin > 0 else "cw",
               "target": self.target, "door": self.door.wire() if self.state == "door" and self.door else None,
               "doorways": self._doorways_view(), "auctions": sorted(self.auctions.open)}
        if self.maes:
            out["check"] = None if self.check is None else (self.check.kind, self.check.key, self.target)
        return out


def _well_formed(m: Any) -> bool:
    """A Minotaur message whose fields are safe to use (the codec validates what comes over the wire;
    in-process delivery hands over the sender's object, so check again). A doorway list is checked
    entry by entry when merged, only for the entries that changed: it is the bulk of the traffic.

    In-process, one message object reaches every receiver: a swarm's robot hears hundreds a tick, and
    checking each once per receiver made the checks grow with robots x robots (issue 47). So a message
    found well formed is remembered by identity (it is frozen: it cannot change after the check) and
    not checked again; each receiver gets exactly the answer it would have computed."""
    seen = _VALID.get(id(m))
    if seen is not None and seen() is m:
        return True
    if isinstance(m, DoorwayList):
        ok = isinstance(m.doors, tuple) and valid_heading(m.target, m.door)
    else:
        check = getattr(m, "validate", None)
        if check is None:
            return False
        try:
            check()
            ok = True
        except (MessageError, TypeError, ValueError, AttributeError):
            ok = False
    if ok:
        key = id(m)
        try:
            _VALID[key] = weakref.ref(m, lambda _ref, key=key: _VALID.pop(key, None))
        except TypeError:                       # an object that takes no weak reference: not remembered
            pass
    return ok


_VALID: dict[int, weakref.ref] = {}
"""Messages already found well formed, by identity (frozen: they cannot change after the check); an
entry leaves when its message is collected."""


def _bit(side: int) -> int:
    return 1 if side < 0 else 2
