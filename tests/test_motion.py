"""Contact times of free flight (hsgran.motion): the quadratic and quartic roots, and how touching
spheres are told apart from approaching ones at the rounding level (MODEL-independent kinematics;
docs/enduring-contact.md)."""

import itertools
import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from hsgran.motion import (
    APPROACH_NOISE_ULPS,
    NEVER,
    OUT_OF_REACH_MARGIN,
    approach_noise,
    cylinder_contact_time,
    pair_contact_accelerated,
    pair_contact_before,
    plane_contact_time,
    upward_root,
)

#: Contact times here are roots of well-conditioned polynomials; rounding only.
ROOT_RTOL = 1e-9
#: Unit round-off of a double [-].
EPS = np.finfo(float).eps


def test_upward_root_of_a_parabola():
    assert upward_root(-1.0, 0.0, 2.0) == pytest.approx(1.0, rel=1e-15)  # −1 + τ²
    assert upward_root(-1.0, 1.0, 0.0) == pytest.approx(1.0, rel=1e-15)  # −1 + τ
    assert upward_root(-1.0, 0.0, -2.0) == NEVER  # never reaches zero
    assert upward_root(1e-20, 1.0, 0.0) == 0.0  # already past the crossing: now


def test_head_on_pair_meets_after_gap_over_speed():
    assert pair_contact_before(3.0, 0.0, 0.0, -1.0, 0.0, 0.0, 2.0, NEVER) == pytest.approx(1.0)
    assert pair_contact_before(3.0, 0.0, 0.0, 1.0, 0.0, 0.0, 2.0, NEVER) == NEVER
    # a horizon before the contact: none reported
    assert pair_contact_before(3.0, 0.0, 0.0, -1.0, 0.0, 0.0, 2.0, 0.5) == NEVER


def _touching_pair(vn, vt=1.5e-3, sigma=2.2e-3, x=0.05):
    """Touching spheres (|r| = σ), relative velocity vn along r and vt across it [m/s]; and the
    rounding scales (Σ|v|, Σ|x|) of two such spheres near x [m]."""
    n = np.array([1.0, 0.0, 0.0])  # axis-aligned: r and w are exact, |r| = σ exactly
    t = np.array([0.0, 1.0, 0.0])
    r = sigma * n
    w = vn * n + vt * t
    return r, w, sigma, 2.0 * vt, 6.0 * x


def test_touching_pair_approaching_below_rounding_does_not_touch_again():
    # the diagnosed loop: met at ~1e-20 m/s by a neighbour moving at 1.5e-3 m/s
    r, w, sigma, vs, xs = _touching_pair(-1e-20)
    assert 1e-20 < approach_noise(sigma, vs, xs) / sigma
    assert pair_contact_before(*r, *w, sigma, NEVER, vs, xs) == NEVER
    # without the rounding scales any approach is a contact: now
    assert pair_contact_before(*r, *w, sigma, NEVER) == 0.0


def test_touching_pair_approaching_beyond_rounding_touches_now():
    r, w, sigma, vs, xs = _touching_pair(-1e-9)
    assert pair_contact_before(*r, *w, sigma, NEVER, vs, xs) == 0.0


@pytest.mark.parametrize("gn", [0.0, 0.23, 9.81])
def test_touching_plane_approached_below_rounding_without_load_is_no_contact(gn):
    """The diagnosed loop: a cluster solve left a sphere moving at 3.7e-4 m/s touching an
    overhanging plane (gravity along n: +0.23 m/s²) at −1e-22 m/s; met again at that instant
    for ever. Below the rounding of vn and not pressed: no contact (gn = 0, a vertical wall:
    a straight line into it at 1e-22 m/s is noise too)."""
    v_sum = 3.7e-4 + 8.5e-7 + 3.6e-5
    assert 1e-22 < APPROACH_NOISE_ULPS * EPS * v_sum
    assert plane_contact_time(0.0, -1e-22, gn, v_sum) == NEVER
    # without the rounding scale any approach of a touching sphere is a contact: now
    assert plane_contact_time(0.0, -1e-22, gn) == 0.0


