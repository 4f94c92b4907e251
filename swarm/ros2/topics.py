"""A swarm run as ROS 2 topics, whatever the source: a :class:`TickFrame` holds what one tick of a run has
(built from a recording or from a live simulation by :mod:`swarm.ros2.frames`), and :class:`RunTopics`
turns frames into messages ``(topic, type, message, stamp_ns)`` on the topics :attr:`RunTopics.topics`
lists. The MCAP export (:mod:`swarm.ros2.mcap_export`) and a live publisher share this one translation.

Frames follow REP 105: ``map`` is the fixed frame (the map's corner at the origin, x east, y north), robot
i's body is ``robot_<i>/base_link``. Stamps are sim time, ``tick * tick_s`` (0.1 s), from 0.

===================== ============================== =================================================
topic                 type                           published
===================== ============================== =================================================
/clock                rosgraph_msgs/Clock            every tick
/map                  nav_msgs/OccupancyGrid         once, with the first frame; latched
/tf                   tf2_msgs/TFMessage             every tick: ``map -> robot_<i>/base_link``
/explored, /coverage  std_msgs/Float64               every tick: the run's explored and coverage shares
/robot_<i>/pose       geometry_msgs/PoseStamped      every tick
/robot_<i>/scan       sensor_msgs/LaserScan          every tick (noise-free geometry, below)
/robot_<i>/goal       geometry_msgs/PoseStamped      when the robot's goal changes to a new point
/robot_<i>/map        nav_msgs/OccupancyGrid         every ``map_every`` ticks and at the last, if changed
/robot_<i>/doorways   visualization_msgs/MarkerArray as the maps, if the action's debug lists doorways
/comm/links           visualization_msgs/MarkerArray every tick with links (or to remove the last ones)
/comm/groups          visualization_msgs/MarkerArray every tick with groups (or to remove the last ones)
/comm/lost            visualization_msgs/MarkerArray ticks with failed deliveries
===================== ============================== =================================================

**Knowledge maps** map a robot's cells UNSEEN, FREE, SOLID to -1, 0, 100; the true map is 0 or 100.

**Scans are recomputed.** Recordings hold poses, not scans, so every scan (live runs too, so that both
agree) is the run's lidar geometry (range, field of view, rays) cast by the simulator's own ray code
(:meth:`swarm.world.sensing.Lidar.scan`, ``write=False``) against the true map from the robot's exact pose:
each range is the distance at which the ray enters its first solid cell, ``inf`` without one in range.
That is what the ternary lidar measures; a noisy (log-odds) lidar's noise and other robots hiding walls
(``lidar.robots_occlude``) are not in the scans.

**Markers** are drawn as the replay viewer (``swarm/viewer/viewer.js``) draws them: links in the colour of
the weaker direction's RSSI margin on the viewer's ramp (one-way links thinner, where the viewer dashes
them), communication groups of two or more as their members' hull widened by a robot, in the colour of
the smallest member at 30 %, failed deliveries as a line from the transmitter three quarters of the way to
the robot it missed, ending in a cross, in the cause's colour, for :data:`LOST_TICKS` ticks. Doorways
(Minotaur: ``debug["doorways"]``, entries ``(x, y, axis, width, explored)``) are segments across each
opening in the robot's colour, explored ones faded.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from itertools import pairwise
from typing import Any

import numpy as np

from maps import CELL_M, Map
from swarm.base.errors import InvalidInput

from . import messages as msg

MAP_FRAME = "map"
LOST_TICKS = 6
"""A failed delivery stays drawn this many ticks (the viewer's LOST_TICKS)."""
RAMP = ((0.0, (215, 48, 39)), (10.0, (252, 141, 89)), (20.0, (254, 224, 139)), (30.0, (145, 207, 96)),
        (40.0, (26, 152, 80)))
"""RSSI margin (dB) to link colour: the viewer's RAMP."""
CAUSE_COLOURS = {"link": (200, 0, 0), "loss": (230, 0, 180), "bandwidth": (30, 30, 30),
                 "packet_error": (255, 130, 0)}
"""Failed-delivery colours by cause: the viewer's CAUSE_STYLE (others: :data:`OTHER_CAUSE`)."""
OTHER_CAUSE = (90, 90, 90)
KNOWN_TO_OCCUPANCY = np.array([-1, 0, 100], dtype=np.int8)
"""Knowledge value (UNSEEN, FREE, SOLID) to OccupancyGrid value."""

Doorway = tuple[float, float, int, float, bool]
"""A doorway as Minotaur's debug lists it: centre x, y (m), axis (0: the opening runs along x), width (m),
explored."""
Published = tuple[str, str, Any, int]
"""One message: (topic, type name, rosbags message, stamp in ns of sim time)."""


def base_link(robot: int) -> str:
    """Robot ``robot``'s body frame."""
    return f"robot_{robot}/base_link"


@dataclass(frozen=True)
class Topic:
    """A topic, its ROS 2 type and whether it is latched (transient local: late subscribers get the last
    message)."""

    name: str
    type: str
    latched: bool = False


@dataclass(frozen=True)
class RunInfo:
    """What stays fixed over a run: the true map, the robots, their lidar (a LidarParams) and radios."""

    truth: Map
    n_robots: int
    lidar: Any
    robot_radius_m: float
    sensitivity_dbm: np.ndarray     # float64[R]: receiver sensitivities (the RSSI margin's reference)
    tick_s: float = 0.1


@dataclass(frozen=True)
class Loss:
    """A failed delivery: ``transmitter``'s transmission did not reach ``robot`` because of ``cause``."""

    transmitter: int
    robot: int
    cause: str


@dataclass(frozen=True)
class RobotAction:
    """What a robot's action says that the topics show: its new goal (x, y), whether it dropped its goal,
    and the doorways its debug lists (None: the debug lists none)."""

    goal: tuple[float, float] | None = None
    clear_goal: bool = False
    doorways: tuple[Doorway, ...] | None = None


@dataclass(frozen=True)
class TickFrame:
    """One tick of a run, as observers see it after the tick's decisions (the last tick: after sensing).

    ``actions`` holds the actions decided at this tick, by robot (None: no action, a failed agent); a
    source may leave out robots whose action repeats their previous one, since applying an action twice
    changes nothing. ``losses`` are the failed deliveries of the messages sent at the previous tick (the
    medium has judged them by this tick, whatever ``comm.link_at``)."""

    tick: int
    poses: np.ndarray                   # float64[R, 3]: x, y (m), theta (rad), exact
    known: np.ndarray                   # uint8[R, H, W]: every robot's knowledge map
    link: np.ndarray                    # bool[R, R]: link[i, j], j's message reaches i
    rssi: np.ndarray                    # float64[R, R]: dBm received by i from j (NaN on the diagonal)
    groups: Sequence[frozenset[int]]    # communication groups (radio.LinkState.groups())
    losses: Sequence[Loss]
    actions: Mapping[int, RobotAction | None]
    explored: float
    coverage: float
    final: bool = False                 # the run's last tick: the robot maps are published whatever the rate


def ramp_colour(margin: float) -> tuple[int, int, int]:
    """The viewer's colour of an RSSI margin (dB): red at 0 or below, through yellow, to green at 40."""
    if not margin > RAMP[0][0]:
        return RAMP[0][1]
    for (a, ca), (b, cb) in pairwise(RAMP):
        if margin <= b:
            f = (margin - a) / (b - a)
            return tuple(math.floor(c + f * (d - c) + 0.5) for c, d in zip(ca, cb))  # type: ignore[return-value]
    return RAMP[-1][1]


def convex_hull(points: list[tuple[float, float]]) -> list[tuple[float, float]]:
    """Convex hull of (x, y) points, counter-clockwise (Andrew's monotone chain, as the viewer's)."""
    p = sorted(set(points))
    if len(p) < 3:
        return p

    def half(seq: list[tuple[float, float]]) -> list[tuple[float, float]]:
        out: list[tuple[float, float]] = []
        for q in seq:
            while len(out) >= 2 and ((out[-1][0] - out[-2][0]) * (q[1] - out[-2][1])
                                     - (out[-1][1] - out[-2][1]) * (q[0] - out[-2][0])) <= 0:
                out.pop()
            out.append(q)
        return out

    return half(p)[:-1] + half(p[::-1])[:-1]


class RunTopics:
    """Turns a run's frames, in tick order, into its messages. Stateful: it remembers which robot maps,
    goals, doorways and markers it has published, to publish only changes and remove markers that go."""

    def __init__(self, info: RunInfo, map_every: int = 10) -> None:
        from swarm.draw import ROBOT_COLOURS
        from swarm.world.sensing import Lidar, LidarParams

        if not isinstance(map_every, int) or map_every < 1:
            raise InvalidInput("map_every", map_every, "an integer >= 1 (ticks between robot map messages)")
        self.info = info
        self.map_every = map_every
        n = info.n_robots
        p = info.lidar
        self._lidar = Lidar(info.truth, LidarParams(range_m=p.range_m, fov_deg=p.fov_deg, rays=p.n_rays))
        self._scratch = np.zeros((n, *info.truth.shape), dtype=np.uint8)  # untouched: write=False
        angles = self._lidar.angles
        self._angle_min = float(angles[0])
        self._angle_step = float(angles[1] - angles[0]) if len(angles) > 1 else 0.0
        self._tick_ns = round(info.tick_s * 1e9)
        self._colours = [ROBOT_COLOURS[i % len(ROBOT_COLOURS)] for i in range(n)]
        self._sensitivity = np.asarray(info.sensitivity_dbm, dtype=np.float64)
        self._started = False
        self._maps: list[np.ndarray | None] = [None] * n          # each robot's last published map
        self._goals: list[tuple[float, float] | None] = [None] * n
        self._doorways: list[tuple[Doorway, ...] | None] = [None] * n
        self._doorways_sent: list[tuple[Doorway, ...] | None] = [None] * n
        self._shown: dict[str, set[tuple[str, int]]] = {"/comm/links": set(), "/comm/groups": set()}

    @property
    def topics(self) -> list[Topic]:
        """Every topic a run may publish on (per-robot topics for each robot), in a fixed order."""
        out = [Topic("/clock", msg.CLOCK), Topic("/map", msg.OCCUPANCY_GRID, latched=True),
               Topic("/tf", msg.TF_MESSAGE), Topic("/explored", msg.FLOAT64), Topic("/coverage", msg.FLOAT64),
               Topic("/comm/links", msg.MARKER_ARRAY), Topic("/comm/groups", msg.MARKER_ARRAY),
               Topic("/comm/lost", msg.MARKER_ARRAY)]
        for i in range(self.info.n_robots):
            out += [Topic(f"/robot_{i}/pose", msg.POSE_STAMPED), Topic(f"/robot_{i}/scan", msg.LASER_SCAN),
                    Topic(f"/robot_{i}/goal", msg.POSE_STAMPED), Topic(f"/robot_{i}/map", msg.OCCUPANCY_GRID),
                    Topic(f"/robot_{i}/doorways", msg.MARKER_ARRAY)]
        return out

    def stamp(self, tick: int) -> int:
        """Sim time of ``tick`` in nanoseconds."""
        return tick * self._tick_ns

    def messages(self, frame: TickFrame) -> list[Published]:
        """The messages of ``frame``, in a fixed order (frames must come in tick order, one per tick)."""
        ns = self.stamp(frame.tick)
        n = self.info.n_robots
        out: list[Published] = [("/clock", msg.CLOCK, msg.clock(ns), ns)]
        if not self._started:
            self._started = True
            cells = np.where(self.info.truth.solid, 100, 0).astype(np.int8)
            out.append(("/map", msg.OCCUPANCY_GRID, msg.occupancy_grid(MAP_FRAME, ns, cells, CELL_M), ns))
        poses = frame.poses
        out.append(("/tf", msg.TF_MESSAGE, msg.tf_message(ns, MAP_FRAME, ((base_link(i), *poses[i]) for i in range(n))),
                    ns))
        out.append(("/explored", msg.FLOAT64, msg.float64(frame.explored), ns))
        out.append(("/coverage", msg.FLOAT64, msg.float64(frame.coverage), ns))
        ranges = self._lidar.scan(poses, self._scratch, write=False)
        p = self.info.lidar
        for i in range(n):
            x, y, theta = poses[i]
            out.append((f"/robot_{i}/pose", msg.POSE_STAMPED, msg.pose_stamped(MAP_FRAME, ns, x, y, theta), ns))
            out.append((f"/robot_{i}/scan", msg.LASER_SCAN,
                        msg.laser_scan(base_link(i), ns, ranges[i], self._angle_min, self._angle_step, p.range_m,
                                       self.info.tick_s), ns))
        out += self._actions(frame, ns)
        if frame.tick % self.map_every == 0 or frame.final:
            out += self._maps_of(frame, ns)
        out += self._links(frame, ns)
        out += self._groups(frame, ns)
        out += self._losses(frame, ns)
        return out

    # ----------------------------------------------------------------------------------- robots ----
    def _actions(self, frame: TickFrame, ns: int) -> list[Published]:
        """Take in the frame's actions: a goal message for each robot whose goal became a new point (the
        viewer's current goal: an action's goal, else cleared by ``clear_goal`` or no action, else kept);
        the doorways a debug lists are kept for the next map tick."""
        out: list[Published] = []
        for i in sorted(frame.actions):
            action = frame.actions[i]
            goal = self._goals[i]
            if action is None:
                goal = None
            elif action.goal is not None:
                goal = action.goal
            elif action.clear_goal:
                goal = None
            if action is not None and action.doorways is not None:
                self._doorways[i] = action.doorways
            if goal is not None and goal != self._goals[i]:
                out.append((f"/robot_{i}/goal", msg.POSE_STAMPED, msg.pose_stamped(MAP_FRAME, ns, *goal), ns))
            self._goals[i] = goal
        return out

    def _maps_of(self, frame: TickFrame, ns: int) -> list[Published]:
        out: list[Published] = []
        for i in range(self.info.n_robots):
            known = frame.known[i]
            last = self._maps[i]
            if last is None or not np.array_equal(last, known):
                self._maps[i] = known.copy()
                out.append((f"/robot_{i}/map", msg.OCCUPANCY_GRID,
                            msg.occupancy_grid(MAP_FRAME, ns, KNOWN_TO_OCCUPANCY[known], CELL_M), ns))
            doors = self._doorways[i]
            if doors is not None and doors != self._doorways_sent[i]:
                self._doorways_sent[i] = doors
                out.append((f"/robot_{i}/doorways", msg.MARKER_ARRAY, self._doorway_markers(i, doors, ns), ns))
        return out

    def _doorway_markers(self, robot: int, doors: tuple[Doorway, ...], ns: int) -> Any:
        segments: dict[bool, list[tuple[float, float]]] = {False: [], True: []}
        for x, y, axis, width, explored in doors:
            half = width / 2
            ends = ((x - half, y), (x + half, y)) if axis == 0 else ((x, y - half), (x, y + half))
            segments[explored] += ends
        rgb = self._colours[robot]
        return msg.marker_array([msg.marker(MAP_FRAME, ns, name, 0, msg.LINE_LIST, segments[explored], rgb=rgb,
                                            alpha=0.4 if explored else 1.0, width=0.15, z=0.02)
                                 for name, explored in (("open", False), ("explored", True))])

    # ---------------------------------------------------------------------------- communication ----
    def _replace(self, topic: str, ns: int, markers: dict[tuple[str, int], Any]) -> list[Published]:
        """``markers`` on ``topic``, with a DELETE for each marker shown there before and gone now; nothing
        when there is nothing to show or remove."""
        shown = self._shown[topic]
        gone = sorted(shown - markers.keys())
        self._shown[topic] = set(markers)
        if not markers and not gone:
            return []
        deletes = [msg.marker(MAP_FRAME, ns, space, ident, msg.LINE_LIST, action=msg.DELETE) for space, ident in gone]
        return [(topic, msg.MARKER_ARRAY, msg.marker_array([*markers.values(), *deletes]), ns)]

    def _links(self, frame: TickFrame, ns: int) -> list[Published]:
        link = frame.link
        either = np.triu(link | link.T, 1)
        xy = frame.poses[:, :2]
        lines: dict[str, tuple[list[tuple[float, float]], list[Any]]] = {"two_way": ([], []), "one_way": ([], [])}
        for i, j in zip(*np.nonzero(either)):
            ij, ji = bool(link[i, j]), bool(link[j, i])
            margin = math.inf
            if ij:
                margin = min(margin, frame.rssi[i, j] - self._sensitivity[i])
            if ji:
                margin = min(margin, frame.rssi[j, i] - self._sensitivity[j])
            c = msg.colour(ramp_colour(margin if math.isfinite(margin) else 40.0), 0.85)
            points, colours = lines["two_way" if ij and ji else "one_way"]
            points += [tuple(xy[i]), tuple(xy[j])]
            colours += [c, c]
        markers = {(name, 0): msg.marker(MAP_FRAME, ns, name, 0, msg.LINE_LIST, points, colours, alpha=0.85,
                                         width=0.08 if name == "two_way" else 0.04, z=0.03)
                   for name, (points, colours) in lines.items() if points}
        return self._replace("/comm/links", ns, markers)

    def _groups(self, frame: TickFrame, ns: int) -> list[Published]:
        pad = 2 * self.info.robot_radius_m
        ring = [(pad * math.cos(k * math.pi / 4), pad * math.sin(k * math.pi / 4)) for k in range(8)]
        markers: dict[tuple[str, int], Any] = {}
        for members in frame.groups:
            if len(members) < 2:
                continue
            first = min(members)
            hull = convex_hull([(float(frame.poses[r, 0]) + dx, float(frame.poses[r, 1]) + dy)
                                for r in sorted(members) for dx, dy in ring])
            fan = [v for a, b in pairwise(hull[1:]) for v in (hull[0], a, b)]
            markers[("groups", first)] = msg.marker(MAP_FRAME, ns, "groups", first, msg.TRIANGLE_LIST, fan,
                                                    rgb=self._colours[first], alpha=0.3, width=1.0, z=0.01)
        return self._replace("/comm/groups", ns, markers)

    def _losses(self, frame: TickFrame, ns: int) -> list[Published]:
        if not frame.losses:
            return []
        xy = frame.poses[:, :2]
        by_cause: dict[str, list[tuple[float, float]]] = {}
        for loss in frame.losses:
            sx, sy = xy[loss.transmitter]
            rx, ry = xy[loss.robot]
            ex, ey = sx + 0.75 * (rx - sx), sy + 0.75 * (ry - sy)
            c = 0.175  # half the cross
            by_cause.setdefault(loss.cause, []).extend(
                [(sx, sy), (ex, ey), (ex - c, ey - c), (ex + c, ey + c), (ex + c, ey - c), (ex - c, ey + c)])
        markers = [msg.marker(MAP_FRAME, ns, f"lost/{cause}", frame.tick % LOST_TICKS, msg.LINE_LIST, points,
                              rgb=CAUSE_COLOURS.get(cause, OTHER_CAUSE), width=0.05, z=0.04,
                              lifetime_ns=LOST_TICKS * self._tick_ns)
                   for cause, points in sorted(by_cause.items())]
        return [("/comm/lost", msg.MARKER_ARRAY, msg.marker_array(markers), ns)]


__all__ = ["CAUSE_COLOURS", "KNOWN_TO_OCCUPANCY", "LOST_TICKS", "MAP_FRAME", "RAMP", "Loss", "Published", "RobotAction",
           "RunInfo", "RunTopics", "TickFrame", "Topic", "base_link", "convex_hull", "ramp_colour"]
