"""rmw_zenoh's wire conventions (swarm.ros2.rmw) against the examples of its design doc and rosbags."""

from __future__ import annotations

import pytest

pytest.importorskip("rosbags")

from rosbags.typesys import Stores, get_typestore  # noqa: E402

from swarm.base.errors import InvalidInput  # noqa: E402
from swarm.ros2 import rmw  # noqa: E402

STRING_HASH = "RIHS01_df668c740482bbd48fb39d76a70dfd4bd59db1288021743503259e948f6b1a18"  # design.md
TYPES = ("std_msgs/msg/String", "rosgraph_msgs/msg/Clock", "geometry_msgs/msg/PoseStamped",
         "geometry_msgs/msg/Twist", "nav_msgs/msg/OccupancyGrid")


def test_topic_key_is_the_design_docs():
    assert rmw.topic_key(0, "/chatter", "std_msgs/msg/String", STRING_HASH) == (
        "0/chatter/std_msgs::msg::dds_::String_/" + STRING_HASH)
    assert rmw.topic_key(0, "/robot1/chatter", "std_msgs/msg/String", STRING_HASH) == (
        "0/robot1/chatter/std_msgs::msg::dds_::String_/" + STRING_HASH)


def test_dds_type_name():
    assert rmw.dds_type_name("geometry_msgs/msg/PoseStamped") == "geometry_msgs::msg::dds_::PoseStamped_"
    for bad in ("geometry_msgs/PoseStamped", "geometry_msgs/srv/Foo", "a/msg/b", 3):
        with pytest.raises(InvalidInput):
            rmw.dds_type_name(bad)


@pytest.mark.parametrize("topic", ["chatter", "/a//b", "/a/", "/1a", "/a b", "/a/*", "/a__b", "/~/x"])
def test_topics_that_are_not_fully_qualified_names_are_refused(topic):
    with pytest.raises(InvalidInput, match="fully qualified"):
        rmw.check_topic(topic)


def test_string_hash_is_the_design_docs_and_rosbags_for_humble_and_jazzy_stores():
    assert rmw.type_hash("std_msgs/msg/String", "jazzy") == STRING_HASH
    for typename in TYPES:
        for store in (Stores.ROS2_HUMBLE, Stores.ROS2_JAZZY):
            assert get_typestore(store).hash_rihs01(typename) == rmw.type_hash(typename, "jazzy")
        assert rmw.type_hash(typename, "kilted") == rmw.type_hash(typename, "jazzy")
        assert rmw.type_hash(typename, "humble") == rmw.HASH_NOT_SUPPORTED  # Humble has no type hashes


def test_qos_to_keyexpr_matches_the_design_docs_tokens():
    assert rmw.qos_to_keyexpr(rmw.QoS(depth=7)) == "::,7:,:,:,,"     # talker
    assert rmw.qos_to_keyexpr(rmw.QoS(depth=10)) == "::,10:,:,:,,"   # listener
    assert rmw.qos_to_keyexpr(rmw.DEFAULT_QOS) == "::,:,:,:,,"
    assert rmw.qos_to_keyexpr(rmw.LATCHED) == ":1:,1:,:,:,,"
    assert rmw.qos_to_keyexpr(rmw.QoS(reliability=rmw.BEST_EFFORT, history=rmw.KEEP_ALL, deadline=(1, 5))) == (
        "2::2,:1,5:,:,,")


def test_liveliness_tokens_are_the_design_docs():
    zid = "8b20917502ee955ac4476e0266340d5c"
    assert rmw.node_token(2, "aac3178e146ba6f1fc6e6a4085e77f21", 0, "listener") == (
        "@ros2_lv/2/aac3178e146ba6f1fc6e6a4085e77f21/0/0/NN/%/%/listener")
    assert rmw.entity_token(rmw.PUBLISHER, 2, zid, 0, 10, "talker", "/chatter", "std_msgs/msg/String", STRING_HASH,
                            rmw.QoS(depth=7)) == (
        f"@ros2_lv/2/{zid}/0/10/MP/%/%/talker/%chatter/std_msgs::msg::dds_::String_/{STRING_HASH}/::,7:,:,:,,")
    assert rmw.entity_token(rmw.SUBSCRIPTION, 0, zid, 1, 3, "n", "/robot_1/cmd_vel", "geometry_msgs/msg/Twist",
                            "H", rmw.DEFAULT_QOS, namespace="/sim") == (
        f"@ros2_lv/0/{zid}/1/3/MS/%/%sim/n/%robot_1%cmd_vel/geometry_msgs::msg::dds_::Twist_/H/::,:,:,:,,")


def test_attachment_is_33_bytes_and_round_trips():
    import zenoh.ext as ze

    gid = rmw.gid("@ros2_lv/0/x/0/1/MP/%/%/n/%t/T/H/::,:,:,:,,")
    data = rmw.encode_attachment(5, 1_700_000_000_123_456_789, gid)
    assert len(data) == 33 and data[16] == 16
    # the zenoh-ext serializer rmw_zenoh uses writes (int64, int64, 16-byte array) the same way
    assert data == ze.z_serialize((ze.Int64(5), ze.Int64(1_700_000_000_123_456_789), gid)).to_bytes()
    assert rmw.decode_attachment(data) == (5, 1_700_000_000_123_456_789, gid)
    for bad in (None, data[:-1], data + b"\0", data[:16] + b"\x0f" + data[17:]):
        with pytest.raises(ValueError):
            rmw.decode_attachment(bad)


def test_cdr_round_trip_and_garbage_is_a_cdr_error():
    store = rmw.typestore("jazzy")
    Clock, Time = store.types["rosgraph_msgs/msg/Clock"], store.types["builtin_interfaces/msg/Time"]
    data = rmw.serialize(store, Clock(clock=Time(sec=3, nanosec=7)), "rosgraph_msgs/msg/Clock")
    assert data[:4] == b"\x00\x01\x00\x00"
    assert rmw.deserialize(store, data, "rosgraph_msgs/msg/Clock").clock.sec == 3
    for bad in (b"", b"\x00\x01\x00\x00\x01", b"\x07\x07\x00\x00" + bytes(8),
                b"\x00\x01\x00\x00" + bytes(8) + b"\xff\xff\xff\x7f"):
        with pytest.raises(rmw.CdrError):
            rmw.deserialize(store, bad, "geometry_msgs/msg/PoseStamped")
