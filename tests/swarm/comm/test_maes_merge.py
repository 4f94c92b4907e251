"""The runtime's MAES-parity options reproduce MAES's behaviour on hand-built cases: its heartbeat merge
(Greed, Minotaur) and its TNF sync, link judgement at receipt, and its wall pricing."""

from __future__ import annotations

import numpy as np
import pytest

from maps import Map
from radio import build_link_model, config_from_mapping
from swarm.comm.maes_merge import MaesMerge, MapHeartbeat
from swarm.comm.medium import CommSpec
from swarm.sim.loop import Simulation

from tests.conftest import box_map
from tests.swarm.agents import Leaver


def maps(n: int) -> np.ndarray:
    """n knowledge maps of 4 x 4 cells, robot i having seen only cell (i, i)."""
    known = np.zeros((n, 4, 4), np.uint8)
    for i in range(n):
        known[i, i, i] = 1
    return known


def beats(*pairs: tuple[int, list[int]]) -> list:
    return [(MapHeartbeat(sender=s, tick=10), receivers) for s, receivers in pairs]


def test_one_heartbeat_merges_nothing_two_merge_the_senders_not_the_receiver():
    """MAES Greed.cs line 112 / MinotaurAlgorithm.cs line 174: a merge needs two heartbeats in one tick, and
    it synchronises the senders' maps with each other; the receiver's own map is left as it was."""
    merge = MaesMerge(3, "maes_heartbeat", 10)
    known = maps(3)
    before = known.copy()
    assert merge.receive(beats((0, [1])), known, np.ones(3, bool)) == set()
    assert (known == before).all(), "two robots never share maps in MAES"
    changed = merge.receive(beats((0, [2]), (1, [2])), known, np.ones(3, bool))
    assert changed == {0, 1}
    union = np.maximum(before[0], before[1])
    assert (known[0] == union).all() and (known[1] == union).all()
    assert (known[2] == before[2]).all(), "the receiver's map is unchanged"


def test_heartbeat_merge_is_pairwise_in_order_so_a_middle_sender_gets_part_of_the_union():
    """Issue 49 row 12: MinotaurAlgorithm.cs 176-180 (Greed.cs 114-118) combine the first heartbeat with each
    later one in turn, each Combine synchronising two maps (HeartbeatMessage.cs 56-57, Greed.cs 254-255):
    with senders 0, 1, 2 heard by robot 3, robots 0 and 2 end with the union, robot 1 with 0 | 1 only."""
    merge = MaesMerge(4, "maes_heartbeat", 10)
    known = maps(4)
    before = known.copy()
    changed = merge.receive(beats((0, [3]), (1, [3]), (2, [3])), known, np.ones(4, bool))
    assert changed == {0, 1, 2} and merge.merges == 2
    union = np.maximum.reduce(before[[0, 1, 2]])
    assert (known[0] == union).all() and (known[2] == union).all()
    assert (known[1] == np.maximum(before[0], before[1])).all() and known[1, 2, 2] == 0, "sender 1 misses 2's cell"
    assert (known[3] == before[3]).all()


def test_tnf_sync_the_highest_id_broadcaster_merges_everyone():
    """MAES TnfExplorationAlgorithm.AwaitCommunication: a broadcaster none of whose senders has a higher id
    synchronises its own map with the senders' maps; others do nothing; a robot that did not broadcast
    does not read."""
    merge = MaesMerge(4, "maes_sync", 20)
    near = np.zeros((4, 4), bool)
    near[0, 1] = near[1, 0] = near[1, 2] = near[2, 1] = True  # robot 3 senses nobody: it does not broadcast
    out = merge.outgoing(20, lambda: near)
    assert [len(o) for o in out] == [1, 1, 1, 0]
    known = maps(4)
    before = known.copy()
    merge.receive(beats((0, [1, 3]), (1, [0, 2, 3]), (2, [1, 3])), known, np.ones(4, bool))
    union = np.maximum.reduce(before[[1, 2]])
    assert (known[1] == union).all() and (known[2] == union).all(), "robot 2 merged with robot 1, its only sender"
    # robot 1 heard 0 and 2: 2 is higher, so robot 1 did not merge robot 0 in; robot 0 heard 1 (higher)
    assert (known[0] == before[0]).all() and (known[3] == before[3]).all(), "robot 3 did not broadcast: no read"
    assert merge.outgoing(21, lambda: near) == [[], [], [], []], "every share_every ticks only"


