"""Indexed 4-ary min-heap over a fixed set of entries (one per particle, plus the frame tick).

Every entry always has exactly one key (time, seq); ``inf`` means "nothing scheduled". Ties in
time are broken by the sequence number ``seq``, which the scheduler increments at every
prediction: the order is total, so runs are bit-for-bit reproducible (DESIGN.md §3).

Layout, chosen for the cache (the heap is touched at every event, at random entries):

- ``heap[p]`` is the entry at heap position p and ``where[e]`` the position of entry e, so an
  entry's key is changed in O(log n) without searching;
- the keys are stored in heap order (``key_t[p]``, ``key_s[p]``), so a sift compares neighbouring
  memory instead of jumping to each entry's own record;
- four children per node (positions 4p + 1 … 4p + 4, adjacent in memory) halve the depth of a
  binary heap for the price of three comparisons per level.
"""

from __future__ import annotations

import numpy as np

from hsgran._jit import njit

#: Children per node.
ARITY = 4


@njit(inline="always")
def _before(ta, sa, tb, sb):
    """Key (ta, sa) comes strictly before (tb, sb)."""
    return ta < tb or (ta == tb and sa < sb)


@njit
def _sift_up(heap, where, key_t, key_s, pos, e, t, s):
    """Place entry e with key (t, s) at or above ``pos``; returns its final position."""
    while pos > 0:
        parent = (pos - 1) // ARITY
        if not _before(t, s, key_t[parent], key_s[parent]):
            break
        p = heap[parent]
        heap[pos] = p
        key_t[pos] = key_t[parent]
        key_s[pos] = key_s[parent]
        where[p] = pos
        pos = parent
    heap[pos] = e
    key_t[pos] = t
    key_s[pos] = s
    where[e] = pos
    return pos


@njit
def _sift_down(heap, where, key_t, key_s, pos, e, t, s):
    """Place entry e with key (t, s) at or below ``pos``."""
    n = heap.shape[0]
    while True:
        first = ARITY * pos + 1
        if first >= n:
            break
        best = first
        bt = key_t[first]
        bs = key_s[first]
        last = min(first + ARITY, n)
        for c in range(first + 1, last):
            if _before(key_t[c], key_s[c], bt, bs):
                best = c
                bt = key_t[c]
                bs = key_s[c]
        if not _before(bt, bs, t, s):
            break
        b = heap[best]
        heap[pos] = b
        key_t[pos] = bt
        key_s[pos] = bs
        where[b] = pos
        pos = best
    heap[pos] = e
    key_t[pos] = t
    key_s[pos] = s
    where[e] = pos


@njit
def heap_build(heap, where, key_t, key_s, t, seq):
    """Arrange entries 0..n−1 with keys (t[e], seq[e]) into a heap."""
    n = heap.shape[0]
    for k in range(n):
        heap[k] = k
        where[k] = k
        key_t[k] = t[k]
        key_s[k] = seq[k]
    for k in range((n - 2) // ARITY, -1, -1):
        _sift_down(heap, where, key_t, key_s, k, heap[k], key_t[k], key_s[k])


@njit
def heap_update(heap, where, key_t, key_s, e, t, s):
    """Give entry ``e`` the new key (t, s) and restore the heap."""
    pos = _sift_up(heap, where, key_t, key_s, where[e], e, t, s)
    _sift_down(heap, where, key_t, key_s, pos, e, t, s)


def new_heap(n: int):
    """Arrays (heap, where, key_t, key_s) for ``n`` entries."""
    return (np.zeros(n, dtype=np.int64), np.zeros(n, dtype=np.int64),
            np.full(n, np.inf), np.zeros(n, dtype=np.int64))
