"""Parameter validation for plugins: the checks swarm's own algorithms use, and the one error type.

Every check raises :class:`InvalidInput` naming the field, the value and what is allowed, which the
command line prints as one line with exit status 2. Call them in your ``Params.__post_init__``;
:func:`from_mapping` builds a ``Params`` dataclass from a table, refusing unknown keys and values of the
wrong type. A parameter added to a published explorer should be declared
``field(default=..., metadata={OMIT_DEFAULT: True})``: left out of the canonical spec at its default, it keeps
every earlier run's key (campaign folders resume).
"""

from __future__ import annotations

from swarm.base.errors import InvalidInput
from swarm.base.params import OMIT_DEFAULT, check_bool, check_choice, check_float, check_int, from_mapping, to_mapping

OMIT_DEFAULT: str
"""Field metadata key: ``field(default=..., metadata={OMIT_DEFAULT: True})`` leaves the field out of
:func:`to_mapping` while it holds its default. A setting added to an existing section carries it, so every
spec written before it existed keeps its canonical form and its run key (campaign folders resume)."""

__all__ = ["InvalidInput", "OMIT_DEFAULT", "check_bool", "check_choice", "check_float", "check_int", "from_mapping",
           "to_mapping"]