def test_a_run_with_two_robots_never_merges_under_the_heartbeat_rule():
    spec = {"seed": 2, "map": {"kind": "building", "size": 30}, "robots": {"count": 2}, "algorithm": {"name": "greed"},
            "comm": {"map_sharing": "maes_heartbeat"}, "stop": {"max_ticks": 300}}
    sim = Simulation(spec)
    r = sim.run()
    assert sim.maes_merge.merges == 0 and r.summary["messages"]["delivered"] > 0, "heartbeats heard, never merged"
    three = Simulation({**spec, "robots": {"count": 3}})
    three.run()
    assert three.maes_merge.merges > 0


def heard_from_the_leaver(link_at: str) -> list[int]:
    """The send ticks of robot 1's messages robot 0 heard, robot 1 driving out of its 8 m radio range."""
    truth = box_map(120, 20)
    start = np.array([[2.0, 5.0, 0.0], [3.0, 5.0, 0.0]])
    spec = {"seed": 1, "robots": {"count": 2}, "algorithm": {"name": "tests.swarm.agents:Leaver"},
            "radio": {"model": "los", "max_range_m": 8.0}, "comm": {"map_sharing": "off", "link_at": link_at},
            "stop": {"max_ticks": 150, "stall_ticks": 10_000}}
    Simulation(spec, truth=truth, start_poses=start).run()
    return [sent for _, sender, sent in Leaver.log[0] if sender == 1]


def test_links_judged_at_receipt_lose_the_message_sent_just_before_leaving_range():
    """Judged at send time (a radio), the last message sent in range still arrives; judged at receipt
    (MAES, docs/maes.md section 6.1), it does not: the robot has left by then."""
    at_send, at_receipt = heard_from_the_leaver("send"), heard_from_the_leaver("receive")
    assert at_send == list(range(len(at_send))) and len(at_send) < 149, "heard every tick until it left"
    assert at_receipt == at_send[:-1]


def test_a_two_tile_concrete_wall_costs_maes_figure_under_per_metre_pricing():
    """MAES charges 15 dB (2.4 GHz concrete) per quarter metre of wall path: a 2-tile (2 m) concrete wall
    crossed at right angles costs 8 x 15 = 120 dB (docs/maes.md section 6.5). radio = "maes" charges that,
    and so does per_metre pricing of a 0.25 m concrete; our per-crossing model charges 15 dB once."""
    solid = np.zeros((20, 40), bool)
    solid[:, 18:22] = True                      # a wall 4 cells = 2 m thick, floor to ceiling
    solid[0, :] = solid[-1, :] = solid[:, 0] = solid[:, -1] = True
    truth = Map(solid=solid, material=solid.astype(np.uint8), materials=("air", "concrete"))
    xy = np.array([[5.0, 5.0], [15.0, 5.0]])

    def wall_db(radio: dict) -> float:
        return float(build_link_model(truth, config_from_mapping(radio)).evaluate(xy).wall_db[1, 0])

    assert wall_db({"model": "maes"}) == pytest.approx(120.0, abs=0.5)
    quarter = {"concrete": {"db": [13.0, 15.0, 23.0], "freq_ghz": [1.3, 2.4, 5.2], "thickness_m": 0.25}}
    assert wall_db({"model": "multiwall", "wall_mode": "per_metre", "materials": quarter}) == pytest.approx(120.0, abs=0.5)
    assert wall_db({"model": "multiwall"}) == pytest.approx(15.0, abs=0.01)


def test_new_parity_settings_keep_every_earlier_run_key():
    """link_at is left out of the canonical spec at its default, so specs written before it keep their keys."""
    from swarm.sim.spec import RunSpec

    assert "link_at" not in RunSpec().canonical()["comm"]
    assert RunSpec.from_mapping({"comm": {"link_at": "receive"}}).canonical()["comm"]["link_at"] == "receive"
    assert CommSpec(link_at="send") == CommSpec()


def test_map_sharing_maes_is_each_algorithms_own_merge():
    """map_sharing = "maes" is what MAES's version of the run's algorithm does: TNF syncs every 20 ticks,
    Greed (and Minotaur) heartbeat every 10."""
    def merge_of(name: str) -> tuple[str, int]:
        sim = Simulation({"map": {"kind": "building", "size": 20}, "robots": {"count": 3}, "algorithm": {"name": name},
                          "comm": {"map_sharing": "maes"}, "stop": {"max_ticks": 5}})
        return sim.maes_merge.mode, sim.maes_merge.share_every

    assert merge_of("tnf") == ("maes_sync", 20)
    assert merge_of("greed") == ("maes_heartbeat", 10) == merge_of("minotaur")
