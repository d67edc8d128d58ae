"""The indexed heap keeps the earliest (time, seq) key on top through pushes, changes and
removals."""

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from hsgran.events.queue import ARITY, heap_change, heap_push, heap_remove, new_heap

times = st.one_of(st.floats(0.0, 10.0), st.just(np.inf), st.sampled_from([1.0, 2.0]))
N = 20


def check_heap(heap, where, key_t, key_s, size, members, t, seq):
    """Heap order, consistent positions, and keys mirrored in heap order."""
    assert sorted(heap[:size]) == sorted(members)
    for p in range(size):
        e = heap[p]
        assert where[e] == p
        assert (key_t[p], key_s[p]) == (t[e], seq[e])
        if p:
            parent = (p - 1) // ARITY
            assert (key_t[parent], key_s[parent]) <= (key_t[p], key_s[p])


@settings(max_examples=200, deadline=None)
@given(st.lists(st.tuples(st.sampled_from(["push", "change", "remove"]), st.integers(0, N - 1),
                          times), max_size=80))
def test_heap_top_is_the_earliest_key_after_any_operations(ops):
    t = np.full(N, np.inf)
    seq = np.zeros(N, dtype=np.int64)
    heap, where, key_t, key_s = new_heap(N)
    members: set[int] = set()
    size = 0
    for k, (op, e, new_t) in enumerate(ops):
        if op == "push" and e not in members:
            t[e], seq[e] = new_t, k
            size = heap_push(heap, where, key_t, key_s, size, e, t[e], seq[e])
            members.add(e)
        elif op == "change" and e in members:
            t[e], seq[e] = new_t, k
            heap_change(heap, where, key_t, key_s, size, e, t[e], seq[e])
        elif op == "remove" and e in members:
            size = heap_remove(heap, where, key_t, key_s, size, e)
            members.remove(e)
        check_heap(heap, where, key_t, key_s, size, members, t, seq)
        if members:
            assert heap[0] == min(members, key=lambda m: (t[m], seq[m]))


def test_equal_times_pop_in_sequence_order():
    """Ties in time are broken by the sequence number, so runs are reproducible."""
    seq = np.array([5, 3, 8, 0, 7, 1, 6, 2, 4], dtype=np.int64)
    n = len(seq)
    heap, where, key_t, key_s = new_heap(n)
    size = 0
    for e in range(n):
        size = heap_push(heap, where, key_t, key_s, size, e, 1.0, seq[e])
    order = []
    while size:
        e = heap[0]
        order.append(int(seq[e]))
        size = heap_remove(heap, where, key_t, key_s, size, e)
    assert order == list(range(n))
