"""The event calendar: the priority queue of the event loop (layer 3).

A queue of a fixed set of entries (one per sphere and the frame tick), each with one key
(time, seq) at a time; ``inf`` means "nothing scheduled". The key of entry e is
``key_time[e], key_seq[e]`` (the loop's ``ev_t`` and ``ev_seq``): the caller sets them and then
calls :func:`calendar_update`. :func:`calendar_top` gives the entry with the earliest key, ties in
time broken by ``seq`` (a total order: runs are reproducible, docs/architecture.md §3).

Structure (Paul, J. Comput. Phys. 221, 615 (2007): an O(1) queue for event-driven simulation;
our implementation):

- time is cut into buckets of width ``w`` from a base time: the bucket of time t is
  ``B(t) = floor((t − base) / w)``, a non-decreasing function of t even in floating point, so an
  entry in a later bucket never comes before one in an earlier bucket;
- entries of the current bucket ``cur`` (and of earlier ones) are in an indexed heap
  (:mod:`hsgran.events.queue`), whose top is the earliest key of all;
- entries of the next ``nb − 1`` buckets are in doubly linked lists, one per bucket (circular:
  bucket B in list ``B mod nb``); entries further ahead, or at ``inf``, in an overflow list;
- when the heap is empty, the next bucket's list moves into it; each time ``cur`` passes a
  multiple of ``nb`` (a revolution) the overflow list is sorted into the buckets it reaches.

An update of a sphere's event (two per collision) then touches the heap of a few entries, one
list head and the neighbours in a list, instead of ~log₄ N levels of a heap of all entries,
whose lower levels are cache misses for large N (measured: ``tools/bench_engine.py``). The
bucket width is chosen so that about :data:`BUCKET_TARGET` entries pass through each bucket,
from the spread of the keys at the start and then from the count of each revolution.

Below :data:`BUCKETS_FROM` entries there are no buckets (``nb`` = 0): every entry stays in the
heap, which then fits the cache. Whether there are buckets is a constant of the calendar's tuple
type (:func:`has_buckets`), so LLVM drops the bucket code from a loop compiled for a calendar
without them; tested at run time instead, the bucket code slowed small systems down
(measurements in docs/performance.md).

``where[e]`` says where entry e is: its heap position (≥ 0), :data:`IN_OVERFLOW`, or
``IN_BUCKET0 − slot`` in the list of bucket ``slot``.
"""

from __future__ import annotations

import math

import numpy as np

from hsgran._jit import njit, prefetch
from hsgran.events.queue import ARITY, heap_change, heap_push, heap_remove, new_heap

#: Entries meant to pass through each bucket (the width follows from the event rate). A few
#: keeps the heap of the current bucket tiny and the lists short.
BUCKET_TARGET = 2.0
#: The width is re-chosen at the end of a revolution when the entries that passed through it
#: are off the target by more than this factor (either way).
RETUNE_FACTOR = 4.0
#: Most the width changes at one retune (a revolution with very few entries says little).
RETUNE_MAX = 64.0
#: Fewest buckets.
MIN_BUCKETS = 64
#: Entries from which the calendar uses buckets; below, every entry stays in the heap (no
#: buckets: ``nb`` = 0), which is then small enough for the cache and cheaper than buckets
#: (measured with tools/bench_engine.py: the heap alone is faster at N = 10³ and 10⁴, the
#: buckets at N = 10⁶).
BUCKETS_FROM = 1 << 16
#: Bucket number beyond which the calendar is rebuilt from the earliest key (keeps
#: (t − base) / w far inside the 53-bit integers that float64 holds exactly).
REBASE_BUCKETS = 2**40

IN_OVERFLOW = -1  #: ``where`` of an entry in the overflow list
IN_BUCKET0 = -2  #: ``where`` of an entry in the list of bucket 0 (bucket k: IN_BUCKET0 − k)

