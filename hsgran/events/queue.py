"""Indexed 4-ary min-heap of a varying subset of entries (layer 3).

The event calendar (:mod:`hsgran.events.calendar`) keeps the events of its current time bucket
here. Ties in time are broken by the sequence number ``seq``, which the scheduler increments at
every prediction: the order is total, so runs are bit-for-bit reproducible
(docs/architecture.md §3).

Layout, chosen for the cache:

- ``heap[p]`` is the entry at heap position p (0 ≤ p < size) and ``where[e]`` the position of an
  entry e that is in the heap, so an entry's key is changed or removed in O(log size) without
  searching;
- the keys are stored in heap order (``key_t[p]``, ``key_s[p]``), so a sift compares neighbouring
  memory instead of jumping to each entry's own record;
- four children per node (positions 4p + 1 … 4p + 4, adjacent in memory) halve the depth of a
  binary heap for the price of three comparisons per level.

The caller keeps ``size``; :func:`heap_push` and :func:`heap_remove` return the new one.
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
def _sift_down(heap, where, key_t, key_s, size, pos, e, t, s):
    """Place entry e with key (t, s) at or below ``pos`` in a heap of ``size`` positions."""
    while True:
        first = ARITY * pos + 1
        if first >= size:
            break
        best = first
        bt = key_t[first]
        bs = key_s[first]
        last = min(first + ARITY, size)
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
def heap_push(heap, where, key_t, key_s, size, e, t, s):
    """Add entry e (not in the heap) with key (t, s); returns the new size."""
    _sift_up(heap, where, key_t, key_s, size, e, t, s)
    return size + 1


@njit
def heap_change(heap, where, key_t, key_s, size, e, t, s):
    """Give entry e (in the heap) the new key (t, s) and restore the heap."""
    pos = _sift_up(heap, where, key_t, key_s, where[e], e, t, s)
    _sift_down(heap, where, key_t, key_s, size, pos, e, t, s)


@njit
def heap_remove(heap, where, key_t, key_s, size, e):
    """Take entry e out of the heap (its ``where`` is left to the caller); returns the new
    size."""
    pos = where[e]
    size -= 1
    if pos < size:
        # the last entry fills the hole and moves up or down from there
        m = heap[size]
        tm = key_t[size]
        sm = key_s[size]
        pos = _sift_up(heap, where, key_t, key_s, pos, m, tm, sm)
        _sift_down(heap, where, key_t, key_s, size, pos, m, tm, sm)
    return size


def new_heap(n: int, where: np.ndarray | None = None):
    """Arrays (heap, where, key_t, key_s) for up to ``n`` entries; ``where`` may be given (an
    int64 array of ``n``, e.g. a field of per-entry records), else it is made."""
    if where is None:
        where = np.zeros(n, dtype=np.int64)
    return (np.zeros(n, dtype=np.int64), where, np.full(n, np.inf), np.zeros(n, dtype=np.int64))
