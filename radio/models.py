"""Link models: positions -> distance, walls, RSSI and link matrices, behind one interface.

Orientation: ``rssi[i, j]`` is the power (dBm) robot ``i`` receives from transmitter ``j``, and
``link[i, j]`` is True iff a message sent by ``j`` reaches ``i`` (Minotaur paper eq. 2 with ``S_i`` the
receiver's sensitivity and ``T_j`` the sender's power). The diagonal is ``link = False`` and ``rssi = NaN``
(a robot does not receive its own messages; docs/maes.md section 6.1). Geometry (distance, walls) is symmetric; RSSI
and links are symmetric for equal radios and can be asymmetric with per-robot overrides.

- :class:`MultiWall` (default): ``rssi = Ptx_j - L(d, f) - sum(A_wall)`` (eqs. 1-2), walls charged per
  crossing (or per metre with ``wall_mode = "per_metre"``).
- :class:`MaesCompatible`: MAES's material model (docs/maes.md section 6.2): no distance term,
  ``rssi = Ptx_j - sum(A_material * wall_length / 0.25 m)``. MAES charges per triangle of its mesh (4 per
  tile crossed at right angles); per 0.25 m of wall path reproduces its right-angle numbers (section 6.5)
  without its dependence on the crossing angle.
- :class:`LineOfSight`: linked iff no wall is crossed (and ``d <= max_range_m`` if set); ``rssi`` is the
  sender's power where linked and ``-inf`` where not (the model has no propagation physics).
- :class:`Global`: always linked; ``rssi`` is the sender's power (MAES reports 15 dBm in open space).

With ``shadowing_sigma_db > 0`` (``multiwall`` and ``maes``) every RSSI also loses the link's log-normal
shadowing ``S(p, q)`` read from the map's seeded field (:mod:`radio.shadowing`) and links are judged on
that; ``per`` gives the curve the runtime draws packet errors from (:mod:`radio.per`,
:attr:`LinkModel.packet_errors`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import cached_property
from typing import ClassVar, Sequence

import networkx as nx
import numpy as np
from numba import njit

from maps.model import Map
from swarm.base.errors import InvalidInput

from .config import RadioConfig
from .crossings import (WallCrossing, WallRaster, _radio_bucket_robots, _radio_clear_near, _radio_clear_within,
                        _radio_price_runs)
from .evaluate import (ALPHA, BETA, CHARGED, DISTANCE, FREQ_TERM, MAX_RANGE, PATH_LOSS, RSSI, _radio_distances,
                       _radio_evaluate, _radio_first_outside, _radio_groups_mutual, _radio_link_all, _radio_link_columns,
                       _radio_link_columns_only)
from .materials import resolve_table
from .pathloss import GLOBAL, LOS, MAES, MIN_DISTANCE_M, MULTIWALL, _radio_link_budget
from .per import PacketErrorCurve
from .shadowing import ShadowingField, _radio_shadow_links

_NO_ROWS = np.empty((0, 0))
"""Tells :func:`radio.evaluate._radio_link_columns` that only the links are wanted."""
MAES_CELL_M = 0.25
"""MAES charges a material once per mesh triangle; a tile crossed at right angles is 4 triangles (1 m / 4)."""

Point = Sequence[float]


@dataclass(eq=False)
class LinkState:
    """The radio picture for one set of robot positions (arrays are read-only; not a frozen dataclass only
    because frozen construction costs microseconds on the per-tick path).

    ``walls[i, j]``: wall crossings (maximal solid runs) between i and j; ``material_walls[i, j, m]``: how
    many of them charged material ``materials[m]``. ``path_loss_db`` (eq. 1) and ``wall_db`` are what the
    model charged (0 where it has no such term); ``shadowing_db`` the shadowing subtracted from ``rssi``
    (None when the model has none).
    """

    distance: np.ndarray
    walls: np.ndarray
    material_walls: np.ndarray
    materials: tuple[str, ...]
    path_loss_db: np.ndarray
    wall_db: np.ndarray
    rssi: np.ndarray
    link: np.ndarray
    shadowing_db: np.ndarray | None = None

    @property
    def n_robots(self) -> int:
        return int(self.distance.shape[0])

    def groups(self, connectivity: str = "strong") -> list[frozenset[int]]:
        """Communication groups, sorted by their smallest member.

        ``"strong"`` (default): robots that can each reach every other one over directed multi-hop links,
        i.e. can exchange information both ways; with symmetric links this is the ordinary connected
        components. ``"weak"``: connected when link direction is ignored.
        """
        if connectivity not in ("strong", "weak"):
            raise InvalidInput("connectivity", connectivity, "'strong' | 'weak'")
        cached = self._groups.get(connectivity)
        if cached is None:
            cached = self._groups[connectivity] = groups_of(self.link, connectivity)
        return list(cached)

    @cached_property
    def _groups(self) -> dict[str, list[frozenset[int]]]:
        return {}

    def graph(self) -> nx.DiGraph:
        """The links as a networkx graph: an edge j -> i where j's message reaches i."""
        graph = nx.DiGraph()
        graph.add_nodes_from(range(self.n_robots))
        receivers, senders = np.nonzero(self.link)
        graph.add_edges_from(zip(senders.tolist(), receivers.tolist()))
        return graph

    def all_connected(self) -> bool:
        """Every robot can reach every other (one strong group); MAES's "all connected" statistic."""
        return len(self.groups()) <= 1