def test_touching_plane_pressed_or_approached_beyond_rounding_is_a_contact_now():
    v_sum = 4.1e-4
    assert plane_contact_time(0.0, -1e-22, -9.81, v_sum) == 0.0  # pressed: gravity into it
    assert plane_contact_time(0.0, -1e-12, 0.23, v_sum) == 0.0  # approaching beyond rounding
    # apart by a gap: the noise rule is not for it
    assert plane_contact_time(1e-12, -1e-22, 0.0, v_sum) == pytest.approx(1e10, rel=1e-12)


def _first_descent_by_sampling(r, w, a, sigma, horizon, n=200001):
    """Reference: first sample where |r + wτ + ½aτ²| drops to σ, refined by bisection."""
    tau = np.linspace(0.0, horizon, n)
    d = r[None, :] + w[None, :] * tau[:, None] + 0.5 * a[None, :] * tau[:, None] ** 2
    f = np.einsum("ij,ij->i", d, d) - sigma * sigma
    k = np.nonzero((f[:-1] > 0.0) & (f[1:] <= 0.0))[0]
    if len(k) == 0:
        return NEVER
    lo, hi = tau[k[0]], tau[k[0] + 1]
    for _ in range(100):
        mid = 0.5 * (lo + hi)
        dm = r + w * mid + 0.5 * a * mid * mid
        if dm @ dm - sigma * sigma > 0.0:
            lo = mid
        else:
            hi = mid
    return hi


def test_touching_pair_separating_under_a_pressing_acceleration_meets_later_not_now():
    # A sphere in flight touching one at rest (gap at the rounding level, 4e-19 m), just hopped
    # off at 3e-5 m/s, gravity pressing it back: the next contact is ~1e-5 s later. The sign of
    # the gap polynomial near τ = 0 is round-off; it once gave a "contact" 1e-17 s later, again
    # and again, until the collapse guard stopped a pour.
    sigma = 2.17e-3
    n = np.array([0.44, 0.52, 0.62])
    n /= np.linalg.norm(n)
    t = np.cross(n, [0.0, 0.0, 1.0])
    t /= np.linalg.norm(t)
    r = (sigma + 4e-19) * n
    w = 3.05e-5 * n + 7e-3 * t
    a = np.array([0.0, 0.0, -9.81])
    vs, xs = 1.4e-2, 0.13
    tau = pair_contact_accelerated(*r, *w, *a, sigma, NEVER, vs, xs)
    ref = _first_descent_by_sampling(r, w, a, sigma, 1e-4)
    assert 1e-6 < tau < 1e-4
    assert tau == pytest.approx(ref, rel=1e-6)
    # the same with a finite horizon beyond the contact
    assert pair_contact_accelerated(*r, *w, *a, sigma, 5e-5, vs, xs) == pytest.approx(tau)


def test_touching_pair_pressed_together_without_approach_touches_now():
    # a sphere in flight resting on one at rest: no approach, gravity presses: contact now
    sigma = 2e-3
    r = np.array([0.0, 0.0, sigma * (1.0 - 1e-16)])
    w = np.array([1e-21, 0.0, 0.0])
    a = np.array([0.0, 0.0, -9.81])
    assert pair_contact_accelerated(*r, *w, *a, sigma, NEVER, 1e-3, 0.1) == 0.0


@pytest.mark.parametrize("weak", [1e-9, 1e-7])
def test_touching_pair_pressed_only_by_rounding_is_not_met_now(weak):
    """Two spheres falling side by side, one in constrained motion: their accelerations differ
    by rounding (1e-13 m/s², along the tangent) and their distance by 7e-18 m of tangential
    offset (hsgran.motion.pressed): f'' < 0, but the fall it makes (~1e-34 m²) is far below the
    rounding of the distance, so they are not met at once (a solve of it gives no impulse, and
    they were met again at one instant). A pressing of ``weak`` m/s² along the normal is one."""
    sigma = 2e-3
    r = (-sigma, 0.0, 6.938893903907228e-18)
    w = (0.0, 0.0, 1.942890293094024e-16)
    a = (0.0, 0.0, -9.592326932761353e-14)
    vs, xs = 0.25113600000005976, 0.1023927296000012
    assert pair_contact_accelerated(*r, *w, *a, sigma, 1e-4, vs, xs) > 0.0
    assert pair_contact_accelerated(*r, *w, *a, sigma, NEVER, vs, xs) > 0.0
    assert pair_contact_accelerated(*r, *w, weak, 0.0, a[2], sigma, 1e-4, vs, xs) == 0.0


