"""Minotaur (Schmidt et al., the Minotaur paper in docs/papers.md): wall following, spiralling, doorway
detection and doorway auctions. The explorer is :class:`.explorer.Minotaur`; see its module docstring for the state machine
and every departure from the paper and from MAES.

Modules: :mod:`.params` (parameters), :mod:`.doorways` (doorway records), :mod:`.detection` (Alg. 3),
:mod:`.walls` (wall following and the spiral), :mod:`.rooms` (searches without passing doorways),
:mod:`.auction` (Alg. 4), :mod:`.messages` (radio messages), :mod:`.explorer` (Alg. 1-2),
:mod:`.maes` (MAES's doorway checks and corner coverage, ``variant = "maes"``).
"""

from .explorer import Minotaur
from .params import MinotaurParams

Params = MinotaurParams

__all__ = ["Minotaur", "MinotaurParams", "Params"]
