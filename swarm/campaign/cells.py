"""The cells of a campaign grid, counted and listed without building the whole cross product.

A grid is the cross product of its dimensions (``sizes[d]`` options each) minus the cells an ``[[exclude]]``
rule matches. A rule is a *box*: for each dimension it names, the set of option indices it matches (a
dimension it does not name matches everything). Both functions walk the dimensions in grid order and drop
a whole sub-product as soon as a box matches every cell of it, so their work grows with the cells kept
(and the rules), not with the full cross product: a 10^8-cell grid whose rules keep 100 cells costs ~100
steps, and :func:`count` of any grid costs at most a few steps per distinct rule pattern (memoised).
"""

from __future__ import annotations

import math
from collections.abc import Iterator, Mapping, Sequence
from functools import lru_cache

Box = Mapping[int, frozenset[int]]
"""dimension position -> option indices a rule matches there."""


def iter_cells(sizes: Sequence[int], boxes: Sequence[Box]) -> Iterator[tuple[int, tuple[int, ...]]]:
    """``(code, option indices)`` of every cell no box matches, in cross-product order; ``code`` is the
    cell's position in the full cross product (mixed radix, first dimension most significant)."""
    n = len(sizes)
    last = [max(box, default=-1) for box in boxes]  # a box still active past its last named dim matches
    weights = [math.prod(sizes[d + 1:]) for d in range(n)]

    def walk(depth: int, code: int, prefix: tuple[int, ...], active: list[int]) -> Iterator[tuple[int, tuple[int, ...]]]:
        if any(last[b] < depth for b in active):
            return  # every cell below this prefix is excluded
        if depth == n:
            yield code, prefix
            return
        for v in range(sizes[depth]):
            still = [b for b in active if depth not in boxes[b] or v in boxes[b][depth]]
            yield from walk(depth + 1, code + v * weights[depth], prefix + (v,), still)

    yield from walk(0, 0, (), list(range(len(boxes))))


def count(sizes: Sequence[int], boxes: Sequence[Box]) -> int:
    """How many cells :func:`iter_cells` yields, without listing them: options of a dimension that leave
    the same rules active are counted together."""
    n = len(sizes)
    last = [max(box, default=-1) for box in boxes]

    @lru_cache(maxsize=None)
    def rest(depth: int, active: frozenset[int]) -> int:
        if any(last[b] < depth for b in active):
            return 0
        if not active:
            return math.prod(sizes[depth:])
        groups: dict[frozenset[int], int] = {}
        for v in range(sizes[depth]):
            still = frozenset(b for b in active if depth not in boxes[b] or v in boxes[b][depth])
            groups[still] = groups.get(still, 0) + 1
        return sum(k * rest(depth + 1, still) for still, k in groups.items())

    return rest(0, frozenset(range(len(boxes)))) if n else 0


def decode(code: int, sizes: Sequence[int]) -> tuple[int, ...]:
    """The option indices of the cell at position ``code`` of the full cross product."""
    out = []
    for size in reversed(sizes):
        code, v = divmod(code, size)
        out.append(v)
    return tuple(reversed(out))