def _return_time(r, w, a, sign=1.0):
    """Reference: the first τ > 0 where sign (|r + wτ + ½aτ²|² − |r|²) falls back through 0,
    by bisection in extended precision after a scan."""
    r, w, a = (np.asarray(x, np.longdouble) for x in (r, w, a))

    def f(t):  # |r + D|² − |r|² = 2 r·D + |D|², free of cancellation
        d = t * (w + 0.5 * a * t)
        return sign * (2.0 * (r * d).sum() + (d * d).sum())

    ts = np.geomspace(1e-14, 1.0, 20001)
    k = next(k for k in range(1, ts.size) if f(ts[k - 1]) > 0 >= f(ts[k]))
    lo, hi = np.longdouble(ts[k - 1]), np.longdouble(ts[k])
    for _ in range(200):
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if f(mid) > 0 else (lo, mid)
    return float(hi)


@settings(max_examples=80, deadline=None)
@given(
    theta=st.floats(0.0, math.pi), phi=st.floats(0.0, 2.0 * math.pi),
    overlap=st.floats(1e-13, 1e-9), clear=st.floats(0.01, 0.9), slip=st.floats(0.0, 1.0),
    press=st.floats(0.5, 30.0), across=st.floats(-10.0, 10.0),
)
def test_overlapping_pair_separating_too_slowly_to_clear_meets_on_its_way_back(
        theta, phi, overlap, clear, slip, press, across):
    # Two spheres overlapping by round-off (σ − |r| = overlap σ), separating along n too slowly
    # to clear σ before the pressing acceleration brings them back (the peak of the distance,
    # un²/2a, is a fraction `clear` of the overlap): no descent through σ exists, and the
    # search once returned "never", so they passed through each other (a 7 % overlap in a
    # corpus pour). They are met where they come back to the distance they have now.
    sigma = 2e-3
    n = np.array([math.sin(theta) * math.cos(phi), math.sin(theta) * math.sin(phi),
                  math.cos(theta)])
    t = np.cross(n, [0.3, -0.5, 0.8])
    t /= np.linalg.norm(t)
    r = sigma * (1.0 - overlap) * n
    # tangential sliding takes the spheres apart as fast as an acceleration |w_t|²/σ would,
    # which the pressing acceleration must beat for the pair to come back
    wt = slip * math.sqrt(0.5 * press * sigma)
    a_n = press - wt * wt / sigma
    un = math.sqrt(2.0 * clear * overlap * sigma * a_n)
    w = un * n + wt * t
    a = -press * n + across * np.cross(n, t)
    tau = pair_contact_accelerated(*r, *w, *a, sigma, NEVER, 1e-3, 0.05)
    assert tau < NEVER
    # f = |d|² − |r|² near the root carries the rounding of |d|² (a few ulp of σ²) and falls
    # at 2σ un: the root is that uncertain in time
    assert abs(tau - _return_time(r, w, a)) <= 1e-9 * tau + 8.0 * EPS * sigma / un


def test_sphere_overlapping_a_drum_and_moving_inwards_too_slowly_meets_it_on_its_way_back():
    # the same inside a cylinder (side +1): a sphere overlapping the wall of a horizontal drum
    # by round-off, leaving it at 5e-9 m/s, gravity pulling it back against the wall
    rho = 0.049
    q = np.array([0.0, 0.0, -rho * (1.0 + 1e-15)])
    u = np.array([1e-3, 0.0, 5e-9])
    g = np.array([0.0, 0.0, -9.81])
    tau = cylinder_contact_time(*q, *u, *g, rho, 1.0, NEVER, 1e-3, 0.1)
    assert tau < NEVER
    assert abs(tau - _return_time(q, u, g, sign=-1.0)) <= 1e-9 * tau + 8.0 * EPS * rho / 5e-9
    # leaving it ten times slower, the excursion (1e-20 m) is below the rounding of the
    # position (5e-18 m): it is met where it starts to come back, not never
    u[2] = 5e-10
    tau = cylinder_contact_time(*q, *u, *g, rho, 1.0, NEVER, 1e-3, 0.1)
    assert tau == pytest.approx(5e-10 * rho / (rho * 9.81 + 1e-6), rel=1e-6)


