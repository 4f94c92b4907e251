"""swarm in the ROS 2 world: runs as ROS 2 messages, written to MCAP for Foxglove and ``ros2 bag play``
(:mod:`swarm.ros2.mcap_export`), or published live on zenoh exactly as rmw_zenoh does
(:mod:`swarm.ros2.live`), without ROS installed. The message layer (:mod:`swarm.ros2.messages`) uses
rosbags' type store for CDR, definitions and type hashes; everything here needs the ``ros`` extra
(``pip install 'swarm-sim[ros]'``) except the map_server files (:mod:`maps.ros`).
"""
