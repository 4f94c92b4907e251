"""Find plug-ins by name: exploration algorithms and path planners.

``explorers`` (the ``swarm.algorithms`` entry-point group or ``"package.module:Class"``, their ``Params``, the
distribution that provides them) and ``planners`` (the ``swarm.planners`` group and the built-in ``astar``).
Nothing here imports ``algorithms``: plug-ins are loaded by name, at run time.

May import: ``swarm.base``, ``swarm.grid``.
"""
