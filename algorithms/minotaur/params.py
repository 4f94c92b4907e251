"""Minotaur's parameters, each tied to the paper (Schmidt et al., "Spiralling Human-Inspired Exploration
Algorithm with Doorway Detection", docs/papers.md) or to MAES's implementation (docs/maes.md section 7.2).

Lengths are metres; the knowledge map has 0.5 m cells, so door widths are rounded to whole cells when the
detector runs (a 2 m building door is exactly 4 cells).
"""

from __future__ import annotations

from dataclasses import dataclass, field

from swarm.api import OMIT_DEFAULT, InvalidInput, check_bool, check_choice, check_float, check_int

SPINS = ("split", "ccw", "cw")
VARIANTS = ("swarm", "maes")


@dataclass(frozen=True)
class MinotaurParams:
    """Doorway detection (paper section 3.3, Alg. 3, section 4.3):

    - ``max_door_width_m``: the paper's "maximum width of doors". Generated building doors are 2 m and
      halls 4 m, so 3 m separates them. A gap wider than this is a hallway, not a door.
    - ``min_door_width_m``: Alg. 3 asks the gap to be "greater than robot size"; we ask for a gap the
      runtime's planner can actually pass (3 cells = 1.5 m for the 0.6 m robot with its margin).
    - ``wall_continue_m``: Alg. 3's single-wall case accepts a gap when "the wall continues after" it; this
      is how far the wall face must continue (in a straight line) beyond the gap. The two-wall case asks
      the same length of the perpendicular wall that closes the gap. Cave walls pass this test now and
      then (issue 33, ``benchmarks/experiments/bench_minotaur_doors.py``, 10 seeds of 50 and 100-tile
      caves, 2 and 8 robots, MAES motion: 2.6-3.8 false doorways per 50-tile cave run, 15-17 per
      100-tile run, 9.6 on average; every one a 3 m gap). 2 m cuts that to 2.1 per run and cave runs
      take up to 14 % fewer ticks, with the same building precision and recall, but 50-tile buildings
      with 4-8 robots take 5-9 % more ticks (doors are accepted later, so auctions start later): not
      the default.
    - ``scan_every``: ticks between doorway scans of the map around the robot (1 m of travel; MAES scans every tick
      while no door waypoint is active; the scan is a few microseconds, the cadence only bounds the cost).
      ``variant = "maes"`` ignores it and scans every tick, as MAES does (issue 49 row 10).
    - ``inspect_doorways``: go and look when a wall ends in unseen space within a door width (Alg. 3
      "move forward doorway width" / "move towards intersection point until it is explored").

    Wall following and spiralling (section 3.1, Alg. 1, section 4.2):

    - ``follow_margin_m``: walls are followed at ``lidar_range - follow_margin_m`` ("a little less than
      maximum vision range"; MAES offsets wall targets by VisionRadius - 2 tiles, i.e. 5 m for 7 m).
    - ``edge_offset_m``: how far inside the explored area the robot stays when following the edge of
      explored space (the spiral); small, so that each lap sees as far as possible into the unseen.
    - ``lookahead_m``: candidate wall ends and edges further than ``lidar_range + lookahead_m`` are not
      "in visual range" (Alg. 1's condition); then the robot goes to the nearest unseen cell in the room.
    - ``spin``: ``split`` (Alg. 2: half the robots in the room counter-clockwise, half clockwise, by rank
      of id among the robots known to be in the room), ``ccw`` (Alg. 1, every robot) or ``cw``.

    Doorway auction (section 3.4, Alg. 4):

    - ``auction_ticks``: the auctioneer decides this many ticks after announcing the door (MAES: 3; a bid
      needs 2 ticks to come back, so later bids are lost with the messages that carried them).
    - ``result_timeout_ticks``: a bidder obeys an auction result only this long after it bid; a result
      that arrives later (or never) leaves it exploring its room, which is what a lost result must mean.
    - ``share_every``: ticks between broadcasts of the robot's doorway list (the paper sends doorways with
      the map; the runtime's map-sharing service has its own fixed message type, so the list travels in
      its own message at the map-sharing cadence, 10 ticks by default as MAES's heartbeat).

    Motion bookkeeping (not in the paper):

    - ``recheck_ticks``: re-choose the target at least this often.
    - ``reach_m``: a target counts as reached this close, so the robot chains targets without stopping.
    - ``pass_through_m``: a door is entered by driving to a point this far beyond its line.
    - ``exclude_ticks``: a target the navigator could not reach is avoided this long.
    - ``greedy_if_nearer``: when the robot's room is done and no unexplored doorway is in it, go to the
      nearest unseen cell (Greed) if it is nearer than the nearest unexplored doorway elsewhere; the
      paper (Alg. 1) always prefers the doorway and uses Greed only when no doorway is left. False
      follows the paper.

    MAES parity (issue 33, :mod:`.maes`; left out of a spec at their defaults, so specs and result digests
    of the default variant are unchanged):

    - ``variant``: ``"swarm"`` (default) reads doorways off the map; ``"maes"`` drives to each candidate
      doorway and verifies it on arrival, covers corners and always takes the nearest unexplored doorway
      before Greed, as MAES's ``MinotaurAlgorithm.cs`` does (the explorer's docstring lists what it
      reproduces and what not).
    - ``maes_door_width``: MAES's ``doorWidth`` (tiles); a checked doorway's jambs must be 3 to
      ``2 doorWidth`` SLAM cells apart (MAES line 864).
    """

    max_door_width_m: float = 3.0
    min_door_width_m: float = 1.5
    wall_continue_m: float = 1.0
    scan_every: int = 10
    inspect_doorways: bool = True
    follow_margin_m: float = 2.0
    edge_offset_m: float = 1.0
    lookahead_m: float = 1.5
    spin: str = "split"
    auction_ticks: int = 3
    result_timeout_ticks: int = 20
    share_every: int = 10
    recheck_ticks: int = 30
    reach_m: float = 1.5
    pass_through_m: float = 1.5
    exclude_ticks: int = 300
    greedy_if_nearer: bool = True
    variant: str = field(default="swarm", metadata={OMIT_DEFAULT: True})
    maes_door_width: int = field(default=2, metadata={OMIT_DEFAULT: True})

    def __post_init__(self) -> None:
        check_float("max_door_width_m", self.max_door_width_m, 0.5, 20.0)
        check_float("min_door_width_m", self.min_door_width_m, 0.5, 20.0)
        if self.min_door_width_m > self.max_door_width_m:
            raise InvalidInput("min_door_width_m", self.min_door_width_m,
                               f"at most max_door_width_m ({self.max_door_width_m:g})")
        check_float("wall_continue_m", self.wall_continue_m, 0.5, 10.0)
        check_int("scan_every", self.scan_every, 1, 1000)
        check_bool("inspect_doorways", self.inspect_doorways)
        check_float("follow_margin_m", self.follow_margin_m, 0.0, 50.0)
        check_float("edge_offset_m", self.edge_offset_m, 0.0, 50.0)
        check_float("lookahead_m", self.lookahead_m, 0.0, 50.0)
        check_choice("spin", self.spin, SPINS)
        check_int("auction_ticks", self.auction_ticks, 2, 1000)
        check_int("result_timeout_ticks", self.result_timeout_ticks, 1, 100_000)
        check_int("share_every", self.share_every, 1, 100_000)
        check_int("recheck_ticks", self.recheck_ticks, 1, 100_000)
        check_float("reach_m", self.reach_m, 0.1, 10.0)
        check_float("pass_through_m", self.pass_through_m, 0.5, 10.0)
        check_int("exclude_ticks", self.exclude_ticks, 0, 1_000_000)
        check_bool("greedy_if_nearer", self.greedy_if_nearer)
        check_choice("variant", self.variant, VARIANTS)
        check_int("maes_door_width", self.maes_door_width, 1, 20)