@settings(max_examples=60, deadline=None)
@given(
    ux=st.floats(-1.0, 1.0), uy=st.floats(-1.0, 1.0), uz=st.floats(-1.0, 1.0),
    speed=st.floats(1e-3, 1.0), t_hit=st.floats(1e-4, 1e-2),
    ax=st.floats(-20.0, 20.0), ay=st.floats(-20.0, 20.0), az=st.floats(-20.0, 20.0),
)
def test_accelerated_contact_is_the_first_descent(ux, uy, uz, speed, t_hit, ax, ay, az):
    # build a pair that touches at t_hit while approaching; the quartic must return that
    # contact or an earlier one, and f must stay positive before it
    u = np.array([ux, uy, uz])
    if np.linalg.norm(u) < 0.1:
        u = np.array([1.0, 0.0, 0.0])
    u /= np.linalg.norm(u)
    sigma = 2e-3
    a = np.array([ax, ay, az])
    w_hit = -speed * u  # approaching at contact
    w0 = w_hit - a * t_hit
    r0 = sigma * u - w0 * t_hit - 0.5 * a * t_hit * t_hit
    if r0 @ r0 <= sigma * sigma * (1.0 + 1e-6):
        return  # starts touching: not this property
    tau = pair_contact_accelerated(*r0, *w0, *a, sigma, NEVER)
    assert tau <= t_hit * (1.0 + ROOT_RTOL)
    ref = _first_descent_by_sampling(r0, w0, a, sigma, t_hit * (1.0 + 1e-6), n=20001)
    assert tau == pytest.approx(ref, rel=1e-6, abs=1e-12)
    d = r0 + w0 * tau + 0.5 * a * tau * tau
    assert math.sqrt(d @ d) == pytest.approx(sigma, rel=1e-9)


def _out_of_reach_cases(count, seed):
    """Pairs of spheres (σ = 2 mm) at gaps from 1e-8 σ to σ, with relative velocities up to
    1 m/s and accelerations up to 20 m/s² in random directions, and horizons 1 µs to 0.1 s."""
    rng = np.random.default_rng(seed)
    sigma = 2e-3
    for _ in range(count):
        n = rng.normal(size=3)
        n /= np.linalg.norm(n)
        r = n * sigma * (1.0 + 10.0 ** rng.uniform(-8, 0))
        w = rng.normal(size=3) * 10.0 ** rng.uniform(-4, 0)
        a = rng.normal(size=3) * 10.0 ** rng.uniform(-2, 1.3)
        yield r, w, a, sigma, 10.0 ** rng.uniform(-6, -1)


def test_a_quartic_contact_skipped_as_out_of_reach_is_none_before_the_horizon():
    """pair_contact_accelerated skips its search where the pair cannot close to σ before the
    horizon (its distance stays above its projection on today's separation): whenever it says
    "none before the horizon", the full search (no horizon, nothing skipped) finds the first
    contact only after it, or never. 3000 random pairs near and far, passing side by side,
    approaching and leaving; among them the pairs this bound skips and the bound before
    2026-11-28 (|w| and |a| in full) did not."""
    out = 1.0 + OUT_OF_REACH_MARGIN
    newly_skipped = 0
    for r, w, a, sigma, h in _out_of_reach_cases(3000, 11):
        tau = pair_contact_accelerated(*r, *w, *a, sigma, h)
        full = pair_contact_accelerated(*r, *w, *a, sigma, NEVER)
        if tau == NEVER:
            assert full > h, (r, w, a, h, full)
        else:
            assert tau <= h
        d = np.linalg.norm(r)
        skip = d - h * (max(-(r @ w) / d, 0.0) + 0.5 * h * max(-(r @ a) / d, 0.0)) > sigma * out
        old_skip = d - h * (np.linalg.norm(w) + 0.5 * h * np.linalg.norm(a)) > sigma * out
        assert skip or not old_skip  # the projection never skips less
        if skip:
            assert tau == NEVER
            assert full > h, (r, w, a, h, full)
            newly_skipped += not old_skip
    assert newly_skipped > 100


