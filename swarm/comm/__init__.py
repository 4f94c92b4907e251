"""Communication: the radio medium, map sharing, and the messages robots exchange.

``medium`` (messages judged by the radio's links, lost, throttled and delivered a tick later; the map-sharing
service and its metrics), ``messages`` (typed, versioned messages and their msgpack wire form) and
``maes_merge`` (MAES's own by-reference map merges, for parity runs).

May import: ``swarm.base``, ``swarm.knowledge``, ``swarm.results``, ``radio``, ``maps``.
"""