def groups_of(link: np.ndarray, connectivity: str = "strong") -> list[frozenset[int]]:
    """The communication groups of a link matrix (``link[i, j]``: j's message reaches i), sorted by their
    smallest member: :meth:`LinkState.groups`."""
    # Components of the sender -> receiver links in one compiled pass (Tarjan): the partition networkx
    # gives (tested); building a scipy sparse matrix took ~400 us for 16 robots, and this runs every
    # recorded tick.
    adjacency = link.T | link if connectivity == "weak" else link.T
    labels = _component_labels(np.ascontiguousarray(adjacency, dtype=np.bool_)).tolist()
    members: list[list[int]] = [[] for _ in range(max(labels, default=-1) + 1)]
    for robot, label in enumerate(labels):  # one pass (a numpy pass per group cost ~3 us each)
        members[label].append(robot)
    return [frozenset(group) for group in members]


@dataclass(frozen=True)
class LinkBudget:
    """One link, transmitter ``p`` -> receiver ``q``, itemised as eqs. 1-2 (for the CLI and reports)."""

    model: str
    distance_m: float
    walls: tuple[WallCrossing, ...]
    path_loss_db: float
    wall_db: float
    tx_power_dbm: float
    rssi_dbm: float
    sensitivity_dbm: float
    link: bool
    shadowing_db: float = 0.0

    @property
    def margin_db(self) -> float:
        """RSSI above sensitivity (negative: short by that much)."""
        return self.rssi_dbm - self.sensitivity_dbm