def _exact_contact_time(r, w, a, sigma, first_guess):
    """Reference: the first τ where f = |r + wτ + ½aτ²|² − σ² falls through zero, with f(0) =
    |r|² − σ² exact (rational arithmetic) and the displacement terms 2 r·D + |D|² in extended
    precision; a scan of (0, 4 first_guess] for the first sign change, then bisection."""
    from fractions import Fraction

    ld = np.longdouble
    exact = sum(Fraction(float(x)) ** 2 for x in r) - Fraction(float(sigma)) ** 2
    head = float(exact)
    f0 = ld(head) + ld(float(exact - Fraction(head)))
    r, w, a = (np.asarray(x, ld) for x in (r, w, a))

    def f(t):
        t = np.asarray(t, ld)[..., None]
        d = t * (w + 0.5 * a * t)
        return f0 + 2.0 * (d * r).sum(-1) + (d * d).sum(-1)

    ts = np.linspace(ld(0.0), ld(4.0 * first_guess), 40001)
    fs = f(ts)
    k = int(np.nonzero((fs[:-1] > 0) & (fs[1:] <= 0))[0][0])
    lo, hi = ts[k], ts[k + 1]
    for _ in range(100):
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if f(mid) > 0 else (lo, mid)
    return hi, (w + a * hi), (r + hi * (w + 0.5 * a * hi))


def test_quartic_contact_time_is_accurate_to_round_off():
    # A sphere approaching another through a gap of 1e-9 … 0.1 σ, sliding across it, under
    # different accelerations, none pulling them apart (a flying sphere near one that rolls or
    # rests): the contact time is the exact root to a few units of round-off, times the
    # conditioning of the crossing (|u||d|/|d·u|: a grazing approach moves the root further
    # per unit of error in f). f is measured from f(0) = |r|² − σ² summed exactly and from the
    # displacement (the rounding of |r + D|² evaluated whole, ~1e-16 σ², moved these roots by
    # up to 4e8 such units).
    rng = np.random.default_rng(11)
    worst = 0.0
    checked = 0
    for _ in range(200):
        sigma = 2e-3 * rng.uniform(0.5, 2.0)
        n = rng.normal(size=3)
        n /= np.linalg.norm(n)
        t = rng.normal(size=3)
        t -= (t @ n) * n
        t /= np.linalg.norm(t)
        gap = sigma * 10.0 ** rng.uniform(-9.0, -1.0)
        un = 10.0 ** rng.uniform(-4.0, 0.0)
        r = (sigma + gap) * n
        w = -un * n + 10.0 ** rng.uniform(-4.0, 0.0) * t
        a = rng.normal(size=3)
        a -= max(a @ n, 0.0) * n  # (not pulling them apart: they do meet)
        a *= 10.0 ** rng.uniform(-1.0, 1.3) / np.linalg.norm(a)
        tau = pair_contact_accelerated(*r, *w, *a, sigma, NEVER)
        if tau == NEVER:
            continue  # slides past: the lift of the curved surface beats the approach
        ref, u, d = _exact_contact_time(r, w, a, sigma, tau)
        cond = float(np.sqrt(u @ u) * np.sqrt(d @ d) / abs(d @ u))
        worst = max(worst, float(abs(np.longdouble(tau) - ref) / ref) / (EPS * cond))
        checked += 1
    assert checked >= 150
    assert worst <= ROOT_ROUNDOFF_UNITS


#: Units of round-off (times the conditioning of the crossing) to which a quartic contact
#: time meets the exact root: the rounding of f near the root, a few units of |r||D|, over its
#: slope (measured: 2.1 over 3,000 random approaches).
ROOT_ROUNDOFF_UNITS = 8.0


@settings(max_examples=300, deadline=None)
@given(
    c=st.lists(st.floats(-1e3, 1e3, allow_nan=False), min_size=4, max_size=4),
    span=st.floats(1e-9, 1e3), where=st.floats(0.0, 1.0),
)
def test_root_search_ends_at_the_two_doubles_where_the_sign_changes(c, span, where):
    # _bracketed_root's contract on a piece where g = f' of a quartic changes sign: the two
    # doubles it returns are adjacent, g at the lower on the side g(lo) was, at the upper not
    # (the bracket keeps its ends' sides, so this holds where g is not monotone too)
    from hsgran.motion import _bracketed_root, _dpoly

    c4 = abs(c[0]) + 1e-3
    lo = where * span
    hi = lo + span
    flo = _dpoly(c4, c[1], c[2], c[3], lo)
    fhi = _dpoly(c4, c[1], c[2], c[3], hi)
    if (flo > 0.0) == (fhi > 0.0):
        return  # no sign change on this piece
    a, b = _bracketed_root(True, c4, c[1], c[2], c[3], 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0,
                           0.0, 0.0, 0.0, lo, hi, flo, fhi)
    assert lo <= a < b <= hi
    assert np.nextafter(a, math.inf) == b
    assert (_dpoly(c4, c[1], c[2], c[3], a) > 0.0) == (flo > 0.0)
    assert (_dpoly(c4, c[1], c[2], c[3], b) > 0.0) != (flo > 0.0)