#: Length of the calendar's tuple without buckets; with buckets it has one more element, an
#: empty array that marks the kind in the type (see :func:`has_buckets`).
HEAP_ONLY = 9

# integer state qi[Q_*]
Q_SIZE = 0  #: entries in the heap
Q_CUR = 1  #: the current bucket (absolute number from the base)
Q_NB = 2  #: number of buckets (a power of two)
Q_OVF = 3  #: first entry of the overflow list, or −1
Q_LISTED = 4  #: entries in bucket lists
Q_PASSED = 5  #: entries that entered the heap since the start of the revolution
Q_LEN = 6
# float state qf[F_*]
F_BASE = 0  #: start of bucket 0 [s]
F_INV_W = 1  #: 1 / bucket width [1/s]
F_LEN = 2


def new_calendar(n: int, where: np.ndarray | None = None, qnext: np.ndarray | None = None,
                 qprev: np.ndarray | None = None, buckets: bool | None = None):
    """The arrays of a calendar of ``n`` entries, as the tuple
    ``(heap, where, key_t, key_s, bhead, qnext, qprev, qi, qf)``, followed with buckets by an
    empty marker array (:func:`has_buckets`); without them, ``bhead`` has one unused entry.

    ``where`` (int64), ``qnext`` and ``qprev`` (int32) may be given, e.g. as fields of per-entry
    records; the rest is made. ``buckets``: use time buckets, or keep every entry in the heap
    (default: buckets from :data:`BUCKETS_FROM` entries on). Fill it with
    :func:`calendar_build`.
    """
    heap, where, key_t, key_s = new_heap(n, where)
    if buckets is None:
        buckets = n >= BUCKETS_FROM
    nb = max(MIN_BUCKETS, 1 << max(0, n - 1).bit_length()) if buckets else 0
    if qnext is None:
        qnext = np.full(n, -1, dtype=np.int32)
    if qprev is None:
        qprev = np.full(n, -1, dtype=np.int32)
    qi = np.zeros(Q_LEN, dtype=np.int64)
    qi[Q_NB] = nb
    qf = np.zeros(F_LEN)
    qf[F_INV_W] = 1.0
    cal = (heap, where, key_t, key_s, np.full(max(nb, 1), -1, dtype=np.int64), qnext, qprev, qi,
           qf)
    return (*cal, np.zeros(0, dtype=np.int8)) if buckets else cal


@njit(inline="always")
def has_buckets(cal):
    """Whether the calendar has time buckets: a constant of its type (its length), so that
    compiled code for a calendar without buckets holds none of theirs."""
    return len(cal) > HEAP_ONLY


@njit(inline="always")
def _link(e, first, qnext, qprev):
    """Put e in front of the list that starts at ``first``; returns the new first entry."""
    qnext[e] = first
    qprev[e] = -1
    if first >= 0:
        qprev[first] = e
    return e


@njit(inline="always")
def _unlink(e, cal):
    """Take e out of its list (bucket or overflow)."""
    where, bhead, qnext, qprev, qi = cal[1], cal[4], cal[5], cal[6], cal[7]
    loc = where[e]
    a = qprev[e]
    b = qnext[e]
    if a >= 0:
        qnext[a] = b
    elif loc == IN_OVERFLOW:
        qi[Q_OVF] = b
    else:
        bhead[IN_BUCKET0 - loc] = b
    if b >= 0:
        qprev[b] = a
    if loc != IN_OVERFLOW:
        qi[Q_LISTED] -= 1


