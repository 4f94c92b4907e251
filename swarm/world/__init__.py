"""The physical world and sensing: where robots are, how they move, and what their lidar sees.

``physics`` (the pymunk world: wall boxes, robot discs, differential drive), ``motion`` (drive limits and the
waypoint follower), ``sensing`` (the lidar: exact ray casting on the truth raster into each robot's knowledge
map) and ``spawn`` (starting poses).

May import: ``swarm.base``, ``swarm.util``, ``swarm.knowledge``, ``maps``.
"""
