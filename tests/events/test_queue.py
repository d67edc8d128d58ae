"""The indexed heap keeps the earliest (time, seq) key on top through any sequence of updates."""

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from hsgran.events.queue import ARITY, heap_build, heap_update, new_heap

times = st.one_of(st.floats(0.0, 10.0), st.just(np.inf), st.sampled_from([1.0, 2.0]))


def check_heap(heap, where, key_t, key_s, t, seq):
    """Heap order, consistent positions, and keys mirrored in heap order."""
    n = len(heap)
    assert sorted(heap) == list(range(n))
    for p in range(n):
        e = heap[p]
        assert where[e] == p
        assert (key_t[p], key_s[p]) == (t[e], seq[e])
        if p:
            parent = (p - 1) // ARITY
            assert (key_t[parent], key_s[parent]) <= (key_t[p], key_s[p])


@settings(max_examples=200, deadline=None)
@given(st.lists(times, min_size=1, max_size=40),
       st.lists(st.tuples(st.integers(0, 39), times), max_size=60))
def test_heap_top_is_the_earliest_key_after_any_updates(initial, updates):
    n = len(initial)
    t = np.array(initial, dtype=np.float64)
    seq = np.arange(n, dtype=np.int64)
    heap, where, key_t, key_s = new_heap(n)
    heap_build(heap, where, key_t, key_s, t, seq)
    check_heap(heap, where, key_t, key_s, t, seq)
    next_seq = n
    for e, new_t in updates:
        e %= n
        t[e] = new_t
        seq[e] = next_seq
        next_seq += 1
        heap_update(heap, where, key_t, key_s, e, t[e], seq[e])
        check_heap(heap, where, key_t, key_s, t, seq)
        first = min(range(n), key=lambda k: (t[k], seq[k]))
        assert heap[0] == first


def test_equal_times_pop_in_sequence_order():
    """Ties in time are broken by the sequence number, so runs are reproducible."""
    n = 9
    t = np.full(n, 1.0)
    seq = np.array([5, 3, 8, 0, 7, 1, 6, 2, 4], dtype=np.int64)
    heap, where, key_t, key_s = new_heap(n)
    heap_build(heap, where, key_t, key_s, t, seq)
    order = []
    for _ in range(n):
        e = heap[0]
        order.append(int(seq[e]))
        t[e] = np.inf
        heap_update(heap, where, key_t, key_s, e, t[e], seq[e])
    assert order == list(range(n))