@njit(inline="always")
def _place(e, t, s, cal):
    """Put e (in no structure) with key (t, s) where its bucket says."""
    heap, where, key_t, key_s, bhead, qnext, qprev, qi, qf = cal[:HEAP_ONLY]
    x = (t - qf[F_BASE]) * qf[F_INV_W]
    cur = qi[Q_CUR]
    nb = qi[Q_NB]
    if not has_buckets(cal) or x < cur + 1:  # no buckets, or B(t) ≤ cur
        qi[Q_SIZE] = heap_push(heap, where, key_t, key_s, qi[Q_SIZE], e, t, s)
        qi[Q_PASSED] += 1
    elif x < cur + nb:  # within the next nb − 1 buckets (inf and NaN are not)
        slot = np.int64(x) & (nb - 1)
        bhead[slot] = _link(e, bhead[slot], qnext, qprev)
        where[e] = IN_BUCKET0 - slot
        qi[Q_LISTED] += 1
    else:
        qi[Q_OVF] = _link(e, qi[Q_OVF], qnext, qprev)
        where[e] = IN_OVERFLOW


@njit(inline="always")
def calendar_update(cal, key_time, key_seq, e):
    """Entry e has a new key (``key_time[e]``, ``key_seq[e]``): move it accordingly."""
    heap, where, key_t, key_s, qi, qf = cal[0], cal[1], cal[2], cal[3], cal[7], cal[8]
    t = key_time[e]
    s = key_seq[e]
    if where[e] >= 0:
        if not has_buckets(cal) or (t - qf[F_BASE]) * qf[F_INV_W] < qi[Q_CUR] + 1:
            heap_change(heap, where, key_t, key_s, qi[Q_SIZE], e, t, s)
            return
        qi[Q_SIZE] = heap_remove(heap, where, key_t, key_s, qi[Q_SIZE], e)
    else:
        _unlink(e, cal)
    _place(e, t, s, cal)


@njit(inline="always")
def calendar_prefetch(cal, key_time, e):
    """Ask for what :func:`calendar_update` of entry e will touch: the list head of its new
    bucket and its neighbours in the list it is in (a hint only)."""
    where, bhead, qnext, qprev, qi, qf = cal[1], cal[4], cal[5], cal[6], cal[7], cal[8]
    if not has_buckets(cal):
        return  # every entry is in the heap, which is in the cache
    if where[e] < 0:
        if qprev[e] >= 0:
            prefetch(qnext, qprev[e])
        if qnext[e] >= 0:
            prefetch(qnext, qnext[e])
    x = (key_time[e] - qf[F_BASE]) * qf[F_INV_W]
    if qi[Q_CUR] + 1 <= x < qi[Q_CUR] + qi[Q_NB]:
        prefetch(bhead, np.int64(x) & (qi[Q_NB] - 1))


@njit(allocates=True)
def calendar_build(cal, key_time, key_seq, inv_w):
    """(Re)build the calendar from every entry's key, with bucket 0 starting at the earliest
    finite key. ``inv_w`` [1/s]: 1 / bucket width, or 0 to choose it from the keys: about
    BUCKET_TARGET entries per bucket at the rate the keys spread out near their start (for keys
    spread like the next events of N independent spheres, exponentially with mean τ, the median
    lies at τ ln 2 and N/τ entries fall in each second near the start).

    Returns:
        Whether any key is finite (else every entry is unscheduled).
    """
    bhead, qi, qf = cal[4], cal[7], cal[8]
    n = key_time.shape[0]
    t0 = math.inf
    for e in range(n):
        if key_time[e] < t0:
            t0 = key_time[e]
    finite = t0 < math.inf
    if not finite:
        t0 = 0.0
    choose = inv_w <= 0.0
    if choose:
        inv_w = 1.0  # (without buckets it is never used, but keeps (inf − base) · w⁻¹ a number)
    if choose and has_buckets(cal):
        gaps = np.empty(n)
        m = 0
        for e in range(n):
            if key_time[e] < math.inf:
                gaps[m] = key_time[e] - t0
                m += 1
        if m >= 2:
            median = np.median(gaps[:m])
            if median > 0.0:
                inv_w = m * math.log(2.0) / median / BUCKET_TARGET
    qf[F_BASE] = t0
    qf[F_INV_W] = inv_w
    qi[Q_SIZE] = 0
    qi[Q_CUR] = 0
    qi[Q_OVF] = -1
    qi[Q_LISTED] = 0
    qi[Q_PASSED] = 0
    bhead[:] = -1
    for e in range(n):
        _place(e, key_time[e], key_seq[e], cal)
    return finite


