"""Predicted information gain along tree paths: numba kernels on flat belief arrays.

The gain of a path is the number of *currently unknown* cells that the optimistic scans at its poses would
observe: unknown cells do not stop a beam, known-occupied cells do (docs/boa.md section 11, decision
13). The start pose is excluded (its scan is already in the belief), so the robot's own cell as a goal
gains 0 and the gain is monotone along a path prefix.

Two exact evaluations share one fan walker (``_fan``):

* ``subtree_gains`` - the per-decision gain table of section 11.1, generalised: one depth-first pass over
  the part of the state tree spanned by the root paths of some target states keeps, per cell, how many
  poses on the current root path see it; entering a pose adds its newly seen unknown cells, leaving
  removes them. Every target's gain in O(sum of fan sizes over the spanned subtree) with O(cells) memory -
  no per-state bitsets, so it also fits 300 x 300 belief maps. With all goal states as targets it is the
  full table; with a generation's new goals it is lazy evaluation with shared prefixes walked once.
* ``chain_gain`` - walk the parent chain of one goal state and count distinct unknown cells with a stamp
  array (union is order-independent). Legs of a long-term plan share one stamp so their union is counted
  once (section 11.2).

Stamps: every fan evaluation uses a fresh stamp id (callers pass a running counter), so one stamp array
serves a whole decision without clearing.
"""

from __future__ import annotations

import numpy as np
from numba import njit


@njit(cache=True, inline="always")
def _fan(state: int, W: int, H: int, unknown: np.ndarray, occupied: np.ndarray, t_dr: np.ndarray,
         t_dc: np.ndarray, t_skip: np.ndarray, t_start: np.ndarray, stamp: np.ndarray, sid: int,
         count: np.ndarray, touched: np.ndarray, tp: int, gain: int, use_count: bool) -> tuple[int, int]:
    cell = state >> 3
    h = state & 7
    r = cell // W
    c = cell - r * W
    # own cell: always seen, never blocks
    if unknown[cell] and stamp[cell] != sid:
        stamp[cell] = sid
        if use_count:
            if count[cell] == 0:
                gain += 1
            count[cell] += 1
            touched[tp] = cell
            tp += 1
        else:
            gain += 1
    i = t_start[h]
    end = t_start[h + 1]
    while i < end:
        rr = r + t_dr[i]
        cc = c + t_dc[i]
        if rr < 0 or rr >= H or cc < 0 or cc >= W:
            i = t_skip[i]
            continue
        k = rr * W + cc
        if unknown[k] and stamp[k] != sid:
            stamp[k] = sid
            if use_count:
                if count[k] == 0:
                    gain += 1
                count[k] += 1
                touched[tp] = k
                tp += 1
            else:
                gain += 1
        if occupied[k]:
            i = t_skip[i]
        else:
            i += 1
    return tp, gain


@njit(cache=True)
def tree_index(order: np.ndarray, parent: np.ndarray, pos: np.ndarray, first: np.ndarray, sib: np.ndarray) -> None:
    """Fill ``pos[state]`` (position in ``order``, -1 if unreachable) and the child lists (first child /
    next sibling, by position, children in search order) of a state tree."""
    n = order.shape[0]
    pos[:] = -1
    for i in range(n):
        pos[order[i]] = i
    first[:] = -1
    for i in range(n - 1, 0, -1):
        p = pos[parent[order[i]]]
        sib[i] = first[p]
        first[p] = i


