"""Indexed binary min-heap over a fixed set of entries (one per particle, plus the frame tick).

Every entry always has exactly one key (time, seq); ``inf`` means "nothing scheduled". The heap
stores entry ids; ``where[e]`` is the heap position of entry ``e``, so an entry's key is changed
in O(log n) without searching. Ties in time are broken by the sequence number ``seq``, which the
scheduler increments at every prediction: the order is total, so runs are bit-for-bit
reproducible (DESIGN.md §3).
"""

from __future__ import annotations

import numpy as np

from hsgran._jit import njit


@njit
def _less(t, seq, a, b):
    return t[a] < t[b] or (t[a] == t[b] and seq[a] < seq[b])


@njit
def _sift_up(heap, where, t, seq, pos):
    e = heap[pos]
    while pos > 0:
        parent = (pos - 1) >> 1
        p = heap[parent]
        if not _less(t, seq, e, p):
            break
        heap[pos] = p
        where[p] = pos
        pos = parent
    heap[pos] = e
    where[e] = pos


@njit
def _sift_down(heap, where, t, seq, pos):
    n = heap.shape[0]
    e = heap[pos]
    while True:
        child = 2 * pos + 1
        if child >= n:
            break
        right = child + 1
        if right < n and _less(t, seq, heap[right], heap[child]):
            child = right
        c = heap[child]
        if not _less(t, seq, c, e):
            break
        heap[pos] = c
        where[c] = pos
        pos = child
    heap[pos] = e
    where[e] = pos


@njit
def heap_build(heap, where, t, seq):
    """Arrange all entries 0..n−1 into a heap by their keys (t, seq)."""
    n = heap.shape[0]
    for k in range(n):
        heap[k] = k
        where[k] = k
    for k in range(n // 2 - 1, -1, -1):
        _sift_down(heap, where, t, seq, k)


@njit
def heap_update(heap, where, t, seq, e):
    """Restore the heap after the key (t[e], seq[e]) of entry ``e`` changed."""
    pos = where[e]
    _sift_up(heap, where, t, seq, pos)
    _sift_down(heap, where, t, seq, where[e])


def new_heap(n: int):
    """Arrays (heap, where) for ``n`` entries."""
    return np.zeros(n, dtype=np.int64), np.zeros(n, dtype=np.int64)
