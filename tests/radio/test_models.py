"""Link models: hand-computed budgets (eqs. 1-2), angles, MAES numbers, LOS / Global, matrices and groups.

Shared arithmetic: L(d) = 17.3 log10(d) + 32.4 + 20 log10(2.4) = 17.3 log10(d) + 40.004225 dB, so
L(20 m) = 22.507819 + 40.004225 = 62.512044 dB; the default radio is 15 dBm tx, -82 dBm sensitivity.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from maps import generate
from radio import RadioConfig, build_link_model
from radio.models import LinkState
from swarm.base.errors import InvalidInput

from .plans import Plan, open_floor, vertical_wall

L20 = 62.512044  # L(20 m) at 2.4 GHz, see the module docstring
A, B = (10.0, 20.25), (30.0, 20.25)  # 20 m apart, across the wall at x in [20, 21) of vertical_wall()


def budget(m, p=A, q=B, **config):
    return build_link_model(m, RadioConfig(**config)).budget(p, q)


@pytest.mark.parametrize("d, rssi", [
    (0.5, -25.004225),   # 15 - L(1 m): distances clamp to 1 m
    (1.0, -25.004225),   # 15 - 40.004225
    (10.0, -42.304225),  # 15 - (17.3 + 40.004225)
    (50.0, -54.396406),  # 15 - (29.392181 + 40.004225)
    (100.0, -59.604225), # 15 - (34.6 + 40.004225)
])
def test_open_space(d, rssi):
    b = budget(open_floor(), (5.0, 10.0), (5.0 + d, 10.0))
    assert b.walls == () and b.wall_db == 0.0
    assert b.rssi_dbm == pytest.approx(rssi, abs=1e-6) and b.link


@pytest.mark.parametrize("material, rssi", [
    ("concrete", -62.512044),  # 15 - 62.512044 - 15
    ("wood", -54.212044),      # 15 - 62.512044 - 6.7
    ("brick", -53.012044),     # 15 - 62.512044 - 5.5
])
def test_one_wall_of_each_material(material, rssi):
    b = budget(vertical_wall(material))
    assert b.distance_m == 20.0 and b.path_loss_db == pytest.approx(L20, abs=1e-6)
    assert b.rssi_dbm == pytest.approx(rssi, abs=1e-6)
    assert b.margin_db == pytest.approx(rssi + 82, abs=1e-6) and b.link


def test_two_different_walls():
    m = Plan(40, 40).wall(15, 0.5, 16, 39.5, "concrete").wall(25, 0.5, 26, 39.5, "wood").build()
    # 15 - 62.512044 - 15 - 6.7 = -69.212044 dBm
    assert budget(m).rssi_dbm == pytest.approx(-69.212044, abs=1e-6)


def test_thick_wall_per_crossing_and_per_metre():
    m = vertical_wall("concrete", thickness_m=3.0)
    # crossing mode: one wall, whatever its thickness: 15 - 62.512044 - 15 = -62.512044
    assert budget(m).rssi_dbm == pytest.approx(-62.512044, abs=1e-6)
    # per-metre mode: 3 m x 15 dB/m (15 dB over the nominal 1 m) = 45 dB: 15 - 62.512044 - 45 = -92.512044
    b = budget(m, wall_mode="per_metre")
    assert b.wall_db == pytest.approx(45.0) and b.rssi_dbm == pytest.approx(-92.512044, abs=1e-6)
    assert not b.link and b.margin_db == pytest.approx(-10.512044, abs=1e-6)


@pytest.mark.parametrize("freq, rssi", [
    (1.3, -55.186686),  # L = 22.507819 + 32.4 + 2.278867 = 57.186686; 15 - 57.186686 - 13
    (5.2, -77.227886),  # L = 22.507819 + 32.4 + 14.320067 = 69.227886; 15 - 69.227886 - 23
    (3.5, -69.692948),  # L = 22.507819 + 32.4 + 10.881361 = 65.789180; concrete 18.903768 (log-f interpolation)
])
def test_frequencies(freq, rssi):
    assert budget(vertical_wall("concrete"), frequency_ghz=freq).rssi_dbm == pytest.approx(rssi, abs=1e-6)


def test_same_wall_same_cost_at_every_angle():
    model = build_link_model(vertical_wall("concrete"))
    for degrees in (0, 15, 30, 45, 60, 75):
        a = math.radians(degrees)
        p = (20.5 - 8 * math.cos(a), 20.13 - 8 * math.sin(a))
        q = (20.5 + 8 * math.cos(a), 20.13 + 8 * math.sin(a))
        b = model.budget(p, q)
        # 16 m apart through one concrete wall: 15 - (17.3 log10 16 + 40.004225) - 15 = -60.835501 dBm
        assert b.rssi_dbm == pytest.approx(-60.835501, abs=1e-6), degrees


def test_per_metre_mode_follows_the_path_length_through_the_wall():
    model = build_link_model(vertical_wall("concrete"), RadioConfig(wall_mode="per_metre"))
    for degrees in (0, 30, 60):
        a = math.radians(degrees)
        p, q = (20.5 - 8 * math.cos(a), 20.3 - 8 * math.sin(a)), (20.5 + 8 * math.cos(a), 20.3 + 8 * math.sin(a))
        # 1 m wall crossed at angle a: 1 / cos(a) metres x 15 dB/m (15, 17.32, 30 dB)
        assert model.budget(p, q).wall_db == pytest.approx(15 / math.cos(a), abs=1e-9)


def test_verdict_flips_where_the_budget_says():
    # 0 dBm tx, -70 dBm sensitivity, one concrete wall: 0 - L(d) - 15 >= -70 <=> L(d) <= 55
    # <=> 17.3 log10(d) <= 55 - 40.004225 = 14.995775 <=> d <= 10^0.866808 = 7.358814 m
    model = build_link_model(vertical_wall("concrete"), RadioConfig(tx_power_dbm=0.0, sensitivity_dbm=-70.0))
    for d in np.arange(2.0, 14.0, 0.01):
        b = model.budget((20.5 - d / 2, 20.25), (20.5 + d / 2, 20.25))
        assert len(b.walls) == 1 and b.link == (d <= 7.358814), d
    assert model.budget((20.5 - 3.679, 20.25), (20.5 + 3.679, 20.25)).link        # d = 7.358
    assert not model.budget((20.5 - 3.68, 20.25), (20.5 + 3.68, 20.25)).link      # d = 7.36


@pytest.mark.parametrize("material, tiles, rssi", [
    ("concrete", 1, -45.0),   # 15 - 4 x 15: docs/maes.md section 6.5
    ("concrete", 2, -105.0),  # 15 - 8 x 15
    ("wood", 1, -11.8),       # 15 - 4 x 6.7
    ("wood", 2, -38.6),       # 15 - 8 x 6.7
    ("wood", 5, -119.0),      # 15 - 20 x 6.7
    ("brick", 1, -7.0),       # 15 - 4 x 5.5
    ("brick", 2, -29.0),      # 15 - 8 x 5.5
    ("brick", 5, -95.0),      # 15 - 20 x 5.5
])
def test_maes_compatible_reproduces_maes(material, tiles, rssi):
    b = budget(vertical_wall(material, thickness_m=float(tiles)), model="maes")
    assert b.rssi_dbm == pytest.approx(rssi, abs=1e-9)
    assert b.link == (rssi >= -82.0)


def test_maes_generic_wall_and_no_distance_term():
    m = Plan(40, 40, ("air", "concrete", "wall")).wall(20, 0.5, 21, 39.5, "wall").build()
    # MAES's generic PGM wall: 0 dB, so 15 dBm through it; LOS is blocked by it all the same
    assert budget(m, model="maes").rssi_dbm == 15.0
    assert not budget(m, model="los").link
    # no distance term: 15 dBm at 1 m and at 100 m in open space
    model = build_link_model(open_floor(), RadioConfig(model="maes"))
    assert model.budget((5, 10), (6, 10)).rssi_dbm == model.budget((5, 10), (105, 10)).rssi_dbm == 15.0


def test_line_of_sight_and_global():
    m = vertical_wall("wood")
    assert not budget(m, model="los").link  # a wall in the way
    assert budget(m, (2, 5), (18, 30), model="los").link  # same side of the wall
    los = build_link_model(open_floor(), RadioConfig(model="los", max_range_m=10.0))
    assert los.budget((5, 10), (14.9, 10)).link and los.budget((5, 10), (15.0, 10)).link
    assert not los.budget((5, 10), (15.1, 10)).link  # 10.1 m > max range
    g = budget(vertical_wall("concrete", thickness_m=10.0), model="global")
    assert g.link and g.rssi_dbm == 15.0  # always linked; RSSI is the sender's power


def test_matrices_orientation_and_per_robot_overrides():
    # robots 0 and 1 are 50 m apart in open space: L = 69.396406 dB
    config = RadioConfig(tx_power_overrides={1: -20.0})
    state = build_link_model(open_floor(), config).evaluate(np.array([[5.0, 10.0], [55.0, 10.0]]))
    # rssi[i, j]: received by i from j. From robot 0 (15 dBm): -54.396406; from robot 1 (-20 dBm): -89.396406
    assert state.rssi[1, 0] == pytest.approx(-54.396406, abs=1e-6)
    assert state.rssi[0, 1] == pytest.approx(-89.396406, abs=1e-6)
    assert state.link[1, 0] and not state.link[0, 1]  # 1 hears 0; 0 cannot hear 1 (below -82 dBm)
    assert np.isnan(state.rssi[0, 0]) and not state.link[0, 0]
    assert state.groups() == [frozenset({0}), frozenset({1})]  # strong: no two-way exchange
    assert state.groups("weak") == [frozenset({0, 1})]
    # a sensitivity override on the receiver side: robot 1 needs -50 dBm, so it no longer hears 0 either
    both = build_link_model(open_floor(), RadioConfig(sensitivity_overrides={"1": -50.0}))
    assert not both.evaluate(np.array([[5.0, 10.0], [55.0, 10.0]])).link[1, 0]


def test_symmetric_for_equal_radios_and_groups():
    m = generate("building", 60, seed=2)
    model = build_link_model(m)
    rng = np.random.default_rng(2)
    free = np.argwhere(m.free)
    xy = (free[rng.choice(len(free), 16)][:, ::-1] + 0.5) * 0.5
    state = model.evaluate(xy)
    assert np.array_equal(state.rssi, state.rssi.T, equal_nan=True)
    assert np.array_equal(state.link, state.link.T) and np.array_equal(state.walls, state.walls.T)
    assert state.walls.dtype == np.int32 and state.walls.max() > 0
    # every member of a group reaches every other over links; no link joins two groups
    groups = state.groups()
    assert sorted(i for g in groups for i in g) == list(range(16))
    label = {i: k for k, g in enumerate(groups) for i in g}
    for i, j in zip(*np.nonzero(state.link)):
        assert label[i] == label[j]
    # the matrices agree with the one-pair budget
    b = model.budget(xy[3], xy[7])
    assert state.rssi[7, 3] == pytest.approx(b.rssi_dbm) and state.walls[7, 3] == len(b.walls)
    # material_walls counts the charged crossings per material
    assert state.material_walls[7, 3].sum() == sum(len(w.charged) for w in b.walls)


def test_rssi_never_increases_with_distance_in_open_space():
    model = build_link_model(open_floor())
    xy = np.column_stack((np.linspace(5.0, 115.0, 200), np.full(200, 10.0)))
    rssi = model.evaluate(xy).rssi[1:, 0]  # received from robot 0 by robots further and further away
    assert np.all(np.diff(rssi) <= 0)
    rssi_field, _ = model.field((5.0, 10.0), xy[1:])
    assert np.array_equal(rssi_field, rssi)


def test_evaluate_is_cached_and_read_only():
    model = build_link_model(open_floor())
    xy = np.array([[5.0, 10.0], [15.0, 10.0], [25.0, 12.0]])
    first = model.evaluate(xy)
    assert model.evaluate(xy.copy()) is first
    assert not first.rssi.flags.writeable and not first.link.flags.writeable
    assert model.evaluate(xy + 0.1) is not first


def _robots_in_free_cells(m, n: int, rng: np.random.Generator) -> np.ndarray:
    """``n`` positions (x, y metres) at random points of random free cells of ``m``."""
    free = np.argwhere(~m.solid)
    return (free[rng.integers(0, len(free), n)][:, ::-1] + rng.random((n, 2))) * 0.5


@pytest.mark.parametrize("kind, seed", [("building", 4), ("cave", 5)])
def test_in_sight_is_evaluate_restricted_to_pairs_in_range(kind, seed):
    """The in-range walk gives evaluate's distances bit for bit and its ``walls == 0`` within the range."""
    m = generate(kind, 40, seed)
    model = build_link_model(m)
    rng = np.random.default_rng(seed)
    for trial in range(20):
        n = int(rng.integers(1, 20))
        xy = _robots_in_free_cells(m, n, rng)
        if trial % 4 == 0:
            xy[n // 2:] = xy[0]  # robots on the same spot
        state = model.evaluate(xy)
        for reach in (0.0, 3.0, 7.0, 12.5, math.inf):
            distance, clear = model.in_sight(xy, reach)
            assert distance.view(np.int64).tolist() == state.distance.view(np.int64).tolist()
            expected = (state.distance <= reach) & (state.walls == 0)
            np.fill_diagonal(expected, False)
            assert np.array_equal(clear, expected)


@pytest.mark.parametrize("kind, seed", [("building", 6), ("cave", 7)])
def test_sight_index_near_is_in_sights_row_within_the_range(kind, seed):
    """The bucketed query gives in_sight's clear robots nearer than the range, in robot order, with its
    distances bit for bit: crowds on one spot, robots on bucket edges, ranges past the sensing range."""
    m = generate(kind, 60, seed)
    model = build_link_model(m)
    rng = np.random.default_rng(seed)
    for trial in range(12):
        n = int(rng.integers(2, 120))
        xy = _robots_in_free_cells(m, n, rng)
        if trial % 3 == 0:
            xy[n // 2:] = xy[0] + rng.random((n - n // 2, 2)) * 2.0  # a packed crowd
        if trial % 3 == 1:
            xy = np.round(xy / 2.0) * 2.0  # on the buckets' edges
        for reach in (3.0, 7.0):
            distance, clear = model.in_sight(xy, reach)
            index = model.sight_index(xy, reach)
            for row in range(n):
                for range_m in (0.0, 1.2, 2.0, 4.5, 10.0):
                    cols, dist = index.near(row, range_m)
                    want = np.flatnonzero(clear[row])
                    want = want[distance[row, want] < range_m]
                    assert cols.tolist() == want.tolist()
                    assert dist.view(np.int64).tolist() == distance[row, want].view(np.int64).tolist()


@pytest.mark.parametrize("positions, value", [
    ([[5.0, 10.0], [130.0, 10.0]], [130.0, 10.0]),
    ([[5.0, 10.0], [float("nan"), 10.0]], [float("nan"), 10.0]),
    ([[-0.1, 10.0]], [-0.1, 10.0]),
])
def test_positions_outside_the_map_are_errors(positions, value):
    with pytest.raises(InvalidInput) as err:
        build_link_model(open_floor()).evaluate(np.array(positions))
    assert err.value.field == "positions" and "inside the map" in err.value.allowed
    assert str(err.value.value) == str(value)


def test_unknown_map_material_fails_at_build_time_unless_configured():
    m = Plan(40, 40, ("air", "concrete", "plaster")).wall(20, 0.5, 21, 39.5, "plaster").build()
    with pytest.raises(InvalidInput) as err:
        build_link_model(m)
    assert err.value.field == "material" and err.value.value == "plaster"
    # defined in the config: 4 dB per crossing: 15 - 62.512044 - 4 = -51.512044
    assert budget(m, materials={"plaster": 4.0}).rssi_dbm == pytest.approx(-51.512044, abs=1e-6)


def test_groups_match_networkx_components():
    import networkx as nx

    rng = np.random.default_rng(3)
    for _ in range(50):
        link = rng.random((9, 9)) < 0.2
        np.fill_diagonal(link, False)
        zeros = np.zeros((9, 9))
        state = LinkState(zeros, zeros.astype(np.int32), np.zeros((9, 9, 1), np.int32), ("air",), zeros, zeros,
                          zeros, link)
        graph = state.graph()
        for mode, fn in (("strong", nx.strongly_connected_components), ("weak", nx.weakly_connected_components)):
            expected = sorted((frozenset(c) for c in fn(graph)), key=min)
            assert state.groups(mode) == expected


@pytest.mark.parametrize("n", [1, 2, 5, 16, 40])
def test_groups_are_the_components_networkx_finds(n):
    import networkx as nx

    rng = np.random.default_rng(n)
    for density in (0.0, 0.05, 0.15, 0.4, 1.0):
        link = rng.random((n, n)) < density
        np.fill_diagonal(link, False)
        z = np.zeros((n, n))
        state = LinkState(z, z.astype(np.int32), np.zeros((n, n, 1), np.int32), ("air",), z, z, z, link)
        graph = nx.DiGraph()
        graph.add_nodes_from(range(n))
        graph.add_edges_from((int(j), int(i)) for i, j in zip(*np.nonzero(link)))  # link[i, j]: i hears j
        strong = sorted((frozenset(c) for c in nx.strongly_connected_components(graph)), key=min)
        weak = sorted((frozenset(c) for c in nx.weakly_connected_components(graph)), key=min)
        assert state.groups() == strong
        assert state.groups("weak") == weak


@pytest.mark.parametrize("config", [
    {}, {"wall_mode": "per_metre"}, {"model": "maes"}, {"model": "los", "max_range_m": 25.0}, {"model": "global"},
    {"tx_power_dbm": -5.0, "tx_power_overrides": {"2": 20.0}, "sensitivity_overrides": {"5": -95.0}},
])
def test_link_columns_are_the_evaluated_columns(config):
    # the runtime asks only for the senders' columns on ticks that need nothing else of the radio
    m = generate("building", 60, 3)
    rng = np.random.default_rng(11)
    free = np.argwhere(~m.solid)
    differs = 0
    for _ in range(25):
        n = int(rng.integers(2, 12))
        cells = free[rng.choice(len(free), n, replace=False)]
        xy = (cells[:, ::-1] + rng.random((n, 2))) * 0.5
        senders = rng.choice(n, int(rng.integers(1, n + 1)), replace=False)
        fresh = build_link_model(m, RadioConfig(**config))
        got = fresh.link_columns(xy, senders)                  # walked pair by pair
        state = fresh.evaluate(xy)
        assert got.dtype == bool and np.array_equal(got, state.link[:, senders])
        assert np.array_equal(fresh.link_columns(xy, senders), got)  # from the evaluated state now
        differs += int(not state.link.all() and state.link.any())
    assert differs >= 5 or config.get("model") == "global"


def test_link_columns_reject_bad_senders_and_positions():
    model = build_link_model(generate("building", 30, 1))
    xy = np.array([[5.0, 5.0], [10.0, 10.0]])
    with pytest.raises(InvalidInput, match="senders"):
        model.link_columns(xy, [2])
    with pytest.raises(InvalidInput, match="positions"):
        model.link_columns(np.array([[5.0, 5.0], [-1.0, 3.0]]), [0])


@pytest.mark.parametrize("config", [{}, {"model": "los", "max_range_m": 20.0}, {"model": "maes"}, {"model": "global"},
                                    {"tx_power_overrides": {"3": 5.0}, "sensitivity_overrides": {"7": -70.0}},
                                    {"shadowing_sigma_db": 4.0}, {"wall_mode": "per_metre"}, {"sensitivity_dbm": -95.0}])
@pytest.mark.parametrize("kind", ["building", "cave"])
def test_the_link_matrix_alone_is_the_states(config, kind):
    """LinkModel.link_matrix (each pair walked once, no float planes, walks stopped once their walls rule
    the link out), link_columns (stopped likewise) and LinkModel.distances give the bits of evaluate()'s
    link and distance: every model, asymmetric radios, shadowing, per-metre walls, robots spread over a
    map (long walks through many walls)."""
    from maps import generate
    from radio import build_link_model, config_from_mapping
    from swarm.world.spawn import spawn

    truth = generate(kind, 150, 3)
    for seed in range(3):
        xy = spawn(truth, "random", 30, np.random.default_rng(seed))[:, :2]
        alone = build_link_model(truth, config_from_mapping(config), field_seed=1).link_matrix(xy)
        senders = np.random.default_rng(seed).choice(30, 6, replace=False)
        columns = build_link_model(truth, config_from_mapping(config), field_seed=1).link_columns(xy, senders)
        state = build_link_model(truth, config_from_mapping(config), field_seed=1).evaluate(xy)
        assert alone.dtype == bool and np.array_equal(alone, state.link)
        assert np.array_equal(columns, state.link[:, senders])
        assert 0 < state.link.sum() < 30 * 29 or config.get("model") == "global"
        assert np.array_equal(build_link_model(truth).distances(xy), state.distance)


@pytest.mark.parametrize("config", [{}, {"model": "los", "max_range_m": 20.0}, {"model": "maes"}, {"model": "global"},
                                    {"tx_power_overrides": {"3": 5.0}, "sensitivity_overrides": {"7": -70.0}},
                                    {"shadowing_sigma_db": 4.0}, {"wall_mode": "per_metre"}, {"sensitivity_dbm": -95.0},
                                    {"sensitivity_dbm": -70.0}])
@pytest.mark.parametrize("kind", ["building", "cave"])
@pytest.mark.parametrize("spawn_kind", ["random", "together"])
def test_the_groups_alone_are_the_states(config, kind, spawn_kind):
    """LinkModel.groups (pairs judged only until their robots are joined, when links hold both ways) gives
    evaluate()'s groups: every model, asymmetric radios and shadowing (which take the link matrix), robots
    spread (many small groups) or gathered (one or a few)."""
    from maps import generate
    from radio import build_link_model, config_from_mapping
    from swarm.world.spawn import spawn

    truth = generate(kind, 150, 3)
    sizes = set()
    for seed in range(3):
        xy = spawn(truth, spawn_kind, 40, np.random.default_rng(seed))[:, :2]
        alone = build_link_model(truth, config_from_mapping(config), field_seed=1).groups(xy)
        state = build_link_model(truth, config_from_mapping(config), field_seed=1).evaluate(xy)
        assert alone == state.groups()
        sizes.add(len(alone))
    strong = config.get("model") == "global" or config.get("sensitivity_dbm") == -95.0  # one group anywhere
    assert sizes != {1} or strong or spawn_kind == "together"


@pytest.mark.parametrize("config", [{"sensitivity_dbm": -52.0}, {"tx_power_dbm": -10.0, "sensitivity_dbm": -75.0},
                                    {"tx_power_overrides": {"3": 20.0}, "sensitivity_dbm": -50.0},
                                    {"model": "los", "max_range_m": 15.0},
                                    {"wall_mode": "per_metre", "sensitivity_dbm": -52.0}])
def test_robots_beyond_the_radios_reach_are_not_judged_and_nothing_changes(config):
    """Issue 47: a link budget bounds the distance of any link (walls only add loss), so the link matrix
    and columns judge only pairs in neighbouring buckets of that size; every bit is evaluate()'s, on a
    map many buckets wide, with a stronger transmitter that widens the reach."""
    from maps import generate
    from radio import build_link_model, config_from_mapping
    from swarm.world.spawn import spawn

    truth = generate("building", 300, 2)
    model = build_link_model(truth, config_from_mapping(config))
    xy = spawn(truth, "random", 150, np.random.default_rng(4))[:, :2]
    tx, sens = model._radio_arrays(150)
    reach = model.reach(tx, sens)
    assert reach < truth.width_m / 4, "the case must use the buckets"
    state = build_link_model(truth, config_from_mapping(config)).evaluate(xy)
    assert np.array_equal(model.link_matrix(xy), state.link)
    senders = np.arange(0, 150, 7)
    assert np.array_equal(build_link_model(truth, config_from_mapping(config)).link_columns(xy, senders),
                          state.link[:, senders])
    d = state.distance[state.link]
    assert state.link.sum() > 20 and d.max() <= reach, "links exist, and none beyond the reach"
