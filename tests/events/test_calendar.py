"""The event calendar gives the entry with the earliest (time, seq) key through any sequence of
updates: as the loop uses it (the top is rescheduled, later or at the same instant, together
with another entry), with ties, far-future and unscheduled (inf) keys, and with bucket widths
far too small or too large (its retuning and its jumps over empty stretches)."""

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from hsgran.events.calendar import (
    HEAP_ONLY,
    IN_OVERFLOW,
    Q_LISTED,
    Q_SIZE,
    calendar_build,
    calendar_top,
    calendar_update,
    new_calendar,
)


def earliest(t, seq):
    return min(range(len(t)), key=lambda k: (t[k], seq[k]))


def check_structure(cal, n):
    """Every entry is in exactly one place, and the counts agree."""
    heap, where, _, _, bhead, qnext, _, qi, _ = cal[:HEAP_ONLY]
    size = qi[Q_SIZE]
    assert all(where[heap[p]] == p for p in range(size))
    listed = 0
    for slot, first in enumerate(bhead):
        e = first
        while e >= 0:
            assert where[e] == -2 - slot
            listed += 1
            e = qnext[e]
    assert listed == qi[Q_LISTED]
    assert size + listed + sum(where[e] == IN_OVERFLOW for e in range(n)) == n


def drive(n, inv_w, delays, steps, seed, buckets=True):
    """Pop the earliest entry and reschedule it (and a random other one) ``steps`` times."""
    rng = np.random.default_rng(seed)
    t = rng.exponential(1.0, n)
    t[rng.random(n) < 0.1] = np.inf
    seq = np.arange(n, dtype=np.int64)
    cal = new_calendar(n, buckets=buckets)
    calendar_build(cal, t, seq, inv_w)
    next_seq = n
    for _ in range(steps):
        e, te = calendar_top(cal, t, seq)
        if not np.isfinite(t).any():
            assert te == math.inf
            assert e == -1 if buckets else t[e] == math.inf
            return
        ref = earliest(t, seq)
        assert (e, te) == (ref, t[ref])
        others = [int(rng.integers(0, n))] if rng.random() < 0.5 else []
        for k in [e, *others]:
            t[k] = te + delays(rng)
            seq[k] = next_seq
            next_seq += 1
            calendar_update(cal, t, seq, k)
    check_structure(cal, n)


def mixed_delay(rng):
    r = rng.random()
    if r < 0.05:
        return np.inf
    if r < 0.15:
        return 0.0  # at the same instant: a tie in time
    if r < 0.2:
        return 1000.0 * rng.random()  # far beyond the calendar's reach
    return rng.exponential(0.5 if rng.random() < 0.5 else 1e-3)


@settings(max_examples=60, deadline=None)
@given(st.integers(1, 80), st.integers(0, 2**31), st.booleans())
def test_top_is_the_earliest_key_with_the_width_chosen_from_the_keys(n, seed, buckets):
    """With buckets, and without (small calendars keep every entry in the heap)."""
    drive(n, 0.0, mixed_delay, 300, seed, buckets)


@pytest.mark.parametrize("inv_w", [1e-9, 1e9])
def test_top_is_the_earliest_key_with_a_width_far_off(inv_w):
    """Buckets of 10⁹ s hold everything; buckets of 1 ns leave most of them empty."""
    for seed in range(5):
        drive(50, inv_w, mixed_delay, 2000, seed)


@pytest.mark.parametrize("buckets", [True, False])
def test_ties_in_time_come_in_sequence_order(buckets):
    n = 9
    t = np.full(n, 1.0)
    seq = np.array([5, 3, 8, 0, 7, 1, 6, 2, 4], dtype=np.int64)
    cal = new_calendar(n, buckets=buckets)
    calendar_build(cal, t, seq, 0.0)
    order = []
    for _ in range(n):
        e, _ = calendar_top(cal, t, seq)
        order.append(int(seq[e]))
        t[e] = np.inf
        calendar_update(cal, t, seq, e)
    assert order == list(range(n))
    assert calendar_top(cal, t, seq)[1] == math.inf
