"""One run: its spec, reading a spec from files and flags, the simulation loop, and ``swarm.run``.

``spec`` (:class:`RunSpec`: everything that determines a run, canonical and hashable; the seed streams),
``spec_input`` (a spec from a file, flags or keyword overrides), ``loop`` (:class:`Simulation`: the tick loop of
docs/design.md section 4) and ``python_api`` (:func:`swarm.run`).

May import: every runtime package below it (``swarm.world``, ``swarm.navigation``, ``swarm.comm``,
``swarm.transport``, ...), ``radio``, ``maps``; not ``swarm.record``, ``swarm.env``, ``swarm.campaign``,
``swarm.cli``.
"""
