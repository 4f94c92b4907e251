"""Drive robots to their algorithms' goals on their own knowledge maps.

``spec`` (the run spec's ``[navigation]`` section) and ``navigator`` (plan on the configuration space,
shortcut, follow, replan when blocked or stuck; every robot's follower stepped in one compiled call).

May import: ``swarm.base``, ``swarm.util``, ``swarm.grid``, ``swarm.world``, ``swarm.plugins``.
"""
