"""What a run measures and returns: the result schema, the metrics recorders and :class:`RunResult`.

``schema`` (the shape of a summary, a time series and a campaign's runs table, defined once), ``metrics``
(the time series, threshold ticks and communication metrics a run records) and ``result`` (the result of one
run, as ``swarm run --json`` writes it).

May import: ``swarm.base``, ``maps``.
"""