class LinkModel:
    """Turns robot positions into a :class:`LinkState`; built once per run with :func:`build_link_model`.

    Subclasses only name their model and how walls are priced; eqs. 1-2 for every model run in one numba
    kernel (:func:`radio.pathloss._radio_link_budget`), shared by :meth:`evaluate`, :meth:`budget` and
    :meth:`field`.
    """

    name: ClassVar[str] = ""
    code: ClassVar[int] = -1
    prices_walls: ClassVar[bool] = True
    """False for models that only count walls (LOS, Global): :meth:`trace` then reports 0 dB per wall."""

    def __init__(self, truth: Map, config: RadioConfig, field_seed: int | None = None) -> None:
        """``field_seed``: the seed of the map's shadowing field (default: the map's own seed, else 0); a run
        passes its map seed, so every run on a map meets the same field."""
        if type(self) is LinkModel:
            raise TypeError("LinkModel is abstract; use build_link_model")
        self.config = config
        self.truth = truth
        self.raster = WallRaster.from_map(truth)
        table = resolve_table(truth.materials, config.material_table())
        f = config.frequency_ghz
        self.materials: tuple[str, ...] = truth.materials
        self.cross_db = np.array([0.0] + [m.crossing_db(f) for m in table[1:]])
        self.metre_db = self._metre_db(np.array([0.0] + [m.per_metre_db(f) for m in table[1:]]))
        self.per_metre = self._per_metre()
        self.tol = config.graze_tolerance_m
        self._freq_term = 10.0 * config.gamma * math.log10(f)
        self._max_range = math.inf if config.max_range_m is None else config.max_range_m
        self._params = np.array([self.raster.cell_m, truth.width_m, truth.height_m, self.tol, config.alpha,
                                 config.beta, self._freq_term, self._max_range])
        self._radios: dict[int, tuple[np.ndarray, np.ndarray]] = {}
        self._last_key: bytes | None = None
        self._last_state: LinkState | None = None
        self.shadowing: ShadowingField | None = None
        if config.shadowing_sigma_db > 0.0:
            seed = field_seed if field_seed is not None else (truth.seed if truth.seed is not None else 0)
            self.shadowing = ShadowingField(truth.width_m, truth.height_m, config.shadowing_corr_m, seed)
        self.packet_errors: PacketErrorCurve | None = (
            PacketErrorCurve(config.per_ref, config.per_ref_bytes) if config.per != "off" else None)
        """The packet error curve the runtime applies to every delivery, None when ``per = "off"``."""

    # ------------------------------------------------------------------ model-specific pieces
    def _metre_db(self, table_metre_db: np.ndarray) -> np.ndarray:
        return table_metre_db

    def _per_metre(self) -> bool:
        return self.config.wall_mode == "per_metre"

    def _budget(self, distance: np.ndarray, walls: np.ndarray, wall_db: np.ndarray, tx: np.ndarray,
                sens: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """(path_loss_db, wall_db charged, rssi, link) for [receiver, transmitter] arrays."""
        shape = distance.shape
        path_loss = np.empty(shape)
        charged = np.empty(shape)
        rssi = np.empty(shape)
        link = np.empty(shape, dtype=np.bool_)
        c = self.config
        _radio_link_budget(self.code, distance, walls, wall_db, tx, sens, c.alpha, c.beta, self._freq_term,
                           self._max_range, False, path_loss, charged, rssi, link)
        return path_loss, charged, rssi, link

    def _radio_arrays(self, n_robots: int) -> tuple[np.ndarray, np.ndarray]:
        if n_robots not in self._radios:
            self._radios[n_robots] = (self.config.tx_power_array(n_robots),
                                      self.config.sensitivity_array(n_robots))
        return self._radios[n_robots]

    # --------------------------------------------------------------------------- public API
    def evaluate(self, positions: np.ndarray, *, tx_power_dbm: np.ndarray | None = None,
                 sensitivity_dbm: np.ndarray | None = None) -> LinkState:
        """The link state for robots at ``positions`` (float64[R, 2], x and y in metres).

        ``tx_power_dbm`` / ``sensitivity_dbm`` (float64[R]) replace the config's per-robot values for this
        call. Calling again with the same inputs returns the same (read-only) state without recomputing.
        """
        xy = np.ascontiguousarray(positions, dtype=np.float64)
        if xy.ndim != 2 or xy.shape[1] != 2:
            raise InvalidInput("positions", xy.shape, "an array of shape (R, 2): x, y in metres")
        r = xy.shape[0]
        tx, sens = self._radio_arrays(r)
        if tx_power_dbm is not None:
            tx = _per_robot_values("tx_power_dbm", tx_power_dbm, r)
        if sensitivity_dbm is not None:
            sens = _per_robot_values("sensitivity_dbm", sensitivity_dbm, r)
        key = xy.tobytes() + tx.tobytes() + sens.tobytes()
        if key == self._last_key and self._last_state is not None:
            return self._last_state
        out = np.empty((5, r, r))
        walls = np.empty((r, r), dtype=np.int32)
        counts = np.empty((r, r, len(self.materials)), dtype=np.int32)
        link = np.empty((r, r), dtype=np.bool_)
        bad = _radio_evaluate(self.raster.blocks, xy, self._params, self.cross_db, self.metre_db, self.per_metre,
                              self.code, tx, sens, out, walls, counts, link)
        if bad >= 0:
            raise self._outside("positions", xy[bad])
        shadow = None
        if self.shadowing is not None:
            values = self.shadowing.at(xy)
            shadow = np.empty((r, r))
            _radio_shadow_links(values, values, np.arange(r), out[DISTANCE], self.config.shadowing_sigma_db,
                                self.shadowing.corr_m, sens, out[RSSI], link, shadow)
            shadow.setflags(write=False)
        for array in (out, walls, counts, link):
            array.setflags(write=False)  # the planes of `out` below are views, read-only with it
        state = LinkState(out[DISTANCE], walls, counts, self.materials, out[PATH_LOSS], out[CHARGED], out[RSSI], link,
                          shadow)
        self._last_key, self._last_state = key, state
        return state

    def link_columns(self, positions: np.ndarray, senders: Sequence[int]) -> np.ndarray:
        """``link[:, senders]`` of :meth:`evaluate` (bool[R, len(senders)]: who hears each sender), walking
        only the pairs with a sender: on a tick when a few robots send and nothing else needs the radio
        picture, that is a few walks instead of all R (R - 1) / 2 pairs. The same numbers bit for bit (the
        same walk and budget kernels, each pair walked from its lower index)."""
        xy = np.ascontiguousarray(positions, dtype=np.float64)
        if xy.ndim != 2 or xy.shape[1] != 2:
            raise InvalidInput("positions", xy.shape, "an array of shape (R, 2): x, y in metres")
        r = xy.shape[0]
        which = np.asarray(senders, dtype=np.int64)
        if which.ndim != 1 or (which.size and (which.min() < 0 or which.max() >= r)):
            raise InvalidInput("senders", list(np.ravel(which)), f"robot indices 0..{r - 1}")
        tx, sens = self._radio_arrays(r)
        if self._last_state is not None and self._last_key == xy.tobytes() + tx.tobytes() + sens.tobytes():
            return self._last_state.link[:, which]
        if self.shadowing is not None:
            return self._columns(xy, which, tx, sens)[0]
        link = np.empty((r, which.size), dtype=np.bool_)
        bad = _radio_link_columns_only(self.raster.blocks, self.raster.free_ids, xy, self._params, self.cross_db,
                                       self.metre_db, self.per_metre, self.code, tx, sens, which, self.reach(tx, sens),
                                       link)
        if bad >= 0:
            raise self._outside("positions", xy[bad])
        return link

    def reach(self, tx: np.ndarray, sens: np.ndarray) -> float:
        """Metres beyond which no link can hold whatever the walls, or ``inf``: for the multi-wall model the
        distance at which eq. 1's path loss alone uses up the best budget (the strongest transmitter to the
        most sensitive receiver), since walls only add loss; for line of sight its range. Slightly widened
        (1e-6 relative) so that rounding never drops a pair the budget keeps: a bound for skipping pairs,
        never a link decision (:func:`radio.evaluate._pair_link` still judges every pair within it)."""
        walls_add = bool((self.cross_db >= 0).all() and (self.metre_db >= 0).all())
        if self.code == LOS:
            limit = float(self._params[MAX_RANGE])
        elif self.code == MULTIWALL and walls_add and len(tx) and float(self._params[ALPHA]) > 0.0:
            budget = float(tx.max()) - float(sens.min()) - float(self._params[BETA]) - float(self._params[FREQ_TERM])
            exponent = budget / (10.0 * float(self._params[ALPHA]))
            limit = math.inf if exponent > 300 else max(10.0 ** exponent, MIN_DISTANCE_M)
        else:
            return math.inf
        return limit * (1.0 + 1e-6) + 1e-6 if math.isfinite(limit) else math.inf

    def link_matrix(self, positions: np.ndarray) -> np.ndarray:
        """:meth:`evaluate`'s ``link`` alone (bool[R, R]), bit for bit: each pair walked once, none of the
        other matrices built (they take 61 bytes a pair: 6 GB for 10,000 robots). What delivery to every
        robot and the groups need. With shadowing the whole state is evaluated (its draws are per pair)."""
        xy = np.ascontiguousarray(positions, dtype=np.float64)
        if xy.ndim != 2 or xy.shape[1] != 2:
            raise InvalidInput("positions", xy.shape, "an array of shape (R, 2): x, y in metres")
        r = xy.shape[0]
        tx, sens = self._radio_arrays(r)
        if self.shadowing is not None or (self._last_state is not None
                                          and self._last_key == xy.tobytes() + tx.tobytes() + sens.tobytes()):
            return self.evaluate(xy).link
        link = np.empty((r, r), dtype=np.bool_)
        bad = _radio_link_all(self.raster.blocks, self.raster.free_ids, xy, self._params, self.cross_db,
                              self.metre_db, self.per_metre, self.code, tx, sens, self.reach(tx, sens), link)
        if bad >= 0:
            raise self._outside("positions", xy[bad])
        return link

    def groups(self, positions: np.ndarray) -> list[frozenset[int]]:
        """:meth:`LinkState.groups` of the robots at ``positions``, the same sets. With one transmit power and
        one sensitivity (links hold both ways or neither) and no shadowing, pairs are judged only until their
        robots are joined (:func:`radio.evaluate._radio_groups_mutual`): a gathered swarm of 1,000 judges
        ~1,000 pairs, not 500,000. Otherwise the groups of :meth:`link_matrix`."""
        xy = np.ascontiguousarray(positions, dtype=np.float64)
        if xy.ndim != 2 or xy.shape[1] != 2:
            raise InvalidInput("positions", xy.shape, "an array of shape (R, 2): x, y in metres")
        tx, sens = self._radio_arrays(xy.shape[0])
        if (self.shadowing is not None or xy.shape[0] < 2 or np.any(tx != tx[0]) or np.any(sens != sens[0])
                or (self._last_state is not None and self._last_key == xy.tobytes() + tx.tobytes() + sens.tobytes())):
            return groups_of(self.link_matrix(xy))  # (a state evaluated for these positions: its link)
        labels = np.empty(xy.shape[0], dtype=np.int64)
        bad = _radio_groups_mutual(self.raster.blocks, self.raster.free_ids, xy, self._params, self.cross_db,
                                   self.metre_db, self.per_metre, self.code, tx, sens, labels)
        if bad >= 0:
            raise self._outside("positions", xy[bad])
        members: list[list[int]] = [[] for _ in range(int(labels.max()) + 1)]
        for robot, label in enumerate(labels.tolist()):
            members[label].append(robot)
        return [frozenset(group) for group in members]

    @staticmethod
    def distances(positions: np.ndarray) -> np.ndarray:
        """:meth:`evaluate`'s ``distance`` matrix (float64[R, R]), bit for bit, without walking any wall."""
        xy = np.ascontiguousarray(positions, dtype=np.float64)
        out = np.empty((xy.shape[0], xy.shape[0]))
        _radio_distances(xy, out)
        return out

    def margin_columns(self, positions: np.ndarray, senders: Sequence[int]) -> tuple[np.ndarray, np.ndarray]:
        """``(link, margin)`` for the columns ``senders``: :meth:`link_columns` and each pair's margin, RSSI
        minus the receiver's sensitivity in dB (float64[R, len(senders)]; NaN for a robot and itself), as
        :meth:`evaluate` gives them: what packet errors are drawn from."""
        xy = np.ascontiguousarray(positions, dtype=np.float64)
        r = xy.shape[0]
        which = np.asarray(senders, dtype=np.int64)
        tx, sens = self._radio_arrays(r)
        if self._last_state is not None and self._last_key == xy.tobytes() + tx.tobytes() + sens.tobytes():
            state = self._last_state
            return state.link[:, which], state.rssi[:, which] - sens[:, None]
        link, rssi = self._columns(xy, which, tx, sens)
        return link, rssi - sens[:, None]

    def _columns(self, xy: np.ndarray, which: np.ndarray, tx: np.ndarray,
                 sens: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """``(link, rssi)`` of the pairs with a sender in ``which`` (checked), shadowing applied."""
        r = xy.shape[0]
        link = np.empty((r, which.size), dtype=np.bool_)
        rssi = np.empty((r, which.size))
        distance = np.empty((r, which.size))
        bad = _radio_link_columns(self.raster.blocks, xy, self._params, self.cross_db, self.metre_db,
                                  self.per_metre, self.code, tx, sens, which, link, rssi, distance)
        if bad >= 0:
            raise self._outside("positions", xy[bad])
        if self.shadowing is not None:
            values = self.shadowing.at(xy)
            _radio_shadow_links(values, values[which], which, distance, self.config.shadowing_sigma_db,
                                self.shadowing.corr_m, sens, rssi, link, np.empty((r, which.size)))
        return link, rssi

    def in_sight(self, positions: np.ndarray, max_distance: float) -> tuple[np.ndarray, np.ndarray]:
        """``(distance, clear)`` for robots at ``positions`` (float64[R, 2]): the pair distances (bit for bit
        :meth:`evaluate`'s) and ``clear[i, j]``, i != j at most ``max_distance`` apart with no wall crossed
        (``evaluate``'s ``walls == 0``). Walks only the pairs within range: what sensing neighbours needs,
        without the all-pairs radio picture. Positions are not checked (callers pass robot poses)."""
        xy = np.ascontiguousarray(positions, dtype=np.float64)
        r = xy.shape[0]
        distance = np.empty((r, r))
        clear = np.empty((r, r), dtype=np.bool_)
        _radio_clear_within(self.raster.blocks, self.raster.cell_m, xy, self.tol, self.cross_db.shape[0],
                            float(max_distance), distance, clear)
        return distance, clear

    def sight_index(self, positions: np.ndarray, max_distance: float) -> "SightIndex":
        """Robots at ``positions`` (float64[R, 2]) bucketed for :meth:`SightIndex.near`: the robots near one
        robot that :meth:`in_sight` would give, without its (R, R) matrices. Positions are not checked."""
        return SightIndex(self, positions, max_distance)

    def trace(self, p: Point, q: Point) -> list[WallCrossing]:
        """The walls crossed from ``p`` to ``q`` in order, each with its materials, lengths and dB charged."""
        p = self._check_point(p, "p")
        q = self._check_point(q, "q")
        start, end, lengths = self.raster.trace(p, q, self.tol)
        out = []
        for k in range(start.shape[0]):
            counts = np.zeros((1, 1, len(self.materials)), dtype=np.int32)
            db = _radio_price_runs(1, lengths[k:k + 1], self.tol, self.cross_db, self.metre_db, self.per_metre,
                                   counts, 0, 0)
            mats = tuple((self.materials[m], float(lengths[k, m])) for m in range(1, len(self.materials))
                         if lengths[k, m] > 0.0)
            charged = tuple(self.materials[m] for m in np.nonzero(counts[0, 0])[0])
            db = db if self.prices_walls else 0.0
            out.append(WallCrossing(float(start[k]), float(end[k]), mats, charged, float(db)))
        return out

    def crossings(self, p: Point, q: Point) -> list[tuple[str, float]]:
        """``(material, metres of wall path)`` for every material of every wall crossed from p to q."""
        return [pair for wall in self.trace(p, q) for pair in wall.materials]

    def budget(self, p: Point, q: Point, *, tx_power_dbm: float | None = None,
               sensitivity_dbm: float | None = None) -> LinkBudget:
        """The itemised link budget from transmitter ``p`` to receiver ``q``."""
        tx = self.config.tx_power_dbm if tx_power_dbm is None else tx_power_dbm
        sens = self.config.sensitivity_dbm if sensitivity_dbm is None else sensitivity_dbm
        rssi, link, path_loss, charged, distance, shadow = self._one_to_many(
            p, np.asarray([q], dtype=np.float64), "q", tx, sens)
        return LinkBudget(self.name, float(distance[0]), tuple(self.trace(p, q)), float(path_loss[0]),
                          float(charged[0]), float(tx), float(rssi[0]), float(sens), bool(link[0]), float(shadow[0]))

    def field(self, p: Point, targets: np.ndarray, *, tx_power_dbm: float | None = None,
              sensitivity_dbm: float | None = None) -> tuple[np.ndarray, np.ndarray]:
        """(rssi, link) at every target (float64[N, 2]) for one transmitter at ``p`` (heatmaps)."""
        tx = self.config.tx_power_dbm if tx_power_dbm is None else tx_power_dbm
        sens = self.config.sensitivity_dbm if sensitivity_dbm is None else sensitivity_dbm
        rssi, link, _, _, _, _ = self._one_to_many(p, targets, "targets", tx, sens)
        return rssi, link

    def _one_to_many(self, p: Point, targets: np.ndarray, name: str, tx: float,
                     sens: float) -> tuple[np.ndarray, ...]:
        tx = _finite("tx_power_dbm", tx)
        sens = _finite("sensitivity_dbm", sens)
        targets = self._check_positions(targets, name)
        src = self._check_point(p, "p")
        distance, walls, wall_db = self.raster.one_to_many(src, targets, self.tol, self.cross_db, self.metre_db,
                                                           self.per_metre)
        n = targets.shape[0]
        sens_rx = np.full(n, sens)
        path_loss, charged, rssi, link = self._budget(distance.reshape(n, 1), walls.reshape(n, 1),
                                                      wall_db.reshape(n, 1), np.full(1, tx), sens_rx)
        shadow = np.zeros((n, 1))
        if self.shadowing is not None:
            _radio_shadow_links(self.shadowing.at(targets), self.shadowing.at(np.array([src])), np.full(1, -1),
                                np.ascontiguousarray(distance.reshape(n, 1)), self.config.shadowing_sigma_db,
                                self.shadowing.corr_m, sens_rx, rssi, link, shadow)
        return rssi[:, 0], link[:, 0], path_loss[:, 0], charged[:, 0], distance, shadow[:, 0]

    # ---------------------------------------------------------------------------- checks
    def _check_positions(self, positions: object, name: str) -> np.ndarray:
        xy = np.ascontiguousarray(positions, dtype=np.float64)
        if xy.ndim != 2 or xy.shape[1] != 2:
            raise InvalidInput(name, xy.shape, "an array of shape (R, 2): x, y in metres")
        bad = _radio_first_outside(xy, self.truth.width_m, self.truth.height_m)
        if bad >= 0:
            raise self._outside(name, xy[bad])
        return xy

    def _outside(self, name: str, point: np.ndarray) -> InvalidInput:
        return InvalidInput(name, point.tolist(), f"finite points inside the map: 0 <= x < {self.truth.width_m:g}, "
                                                  f"0 <= y < {self.truth.height_m:g}")

    def _check_point(self, p: Point, name: str) -> tuple[float, float]:
        xy = self._check_positions(np.asarray(p, dtype=np.float64).reshape(1, -1), name)
        return float(xy[0, 0]), float(xy[0, 1])


def _finite(name: str, value: object) -> float:
    try:
        v = float(value)  # type: ignore[arg-type]
    except (TypeError, ValueError):
        raise InvalidInput(name, value, "a finite number of dBm") from None
    if not math.isfinite(v):
        raise InvalidInput(name, value, "a finite number of dBm")
    return v


def _per_robot_values(name: str, values: object, n_robots: int) -> np.ndarray:
    out = np.ascontiguousarray(values, dtype=np.float64)
    if out.shape != (n_robots,) or not np.isfinite(out).all():
        raise InvalidInput(name, values, f"{n_robots} finite dBm values, one per robot")
    return out


class MultiWall(LinkModel):
    """Eq. 1 path loss plus each crossed wall's material attenuation (eq. 2): the default model."""

    name = "multiwall"
    code = MULTIWALL


class MaesCompatible(LinkModel):
    """MAES's material model: no distance term, each material charged per 0.25 m of wall path."""

    name = "maes"
    code = MAES

    def _metre_db(self, table_metre_db: np.ndarray) -> np.ndarray:
        return self.cross_db / MAES_CELL_M

    def _per_metre(self) -> bool:
        return True


class LineOfSight(LinkModel):
    """Linked iff no wall is crossed (and, optionally, the distance is at most ``max_range_m``)."""

    name = "los"
    code = LOS
    prices_walls = False


class Global(LinkModel):
    """Every message reaches every other robot."""

    name = "global"
    code = GLOBAL
    prices_walls = False


MODEL_CLASSES: dict[str, type[LinkModel]] = {c.name: c for c in (MultiWall, MaesCompatible, LineOfSight, Global)}


def build_link_model(truth: Map, config: RadioConfig | None = None, field_seed: int | None = None) -> LinkModel:
    """The link model ``config.model`` for the map ``truth`` (resolves materials: unknown ones are errors);
    ``field_seed`` seeds its shadowing field (see :class:`LinkModel`)."""
    config = config or RadioConfig()
    return MODEL_CLASSES[config.model](truth, config, field_seed)


@njit(cache=True)
def _component_labels(adjacency: np.ndarray) -> np.ndarray:  # pragma: no cover - compiled
    """Strongly connected components of the directed graph ``adjacency[a, b]`` (an edge a -> b), labelled
    0, 1, ... in the order of their smallest member. Tarjan's algorithm without recursion: every edge is
    looked at once, so a dense matrix costs n^2 reads (the reachability closure it replaces cost n^3: 8 %
    of a 1,000-robot run)."""
    n = adjacency.shape[0]
    index = np.full(n, -1, np.int64)
    low = np.zeros(n, np.int64)
    on_stack = np.zeros(n, np.bool_)
    stack = np.empty(n, np.int64)
    call = np.empty(n, np.int64)      # the DFS path
    cursor = np.zeros(n, np.int64)    # the next neighbour to look at, per vertex on the path
    comp = np.full(n, -1, np.int64)
    top = 0
    counter = 0
    found = 0
    for root in range(n):
        if index[root] >= 0:
            continue
        depth = 0
        call[0] = root
        index[root] = low[root] = counter
        counter += 1
        stack[top] = root
        top += 1
        on_stack[root] = True
        while depth >= 0:
            v = call[depth]
            w = cursor[v]
            row = adjacency[v]
            while w < n and not (row[w] and (index[w] < 0 or on_stack[w])):
                w += 1
            if w < n:
                cursor[v] = w + 1
                if index[w] < 0:
                    index[w] = low[w] = counter
                    counter += 1
                    stack[top] = w
                    top += 1
                    on_stack[w] = True
                    depth += 1
                    call[depth] = w
                elif index[w] < low[v]:
                    low[v] = index[w]
                continue
            cursor[v] = n
            if low[v] == index[v]:  # v roots a component: pop it
                while True:
                    top -= 1
                    u = stack[top]
                    on_stack[u] = False
                    comp[u] = found
                    if u == v:
                        break
                found += 1
            depth -= 1
            if depth >= 0:
                parent = call[depth]
                if low[v] < low[parent]:
                    low[parent] = low[v]
    labels = np.full(n, -1, np.int64)
    relabel = np.full(found, -1, np.int64)
    count = 0
    for i in range(n):  # components in the order of their smallest member
        c = comp[i]
        if relabel[c] < 0:
            relabel[c] = count
            count += 1
        labels[i] = relabel[c]
    return labels


class SightIndex:
    """One tick's robots in square buckets, for the robots near one robot: :meth:`near` gives, bit for bit,
    the columns of :meth:`LinkModel.in_sight`'s row that are clear and nearer than a range, and their
    distances, looking only at the buckets within that range. A check such as "is anyone right behind me"
    then costs the robots around, not the (R, R) matrices (1,000 robots: a million pairs a tick)."""

    SIDE_M = 2.0
    """The buckets' side: a few robots each in a packed crowd."""

    def __init__(self, model: LinkModel, positions: np.ndarray, max_distance: float) -> None:
        self._model = model
        self._xy = np.ascontiguousarray(positions, dtype=np.float64)
        self._max = float(max_distance)
        n = self._xy.shape[0]
        top = self._xy.max(axis=0) if n else np.zeros(2)
        self._gx = max(int(math.ceil(max(float(top[0]), 0.0) / self.SIDE_M)) + 1, 1)
        self._gy = max(int(math.ceil(max(float(top[1]), 0.0) / self.SIDE_M)) + 1, 1)
        self._order = np.empty(n, dtype=np.int64)
        self._starts = np.zeros(self._gx * self._gy + 1, dtype=np.int64)
        _radio_bucket_robots(self._xy, self.SIDE_M, self._gx, self._gy, self._order, self._starts)
        self._cols = np.empty(n, dtype=np.int64)
        self._dist = np.empty(n, dtype=np.float64)

    def near(self, row: int, range_m: float) -> tuple[np.ndarray, np.ndarray]:
        """``(cols, distances)``: the robots j != ``row`` in sight of it (as :meth:`LinkModel.in_sight` with
        this index's ``max_distance``) and nearer than ``range_m`` (finite), in robot order."""
        raster = self._model.raster
        count = _radio_clear_near(raster.blocks, raster.cell_m, self._xy, self._model.tol,
                                  self._model.cross_db.shape[0], self._max, int(row), float(range_m), self.SIDE_M,
                                  self._gx, self._gy, self._order, self._starts, self._cols, self._dist)
        return self._cols[:count].copy(), self._dist[:count].copy()