@njit(cache=True)
def subtree_gains(order: np.ndarray, parent: np.ndarray, pos: np.ndarray, first: np.ndarray, sib: np.ndarray,
                  targets: np.ndarray, H: int, W: int, unknown: np.ndarray, occupied: np.ndarray, t_dr: np.ndarray,
                  t_dc: np.ndarray, t_skip: np.ndarray, t_start: np.ndarray, stamp: np.ndarray, sid0: int,
                  count: np.ndarray, touched: np.ndarray, need: np.ndarray, marked: np.ndarray, stack: np.ndarray,
                  tps: np.ndarray, nxt: np.ndarray, gpos: np.ndarray, out: np.ndarray) -> int:
    """Gains of the ``targets`` states into ``out`` (same order); returns the next free stamp id.

    Work arrays (allocated once per tree by the caller, so memory is visible and bounded): ``count``
    (cells, all 0 on entry and on return), ``touched`` (fans of the deepest root path), and per tree
    position ``need`` (all False on entry and on return), ``marked``, ``stack``, ``tps``, ``nxt``, ``gpos``.
    """
    nm = 0
    for q in range(targets.shape[0]):
        i = pos[targets[q]]
        while i > 0 and not need[i]:
            need[i] = True
            marked[nm] = i
            nm += 1
            i = pos[parent[order[i]]]
    sid = sid0
    stack[0] = 0
    nxt[0] = first[0]
    tps[0] = 0
    gpos[0] = 0
    sp = 1
    tp = 0
    g = 0
    while sp > 0:
        node = stack[sp - 1]
        ch = nxt[node]
        while ch >= 0 and not need[ch]:
            ch = sib[ch]
        if ch >= 0:
            nxt[node] = sib[ch]
            tps[sp] = tp
            tp, g = _fan(order[ch], W, H, unknown, occupied, t_dr, t_dc, t_skip, t_start, stamp, sid, count,
                         touched, tp, g, True)
            sid += 1
            gpos[ch] = g
            nxt[ch] = first[ch]
            stack[sp] = ch
            sp += 1
        else:
            start = tps[sp - 1]
            for q in range(start, tp):
                k = touched[q]
                count[k] -= 1
                if count[k] == 0:
                    g -= 1
            tp = start
            sp -= 1
    for q in range(targets.shape[0]):
        out[q] = gpos[pos[targets[q]]]
    for q in range(nm):
        need[marked[q]] = False
    return sid


@njit(cache=True)
def chain_gain(goal: int, parent: np.ndarray, H: int, W: int, unknown: np.ndarray, occupied: np.ndarray,
               t_dr: np.ndarray, t_dc: np.ndarray, t_skip: np.ndarray, t_start: np.ndarray, stamp: np.ndarray,
               sid: int) -> int:
    """Unknown cells first seen (under stamp ``sid``) by the poses from ``goal`` up to, not including, the root."""
    dummy_i = np.empty(0, np.int32)
    dummy_t = np.empty(0, np.int64)
    g = 0
    s = goal
    while s >= 0 and parent[s] >= 0:
        _, g = _fan(s, W, H, unknown, occupied, t_dr, t_dc, t_skip, t_start, stamp, sid, dummy_i, dummy_t, 0,
                    g, False)
        s = parent[s]
    return g


@njit(cache=True)
def observed_cells(occupied: np.ndarray, H: int, W: int, poses: np.ndarray, t_dr: np.ndarray, t_dc: np.ndarray,
                   t_skip: np.ndarray, t_start: np.ndarray, out: np.ndarray) -> None:
    """Set ``out`` (bool, flat H * W) at every cell the fans at ``poses`` (int64[N, 3]: row, col, heading
    0..7) see on ``occupied`` (flat): the robot's own cell, then each cell of the heading's trie up to and
    including the first occupied one on each beam, none past the grid's edge. A pose outside the grid sees
    nothing. The union of :func:`algorithms.boa.beams.visible_cells` over the poses, in one walk per pose."""
    for p in range(poses.shape[0]):
        r = poses[p, 0]
        c = poses[p, 1]
        h = poses[p, 2]
        if r < 0 or r >= H or c < 0 or c >= W:
            continue
        out[r * W + c] = True
        i = t_start[h]
        end = t_start[h + 1]
        while i < end:
            rr = r + t_dr[i]
            cc = c + t_dc[i]
            if rr < 0 or rr >= H or cc < 0 or cc >= W:
                i = t_skip[i]
                continue
            k = rr * W + cc
            out[k] = True
            if occupied[k]:
                i = t_skip[i]
            else:
                i += 1