def _falling_pieces(r, w, a, sigma, horizon):
    """The pieces [lo, hi] of a quartic pair's search (as hsgran.motion._first_fall splits it)
    on which f' rises through zero: f is convex there, with its minimum inside."""
    from hsgran.motion import _dpoly, root_horizon

    c4 = 0.25 * float(a @ a)
    c3 = float(w @ a)
    c2 = float(w @ w + r @ a)
    c1 = 2.0 * float(r @ w)
    c0 = float(r @ r) - sigma * sigma
    h = root_horizon(c4, c3, c2, c1, c0, horizon)
    roots = np.roots([12.0 * c4, 6.0 * c3, 2.0 * c2])
    cuts = sorted(float(q.real) for q in roots if q.imag == 0.0 and 0.0 < q.real < h)
    bounds = [0.0, *cuts, h]
    return [(lo, hi) for lo, hi in itertools.pairwise(bounds)
            if _dpoly(c4, c3, c2, c1, lo) < 0.0 < _dpoly(c4, c3, c2, c1, hi)]


def _least_gap(r, w, a, sigma, lo, hi):
    """min f on [lo, hi], where f' rises through zero: f at the two doubles between which the
    exact f' changes sign, in rational arithmetic."""
    from fractions import Fraction

    rr, ww, aa = ([Fraction(float(x)) for x in v] for v in (r, w, a))

    def d_u(tau):
        tau = Fraction(tau)
        d = [p + q * tau + b * tau * tau / 2 for p, q, b in zip(rr, ww, aa, strict=True)]
        return d, [q + b * tau for q, b in zip(ww, aa, strict=True)]

    def slope(tau):
        d, u = d_u(tau)
        return sum(x * y for x, y in zip(d, u, strict=True))

    p, q = lo, hi
    for _ in range(200):
        mid = 0.5 * (p + q)
        if not p < mid < q:
            break
        p, q = (mid, q) if slope(mid) < 0 else (p, mid)
    return min(sum(x * x for x in d_u(tau)[0]) for tau in (p, q)) - Fraction(sigma) ** 2


def test_a_convex_piece_is_cleared_only_where_the_distance_stays_above_contact():
    # _clear_minimum lets the quartic search skip a piece where f = |d|² − σ² falls to a
    # minimum and rises again without reaching zero (a flying sphere passing a resting one).
    # Where it clears a piece, f's least value there (exact) is above zero; and it clears
    # most of the passes that stay 1e-6 σ² clear of contact, within horizons of a few times
    # the time the pair takes to pass.
    from hsgran.motion import _clear_minimum, gap_at_start

    rng = np.random.default_rng(5)
    cleared = clear_passes = cleared_clear_passes = 0
    for _ in range(1500):
        sigma = 2e-3 * rng.uniform(0.5, 2.0)
        n = rng.normal(size=3)
        n /= np.linalg.norm(n)
        r = sigma * (1.0 + 10.0 ** rng.uniform(-8.0, 0.0)) * n
        w = rng.normal(size=3) * 10.0 ** rng.uniform(-3.0, 0.0)
        a = rng.normal(size=3) * 10.0 ** rng.uniform(-1.0, 1.3)
        horizon = sigma / np.linalg.norm(w) * 10.0 ** rng.uniform(-1.0, 1.0)
        for lo, hi in _falling_pieces(r, w, a, sigma, horizon):
            least = _least_gap(r, w, a, sigma, lo, hi)
            ok = _clear_minimum(*r, *w, *a, gap_at_start(*r, sigma), 1.0, lo, hi)
            if ok:
                cleared += 1
                assert least > 0, (r, w, a, sigma, lo, hi)
            if least > 1e-6 * sigma * sigma:
                clear_passes += 1
                cleared_clear_passes += ok
    assert cleared >= 100
    assert cleared_clear_passes >= 0.9 * clear_passes, (cleared_clear_passes, clear_passes)
