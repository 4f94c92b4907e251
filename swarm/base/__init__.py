"""The floor under everything: the one error type, the parameter validators and the robot vocabulary.

``errors`` (:class:`InvalidInput`, the one-line message helpers), ``params`` (frozen-dataclass parameter
sets built from mappings and checked field by field) and ``types`` (cells, poses, observations, actions: what
an algorithm implements and sees). ``maps``, ``radio`` and every swarm package use them.

May import: the standard library and numpy only; nothing of maps, radio or the rest of swarm.
"""