@njit
def _revolution(cal, key_time, key_seq):
    """``cur`` has reached a multiple of nb: re-choose the width if the last revolution was far
    off the target (a rebuild; returns True), else sort the overflow list into the buckets it
    now reaches (returns False)."""
    qi, qf = cal[7], cal[8]
    nb = qi[Q_NB]
    passed = qi[Q_PASSED]
    target = BUCKET_TARGET * nb
    if passed > RETUNE_FACTOR * target or passed * RETUNE_FACTOR < target \
            or qi[Q_CUR] >= REBASE_BUCKETS:
        factor = min(RETUNE_MAX, max(1.0 / RETUNE_MAX, target / max(passed, 1)))
        calendar_build(cal, key_time, key_seq, qf[F_INV_W] * factor)
        return True
    qi[Q_PASSED] = 0
    qnext = cal[5]
    e = qi[Q_OVF]
    qi[Q_OVF] = -1
    while e >= 0:
        nxt = qnext[e]
        _place(e, key_time[e], key_seq[e], cal)
        e = nxt
    return False


@njit(inline="always")
def _prefetch_ahead(slot, cal, key_time):
    """Ask for the records of the entries the next drains will read, a list walk in steps: the
    first entry of the bucket after next, and the second of the next bucket (whose first
    entry was asked for at the previous drain, so reading its link costs no wait)."""
    bhead, qnext, qi = cal[4], cal[5], cal[7]
    mask = qi[Q_NB] - 1
    a = bhead[(slot + 2) & mask]
    if a >= 0:
        prefetch(key_time, a)
        prefetch(qnext, a)
    a = bhead[(slot + 1) & mask]
    if a >= 0:
        b = qnext[a]
        if b >= 0:
            prefetch(key_time, b)
            prefetch(qnext, b)


@njit(inline="always")
def calendar_runner_up(cal):
    """The entry likely to come after the top one, or −1: the earliest of the top's children
    in the heap of the current bucket (a guess, for prefetching; the entry after the top may
    also be deeper in the heap, or in the next bucket)."""
    heap, key_t = cal[0], cal[2]
    last = min(ARITY, cal[7][Q_SIZE] - 1)
    if last < 1:
        return -1
    best = 1
    for c in range(2, last + 1):
        if key_t[c] < key_t[best]:
            best = c
    return heap[best]


@njit(inline="always")
def calendar_top(cal, key_time, key_seq):
    """The entry with the earliest key and its time [s] (−1 and inf if every key is inf)."""
    heap, where, key_t, key_s, bhead, qnext, _, qi, qf = cal[:HEAP_ONLY]
    while qi[Q_SIZE] == 0:
        if not has_buckets(cal):
            return -1, math.inf  # no entries at all
        if qi[Q_LISTED] == 0:
            # nothing in the next nb − 1 buckets: start again from the earliest key, if any
            if qi[Q_OVF] < 0 or not calendar_build(cal, key_time, key_seq, qf[F_INV_W]):
                return -1, math.inf
            continue
        qi[Q_CUR] += 1
        if qi[Q_CUR] & (qi[Q_NB] - 1) == 0 and _revolution(cal, key_time, key_seq):
            continue
        slot = qi[Q_CUR] & (qi[Q_NB] - 1)
        e = bhead[slot]
        bhead[slot] = -1
        _prefetch_ahead(slot, cal, key_time)
        size = qi[Q_SIZE]
        while e >= 0:
            nxt = qnext[e]
            size = heap_push(heap, where, key_t, key_s, size, e, key_time[e], key_seq[e])
            qi[Q_LISTED] -= 1
            qi[Q_PASSED] += 1
            e = nxt
        qi[Q_SIZE] = size
    return heap[0], key_t[0]
