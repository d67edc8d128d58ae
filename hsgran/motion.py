"""Free flight and every "when" question of the event loop (layer 2: kinematics only).

Between events a sphere follows an exact parabola x(τ) = x0 + v τ + ½ g τ² (a straight line
without gravity). Two spheres under the same gravity move linearly relative to each other, so
their contact time is the root of a quadratic; so are the times at which a sphere reaches a plane
or a cell face. Every such question reduces to :func:`upward_root`: the first time a quadratic
``c + b τ + ½ a τ²`` crosses zero going up.

All functions are compiled and take scalars; ``inf`` means "never".
"""

from __future__ import annotations

import math

import numpy as np

from hsgran._jit import njit

NEVER = math.inf


@njit
def upward_root(c, b, a):
    """First τ ≥ 0 at which f(τ) = c + b τ + ½ a τ² crosses zero with f' > 0.

    A slightly positive ``c`` (round-off has already carried the point past the crossing) is
    treated as zero, so a crossing that is under way happens now (τ = 0) instead of being lost.

    Args:
        c: f(0) (should be ≤ 0).
        b: f'(0).
        a: f'' (constant).

    Returns:
        τ ≥ 0, or ``inf`` if f never crosses zero upwards.

    Notes:
        The two roots are τ± = (−b ± s)/a with s² = b² − 2 a c, and f'(τ±) = ±s, so the upward
        crossing is always τ+. For b ≥ 0 it is evaluated as −2c/(b + s) to avoid cancellation.
    """
    if c > 0.0:
        c = 0.0
    if a == 0.0:
        if b > 0.0:
            return -c / b
        return NEVER
    disc = b * b - 2.0 * a * c
    if disc < 0.0:
        return NEVER
    s = math.sqrt(disc)
    if b >= 0.0:
        den = b + s
        if den > 0.0:
            return -2.0 * c / den
        return 0.0 if a > 0.0 else NEVER  # c = b = 0: f = ½ a τ²
    if a > 0.0:
        return (s - b) / a
    return NEVER


@njit
def flight_position(x0, v0, g, dt):
    """Coordinate after a free flight of ``dt`` [s]: x0 + v0 dt + ½ g dt² [m]."""
    return x0 + dt * (v0 + 0.5 * g * dt)


@njit
def pair_contact_time(rx, ry, rz, wx, wy, wz, sigma):
    """Time until two spheres in free flight touch.

    Args:
        rx, ry, rz: Relative position x_i − x_j at a common instant [m].
        wx, wy, wz: Relative velocity v_i − v_j [m/s] (constant: gravity cancels).
        sigma: Contact distance R_i + R_j [m].

    Returns:
        Delay τ ≥ 0 [s] until |r + w τ| = σ while approaching, or ``inf``.
    """
    rr = rx * rx + ry * ry + rz * rz
    rw = rx * wx + ry * wy + rz * wz
    if rw >= 0.0:
        return NEVER  # separating or sliding past: no approach
    ww = wx * wx + wy * wy + wz * wz
    # f(τ) = σ² − |r + wτ|² crosses zero upwards at contact
    return upward_root(sigma * sigma - rr, -2.0 * rw, -2.0 * ww)


#: Unit round-off of a double [-].
ROUNDOFF = float(np.finfo(np.float64).eps)
#: Units of round-off within which the normal approach of touching spheres is noise [-]. The
#: normal relative velocity r·w/|r| of touching spheres carries the rounding of both velocities
#: and, through the direction of r, of both positions; an approach below that level is not a
#: collision: the impulse it would give cannot change velocities that large (a sphere met at
#: 1e-20 m/s by a neighbour moving at 1.5e-3 m/s got 8e-25 N s, which left both unchanged and
#: was met again at the same instant until the collapse guard stopped the run). 16 units leave
#: room for the few roundings in r and w; ignoring such an approach lets an overlap grow at most
#: at that speed (~1e-16 m/s for millimetre spheres at 1e-3 m/s in a 0.1 m box). [OURS]
APPROACH_NOISE_ULPS = 16.0
#: Spheres count as touching, for the noise test, while |r|² is within this fraction of σ² [-]
#: (a gap or overlap of 5e-11 σ): far above the rounding of |r|² (~1e-14 σ² for positions of
#: a few hundred σ) and far below the 1e-9 R overlap a run must stay under.
TOUCHING_REL = 1e-10


@njit(inline="always")
def approach_noise(sigma, v_sum, x_sum):
    """Rounding level of r·w for touching spheres [m²/s]: |r| ≈ σ carries the rounding of the
    velocities (``v_sum`` = Σ|v_k| of both spheres [m/s]), |w| ≤ v_sum that of the positions
    (``x_sum`` = Σ|x_k| of both [m]). See APPROACH_NOISE_ULPS. [OURS]"""
    return APPROACH_NOISE_ULPS * ROUNDOFF * v_sum * (sigma + x_sum)


@njit
def pair_contact_before(rx, ry, rz, wx, wy, wz, sigma, horizon, v_sum=0.0, x_sum=0.0):
    """:func:`pair_contact_time`, but ``inf`` for any contact not before ``horizon`` [s].

    The event loop only needs a pair's contact time if it beats the best event found so far.
    The quadratic f(τ) = σ² − |r + wτ|² has its peak at τ* = −r·w/|w|²; if f(horizon) < 0 and
    the peak lies at or after the horizon, f is still below zero and rising there, so there is
    no contact before the horizon: a square root and a division are saved.

    With ``v_sum``, ``x_sum`` (see :func:`approach_noise`) touching spheres whose approach is
    below rounding do not touch again: moving in a straight line relative to each other, they
    are at their closest now.
    """
    rr = rx * rx + ry * ry + rz * rz
    rw = rx * wx + ry * wy + rz * wz
    if rw >= 0.0:
        return NEVER
    ww = wx * wx + wy * wy + wz * wz
    s2 = sigma * sigma
    c = s2 - rr
    if horizon < NEVER and -rw >= ww * horizon and c - horizon * (2.0 * rw + ww * horizon) < 0.0:
        return NEVER
    if c > -TOUCHING_REL * s2 and -rw <= approach_noise(sigma, v_sum, x_sum):
        return NEVER
    return upward_root(c, -2.0 * rw, -2.0 * ww)


@njit
def plane_contact_time(gap, vn, gn, v_sum=0.0):
    """Time until a sphere in free flight touches a plane.

    With ``v_sum`` (Σ|v_k| of the sphere [m/s]) a sphere touching the plane (gap ≤ 0) whose
    approach is below the rounding of vn (APPROACH_NOISE_ULPS units of ``v_sum``) and that
    gravity does not press onto the plane (gn ≥ 0) does not touch it again: the impulse such
    an approach would call for cannot change the velocity (a sphere a cluster solve left
    touching an overhanging plane at −1e-22 m/s was met there again and again at one instant
    until the collapse guard stopped the run), and ignoring it lets the sphere sink in at most
    at that speed until gravity turns it. As for touching spheres (:func:`approach_noise`).
    [OURS]

    Args:
        gap: Distance from the plane minus the radius [m] (≥ 0 when not touching).
        vn: Velocity component along the plane normal [m/s].
        gn: Gravity component along the plane normal [m/s²].
        v_sum: |v_x| + |v_y| + |v_z| of the sphere [m/s] (0: every approach counts).

    Returns:
        Delay τ ≥ 0 [s] until the gap closes while approaching, or ``inf``.
    """
    if gap <= 0.0 and gn >= 0.0 and -vn <= APPROACH_NOISE_ULPS * ROUNDOFF * v_sum:
        return NEVER
    return upward_root(-gap, -vn, -gn)


@njit(inline="always")
def plane_gap(x, y, z, r, planes_p, planes_n, w):
    """Gap [m] between a sphere of radius r [m] centred at (x, y, z) [m] and plane w (negative:
    overlap)."""
    return ((x - planes_p[w, 0]) * planes_n[w, 0] + (y - planes_p[w, 1]) * planes_n[w, 1]
            + (z - planes_p[w, 2]) * planes_n[w, 2] - r)


@njit
def face_exit_time(x, v, g, lo, hi):
    """Time until a coordinate in free flight leaves the interval [lo, hi], and which side.

    Args:
        x, v, g: Coordinate [m], velocity [m/s] and acceleration [m/s²] along one axis.
        lo, hi: Interval bounds [m].

    Returns:
        (τ [s], side): side = +1 through ``hi``, −1 through ``lo``; (``inf``, 0) if never.
    """
    t_hi = upward_root(x - hi, v, g)
    t_lo = upward_root(lo - x, -v, -g)
    if t_hi <= t_lo:
        if t_hi == NEVER:
            return NEVER, 0
        return t_hi, 1
    return t_lo, -1


#: Halvings of a bracket that reach the width of one unit in the last place from any finite
#: bracket: the doubles span 2^2098 from the largest to the smallest (bisection of a
#: well-scaled bracket takes ~60; 200 were not enough for a bracket of 1e62 s, a relative
#: acceleration of 4e-63 m/s², found by the property test). :func:`_bracketed_root`, which
#: halves its bracket at least every fourth point, asks at most 4 ROOT_MAX_ITER points.
ROOT_MAX_ITER = 2200


#: Relative margin by which two spheres must be out of reach (their distance less the most
#: they can close up by the horizon above σ) for pair_contact_accelerated to skip its search
#: [-]. f = |d|² − σ² is then at least 2e-9 σ², far above its rounding error (~1e-15 σ² for
#: separations of a few σ), so f stays positive where the search would evaluate it.
OUT_OF_REACH_MARGIN = 1e-9


#: Units of round-off of the estimate by which a step of :func:`_bracketed_root` is carried
#: past it, away from the point it started from [-] (doubled for every further point on the
#: same side). Newton-type steps close in on a root from one side, so the bracket's far end
#: would come in only by bisection (~60 halvings to adjacent doubles); once a step lands
#: within a unit or two of the root, the nudge puts the next point on the root's other side
#: and the bracket collapses to a few units, which a halving or two finish. Far from the root
#: it changes the step by nothing that matters.
NEWTON_NUDGE_ULPS = 1.0


#: Dekker's splitting constant for doubles, 2^27 + 1 (Dekker 1971, Numer. Math. 18, 224): a
#: double times it splits into two halves whose products are exact.
_SPLIT = 134217729.0


@njit(inline="always")
def _square(a):
    """a² as p + e exactly (p the rounded square, e its rounding error; Dekker's product)."""
    c = _SPLIT * a
    hi = c - (c - a)
    lo = a - hi
    p = a * a
    return p, ((hi * hi - p) + 2.0 * hi * lo) + lo * lo


@njit(inline="always")
def _two_sum(a, b):
    """a + b as s + e exactly (Knuth's two-sum)."""
    s = a + b
    bb = s - a
    return s, (a - (s - bb)) + (b - bb)


@njit
def gap_at_start(rx, ry, rz, sigma):
    """f(0) = |r|² − σ² [m²], the squares and their sum compensated (:func:`_square`,
    :func:`_two_sum`): accurate to round-off of f(0) itself, where the plain sum carries the
    round-off of |r|² and σ² (~1e-16 σ²), which, for two spheres 1e-5 σ apart that close at
    1 mm/s, moves their contact time by ~1e-16 s, and for a grazing pair by far more. The
    root search measures f from it (:func:`_gap_poly`)."""
    px, ex = _square(rx)
    py, ey = _square(ry)
    pz, ez = _square(rz)
    ps, es = _square(sigma)
    s, e1 = _two_sum(px, py)
    s, e2 = _two_sum(s, pz)
    s, e3 = _two_sum(s, -ps)
    return s + ((e1 + e2 + e3) + (ex + ey + ez - es))


@njit(inline="always")
def _displacement(wx, wy, wz, ax, ay, az, t):
    """D(t) = w t + ½ a t² [m], componentwise."""
    return t * (wx + 0.5 * ax * t), t * (wy + 0.5 * ay * t), t * (wz + 0.5 * az * t)


@njit(inline="always")
def _gap_poly(rx, ry, rz, wx, wy, wz, ax, ay, az, f0, sgn, t):
    """f(t) = sgn (|r + w t + ½ a t²|² − σ²), f'(t) and f''(t), from f0 = |r|² − σ² and the
    displacement D = w t + ½ a t² as f0 + 2 r·D + |D|²: near contact D is small, so f carries
    the rounding of f0 (fixed, the same at every t) and of terms of order |r||D|, not the
    rounding of |r + D|² (~1e-16 σ², which scattered f's sign over ~10⁴ doubles around a root
    that a sphere approaching at 1 mm/s through a gap of 1e-5 σ reaches); unlike the expanded
    quartic, it has no cancelling coefficients. sgn = 1 for spheres apart, −1 for a distance
    that must stay below σ (a sphere inside a cylinder). Also f''(t) = 2 (|u|² + d·a), with
    u = w + a t and d = r + D (the root search's local model, :func:`_bracketed_root`)."""
    px, py, pz = _displacement(wx, wy, wz, ax, ay, az, t)
    f = f0 + (2.0 * (rx * px + ry * py + rz * pz) + (px * px + py * py + pz * pz))
    ux = wx + ax * t
    uy = wy + ay * t
    uz = wz + az * t
    dx, dy, dz = rx + px, ry + py, rz + pz
    return (sgn * f, sgn * 2.0 * (dx * ux + dy * uy + dz * uz),
            sgn * 2.0 * (ux * ux + uy * uy + uz * uz + (dx * ax + dy * ay + dz * az)))


@njit(inline="always")
def _dpoly(c4, c3, c2, c1, t):
    """f'(t) of the expanded quartic."""
    return ((4.0 * c4 * t + 3.0 * c3) * t + 2.0 * c2) * t + c1


@njit(inline="always")
def _value_slope(cubic, c4, c3, c2, c1, rx, ry, rz, wx, wy, wz, ax, ay, az, f0, sgn, t):
    """What :func:`_bracketed_root` searches, and its first and second derivatives, at t: f' of
    the expanded quartic, f'' and its derivative (``cubic``), or f, f' (:func:`_gap_poly`) and
    f''."""
    if cubic:
        return (_dpoly(c4, c3, c2, c1, t), (12.0 * c4 * t + 6.0 * c3) * t + 2.0 * c2,
                24.0 * c4 * t + 6.0 * c3)
    return _gap_poly(rx, ry, rz, wx, wy, wz, ax, ay, az, f0, sgn, t)


@njit(inline="always")
def _model_step(g, g1, g2, right):
    """The step s to the nearest zero of the local model g + g1 s + ½ g2 s² on the side where
    the root lies (s ≥ 0 where ``right``, else s ≤ 0; 0 where g is 0, and the caller's nudge
    moves the point); Newton's −g/g1 where the model has no zero there; NaN where neither
    points that way."""
    disc = g1 * g1 - 2.0 * g2 * g
    best = math.nan
    half = 0.5 * g2  # (tested itself: half of a subnormal g2 may be 0)
    if half != 0.0 and disc >= 0.0:
        q = -0.5 * (g1 + math.copysign(math.sqrt(disc), g1))  # (the roots without cancelling)
        if q != 0.0:
            for s in (q / half, g / q):
                if (s >= 0.0 if right else s <= 0.0) and not abs(s) >= abs(best):
                    best = s
        if best == best:
            return best
    s = -g / g1 if g1 != 0.0 else math.nan
    return s if (s >= 0.0 if right else s <= 0.0) else math.nan


# long: one bracketed search, shared by the two functions it finds roots of; split, the
# bracket's state would travel between functions as tuples
@njit
def _bracketed_root(cubic, c4, c3, c2, c1, rx, ry, rz, wx, wy, wz, ax, ay, az, f0, sgn, lo, hi,
                    flo, fhi):
    """The two adjacent doubles (lo, hi) between which g changes sign, on [lo, hi] where g is
    monotone: g(lo) on one side of zero (``flo``: its value, "side" meaning > 0 or not), g(hi)
    (``fhi``) on the other; g is f' of the expanded quartic (``cubic``, coefficients c4 … c1)
    or f (:func:`_gap_poly`, from f0).

    Bisection would ask the sign of g ~60 times; this asks it 5–10 times (98 % of the searches
    of a settling pour). Each point is followed by a step to the zero of g's local quadratic
    model (Chebyshev's method, third order; near a critical point of f, where g is flat and
    Newton's steps only halve the distance, it lands at once). A bisection is taken instead
    where the step has no zero to go to, lands further than the bracket's width outside it,
    or the bracket has not halved over the last three points (the safeguard that keeps the
    search at least as fast as bisection, as Press et al.'s "rtsafe" does with its steps'
    lengths). Such steps close in on the root from one side, so each is carried
    NEWTON_NUDGE_ULPS units of round-off past its estimate (doubling while points keep
    falling on the same side; just inside the bracket's far end where the estimate is at or
    past it), which brings the far end in too. Where g's sign, as computed, changes only once
    on the bracket, the pair is the one bisection finds."""
    up = flo > 0.0
    t = lo
    # the bracket's width after each of the last three points: a point that leaves it wider
    # than half the width three points before is followed by a bisection, so the bracket
    # halves at least every fourth point, which 4 ROOT_MAX_ITER bounds
    w1 = w2 = w3 = math.inf
    nudge = NEWTON_NUDGE_ULPS
    side = True  # the side the last point fell on (True: lo's)
    for _ in range(4 * ROOT_MAX_ITER):
        g, g1, g2 = _value_slope(cubic, c4, c3, c2, c1, rx, ry, rz, wx, wy, wz, ax, ay, az, f0,
                                 sgn, t)
        at_lo = (g > 0.0) == up
        if at_lo:
            lo = t
        else:
            hi = t
        mid = 0.5 * (lo + hi)
        if not (lo < mid < hi):
            break
        width = hi - lo
        slow = width > 0.5 * w3
        w3, w2, w1 = w2, w1, width
        nxt = t + _model_step(g, g1, g2, at_lo)
        if slow or not lo - width < nxt < hi + width:  # (a NaN step too)
            t = mid
            continue
        # a point on the same side as the last one: the nudge doubles until one crosses
        nudge = 2.0 * nudge if at_lo == side else NEWTON_NUDGE_ULPS
        side = at_lo
        e = nudge * ROUNDOFF * abs(nxt)
        # just past the estimate; where that is at or past the far end, just inside it (the
        # far end has come to the root: the next point must fall on the root's other side)
        t = min(nxt + e, hi - e) if at_lo else max(nxt - e, lo + e)
        if not lo < t < hi:
            t = mid
    return lo, hi


@njit(inline="always")
def _first_descent(rx, ry, rz, wx, wy, wz, ax, ay, az, f0, sgn, lo, hi, flo, fhi):
    """Root of f in [lo, hi] where f(lo) = flo > 0 ≥ f(hi) = fhi and f is monotone: the first
    double at which f is not above zero (:func:`_bracketed_root`)."""
    _, hi = _bracketed_root(False, 0.0, 0.0, 0.0, 0.0, rx, ry, rz, wx, wy, wz, ax, ay, az, f0,
                            sgn, lo, hi, flo, fhi)
    return hi


@njit(inline="always")
def _descent_in(rx, ry, rz, wx, wy, wz, ax, ay, az, f0, sgn, a, b):
    """(True, root) if f falls through zero on [a, b], a piece where it is monotone; else
    (False, inf)."""
    fa = _gap_poly(rx, ry, rz, wx, wy, wz, ax, ay, az, f0, sgn, a)[0]
    fb = _gap_poly(rx, ry, rz, wx, wy, wz, ax, ay, az, f0, sgn, b)[0]
    if fa > 0.0 and fb <= 0.0:
        return True, _first_descent(rx, ry, rz, wx, wy, wz, ax, ay, az, f0, sgn, a, b, fa, fb)
    return False, NEVER


@njit(inline="always")
def _dpoly_root(c4, c3, c2, c1, lo, hi, flo, fhi):
    """A root of f' in [lo, hi] where f' changes sign (f'(lo) = flo, f'(hi) = fhi; f' is
    monotone there): the middle of the two adjacent doubles it changes sign between
    (:func:`_bracketed_root`)."""
    lo, hi = _bracketed_root(True, c4, c3, c2, c1, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0,
                             0.0, 0.0, lo, hi, flo, fhi)
    return 0.5 * (lo + hi)


@njit(inline="always")
def root_horizon(c4, c3, c2, c1, c0, horizon):
    """The end of a quartic's root search [s]: the horizon, or Fujiwara's bound on its real
    roots, 2 max(|c3|/c4, √(|c2|/c4), ∛(|c1|/c4), ⁴√(|c0|/2c4)) for c4 > 0, where that is
    less (unlike Cauchy's bound, 1 + max|c_k|/c4, it stays evaluable for a tiny c4: a relative
    acceleration of 4e-63 m/s² put Cauchy's at 1e125 s, where the gap polynomial overflows).
    The two roots of the bound are taken only where its first two terms leave the horizon
    below it (the same value: they cost two calls of pow, a tenth of a search)."""
    bound = 2.0 * max(abs(c3) / c4, math.sqrt(abs(c2) / c4))
    if horizon <= bound:
        return horizon
    bound = max(bound, 2.0 * max((abs(c1) / c4) ** (1.0 / 3.0), (0.5 * abs(c0) / c4) ** 0.25))
    return min(horizon, bound)


@njit
def pair_contact_accelerated(rx, ry, rz, wx, wy, wz, ax, ay, az, sigma, horizon, v_sum=0.0,
                             x_sum=0.0):
    """Time until two spheres with different constant accelerations touch (a quartic).

    A flying sphere and one rolling or resting on a plane, or two spheres rolling differently:
    the separation is r + w τ + ½ a τ² with a the difference of the accelerations, and
    f(τ) = |r + wτ + ½aτ²|² − σ² is a quartic. Its first downward zero crossing is bracketed
    between critical points (the zeros of f', themselves bracketed by the zeros of f'', a
    quadratic) and found by a bracketed search (third-order steps safeguarded by bisection,
    :func:`_bracketed_root`) on f measured from f(0), summed exactly, and the displacement
    (:func:`_gap_poly`), which stays robust at grazing contacts and double roots where
    closed-form quartic formulas lose all accuracy (docs/architecture.md §3), and finds the
    root to a few units of round-off times the crossing's conditioning
    (tests/test_motion.py).

    Args:
        rx, ry, rz: Separation x_i − x_j [m].
        wx, wy, wz: Relative velocity [m/s].
        ax, ay, az: Relative acceleration a_i − a_j [m/s²].
        sigma: Contact distance [m].
        horizon: Only contacts up to this delay [s] are wanted (finite or ``inf``).

    Two spheres that overlap by round-off (f(0) < 0) and separate too slowly to clear σ
    before their accelerations turn them back have no downward crossing of f: they are met
    where they come back to the distance they have now (f measured from |r|² instead of σ²),
    or, where that excursion is below the rounding of the distance, where they start to come
    back; not never, which would let them pass through each other. [OURS]

    Returns:
        Delay τ ≥ 0 [s] of the contact, or ``inf`` if none before the horizon.
    """
    s2 = sigma * sigma
    c4 = 0.25 * (ax * ax + ay * ay + az * az)
    c3 = wx * ax + wy * ay + wz * az
    c2 = wx * wx + wy * wy + wz * wz + rx * ax + ry * ay + rz * az
    c1 = 2.0 * (rx * wx + ry * wy + rz * wz)
    c0 = rx * rx + ry * ry + rz * rz - s2
    if c4 == 0.0:
        return pair_contact_before(rx, ry, rz, wx, wy, wz, sigma, horizon, v_sum, x_sum)
    if horizon < NEVER:
        # out of reach before the horizon: the distance is at least its projection on the
        # separation now, |r + wτ + ½aτ²| ≥ |r| + (r̂·w)τ + ½(r̂·a)τ², and over [0, horizon]
        # that is at least |r| − h (max(0, −r̂·w) + ½ h max(0, −r̂·a)); where this stays
        # above σ, by a margin that keeps f positive in rounding too, the search below would
        # find nothing either (the search costs two powers and a few hundred polynomial
        # evaluations; what skipping it saves on settling pours and sliding beds:
        # docs/performance.md). Only the approaching parts of w and a count: spheres that
        # pass each other side by side are skipped too (|w| and |a| in full, the bound
        # before 2026-11-28, kept them)
        d = math.sqrt(c0 + s2)
        out = sigma * (1.0 + OUT_OF_REACH_MARGIN)
        if d > out:
            close_v = -(rx * wx + ry * wy + rz * wz) / d
            close_a = -(rx * ax + ry * ay + rz * az) / d
            reach = horizon * (max(close_v, 0.0) + 0.5 * horizon * max(close_a, 0.0))
            if d - reach > out:
                return NEVER
    h = root_horizon(c4, c3, c2, c1, c0, horizon)
    touching = c0 <= TOUCHING_REL * s2
    if touching:
        # touching already (round-off): a contact now if approaching beyond rounding, or if
        # pressed together (f'' < 0) with no approach to speak of; else look further on, past
        # the first piece, where f rises from a value that is only round-off (its sign there
        # is noise, and a "root" found in it came 1e-17 s later, again and again)
        # (pressed together: whichever side of σ round-off left them, f falls from here on, and
        # a search past the first piece would miss that contact and let them overlap)
        noise = 2.0 * approach_noise(sigma, v_sum, x_sum)
        if c1 < -noise or (c1 <= noise and pressed(c4, c3, c2, s2)):
            return 0.0
    tau = _first_fall(rx, ry, rz, wx, wy, wz, ax, ay, az, gap_at_start(rx, ry, rz, sigma), 1.0,
                      c4, c3, c2, c1, h, touching)
    if tau == NEVER and c0 < 0.0 and (c2 < 0.0 or c3 < 0.0):
        # (with c2, c3 ≥ 0 and c4 > 0, f' > 0 for τ > 0: a pair that separates never comes back,
        # which is most touching pairs after a collision)
        return _way_back(rx, ry, rz, wx, wy, wz, ax, ay, az, 1.0, c4, c3, c2, c1, h)
    return tau


# long: one walk over the pieces of a quartic, bracketing at each step; split, the pieces'
# bounds would travel between functions as tuples
@njit
def _first_fall(rx, ry, rz, wx, wy, wz, ax, ay, az, f0, sgn, c4, c3, c2, c1, h, touching,
                after=0.0):
    """First τ in [0, h] where f = sgn (|r + wτ + ½aτ²|² − σ²) (coefficients c4 … c1 of τ⁴ …
    τ, sign included; f0 = |r|² − σ² without the sign, :func:`gap_at_start`) falls through
    zero; ``inf`` if none. ``touching``: f(0) is round-off, so
    the piece from τ = 0 is not searched. ``after``: a crossing already found; only the
    pieces that start at or after it are searched (the next crossing, hsgran.facets)."""
    # critical points of f' (zeros of f'' = 12 c4 τ² + 6 c3 τ + 2 c2) split [0, h] into up to
    # three pieces on which f' is monotone; the zeros of f' found there split it into pieces
    # where f is, which are searched in order as they are found (scalars, not arrays: this runs
    # for every flying sphere near a resting one, and kernels do not allocate, see hsgran._jit)
    qa = 12.0 * c4
    qb = 6.0 * c3
    qc = 2.0 * c2
    p1 = p2 = h  # inner bounds of the pieces of f', in order, h where absent
    m = 1  # pieces of f'
    disc = qb * qb - 4.0 * qa * qc
    if disc > 0.0:
        sq = math.sqrt(disc)
        q1 = min((-qb - sq) / (2.0 * qa), (-qb + sq) / (2.0 * qa))
        q2 = max((-qb - sq) / (2.0 * qa), (-qb + sq) / (2.0 * qa))
        if 0.0 < q1 < h:
            p1 = q1
            m += 1
        if 0.0 < q2 < h:
            if m == 1:
                p1 = q2
            else:
                p2 = q2
            m += 1
    bounds = (0.0, p1, p2, h)
    a = 0.0  # start of the current piece of f
    first = True  # it is the piece from τ = 0
    for k in range(m):
        lo = bounds[k]
        hi = bounds[k + 1]
        flo = _dpoly(c4, c3, c2, c1, lo)
        fhi = _dpoly(c4, c3, c2, c1, hi)
        if flo < 0.0 < fhi and _clear_minimum(rx, ry, rz, wx, wy, wz, ax, ay, az, f0, sgn, lo,
                                              hi):
            # f falls to a minimum inside the piece and rises after it, never reaching zero:
            # no crossing from a to the minimum, nor on its way up (which the next piece
            # starts from; from hi instead of the minimum, where f rises still)
            a = hi
            first = False
            continue
        if (flo > 0.0) != (fhi > 0.0) and flo != 0.0 and fhi != 0.0:
            b = _dpoly_root(c4, c3, c2, c1, lo, hi, flo, fhi)
            if b > a and a >= after and not (touching and first):
                found, tau = _descent_in(rx, ry, rz, wx, wy, wz, ax, ay, az, f0, sgn, a, b)
                if found:
                    return tau
            a = b
            first = False
    if h > a and a >= after and not (touching and first):
        found, tau = _descent_in(rx, ry, rz, wx, wy, wz, ax, ay, az, f0, sgn, a, h)
        if found:
            return tau
    return NEVER


#: Relative margin by which a convex piece's lower bound must clear zero for
#: :func:`_clear_minimum` to skip its search [-], of |r|² + |D|² at the tangents' points
#: (D = w τ + ½ a τ², the displacement): f = f0 + 2 r·D + |D|² and f' carry a rounding of a
#: few units of round-off of it there (the tangents' error adds f'·width's, of the same
#: order), 10⁴ times below this; and f'' may be negative within a few units of round-off of
#: the piece's ends (the zeros of f'' are rounded), where f departs from a tangent by a
#: third-order amount, far less again. f's minimum within the margin of zero is searched as
#: before.
CLEAR_MARGIN_REL = 1e-12
#: Tangents :func:`_clear_minimum` draws before it gives up and lets the search decide [-]:
#: each halves (or better) the gap between the lower bound and f's least value found, and a
#: minimum as close to zero as a contact's is not cleared by any number of them.
CLEAR_TANGENTS = 16


@njit(inline="always")
def _displacement2(wx, wy, wz, ax, ay, az, t):
    """|D(t)|² [m²] (:func:`_displacement`)."""
    px, py, pz = _displacement(wx, wy, wz, ax, ay, az, t)
    return px * px + py * py + pz * pz


@njit(inline="always")
def _clear_minimum(rx, ry, rz, wx, wy, wz, ax, ay, az, f0, sgn, lo, hi):
    """Whether f (:func:`_gap_poly`) stays clear above zero on [lo, hi], a piece where it is
    convex (f' rises through zero there; :func:`_first_fall`), shown by a lower bound: on a
    convex piece f lies above its tangents, so the least value of the two tangents at p and q
    (where they meet) bounds f's minimum on [p, q] from below. Starting from the piece's
    ends, each new tangent is drawn where the last two meet, replacing the one on its side of
    the minimum (Kelley's cutting planes). Returns True once the bound clears zero by the
    margin, False where f comes within it or the tangents run out: a minimum near zero (a
    grazing pass or a contact) is left to the exact search, whose answer this never changes.
    It costs a few evaluations of f where the search of f's minimum to round-off costs five to
    ten of f' and then two of f: most flying spheres near resting ones in a settling pour
    pass them by (docs/performance.md)."""
    rr = rx * rx + ry * ry + rz * rz
    # each tangent's point: τ, f, f' and |D|² there (the last for the margin)
    p = lo
    fp, dp, _ = _gap_poly(rx, ry, rz, wx, wy, wz, ax, ay, az, f0, sgn, p)
    mp = _displacement2(wx, wy, wz, ax, ay, az, p)
    q = hi
    fq, dq, _ = _gap_poly(rx, ry, rz, wx, wy, wz, ax, ay, az, f0, sgn, q)
    mq = _displacement2(wx, wy, wz, ax, ay, az, q)
    for _ in range(CLEAR_TANGENTS):
        # the rounding of f and of f'·(t − p) at the tangents' points: of f0 + 2 r·D + |D|²,
        # a few units of round-off of |r|² + |D|² (|D| ≤ |d| + |r|, d = r + D)
        margin = CLEAR_MARGIN_REL * (rr + max(mp, mq))
        if not (fp > margin and fq > margin and dp < 0.0 < dq):
            return False
        # where the tangents meet (between p and q for a convex f), and their value there
        t = p + (fq - fp - dq * (q - p)) / (dp - dq)
        if not p < t < q:
            return False
        if fp + dp * (t - p) > margin:
            return True
        ft, dt, _ = _gap_poly(rx, ry, rz, wx, wy, wz, ax, ay, az, f0, sgn, t)
        mt = _displacement2(wx, wy, wz, ax, ay, az, t)
        if dt < 0.0:
            p, fp, dp, mp = t, ft, dt, mt
        else:
            q, fq, dq, mq = t, ft, dt, mt
    return False


#: An excursion of f = |d|² − |r|² below this many units of round-off of |r|² is lost in the
#: rounding of |d|² (a handful of operations) [-]: :func:`_way_back` meets such a pair where
#: it starts to come back.
DISTANCE_ROUNDING_ULPS = 8


@njit(inline="always")
def pressed(c4, c3, c2, s2):
    """Whether a touching pair (or a sphere touching a cylinder) with f = c4 τ⁴ + c3 τ³ + c2 τ² +
    c1 τ + c0, its approach c1 within rounding, is pressed together [bool]: f'' < 0 now (c2 < 0),
    and the fall that its accelerations make, the least of c2 τ² + c3 τ³ + c4 τ⁴ over τ > 0, is
    deeper than the rounding of the distance, DISTANCE_ROUNDING_ULPS units of s2 = σ² [m²] (or
    unbounded, c4 ≤ 0). A shallower one is the rounding of the accelerations: a sphere in
    constrained motion, whose acceleration is (v⁺ − v)/h, and a flying neighbour it touches
    side by side differed by 1e-13 m/s² along their tangent, a fall of 1e-34 m² that no solve
    can hold (it gives no impulse), and they were met again at one instant until the collapse
    guard stopped the run. [OURS]"""
    if c2 >= 0.0:
        return False
    if c4 <= 0.0:
        return True
    tau = (math.sqrt(9.0 * c3 * c3 - 32.0 * c4 * c2) - 3.0 * c3) / (8.0 * c4)  # g'(τ) = 0
    return tau * tau * (c2 + tau * (c3 + tau * c4)) < -DISTANCE_ROUNDING_ULPS * ROUNDOFF * s2


@njit
def _way_back(rx, ry, rz, wx, wy, wz, ax, ay, az, sgn, c4, c3, c2, c1, h):
    """A pair overlapping by round-off (f(0) < 0) whose f crosses zero nowhere in [0, h]: the
    first τ where f starts to fall (f' from + to −, from the coefficients) where f's rise to
    there is below the rounding of the distance, else the first τ where f falls back to f(0)
    (the distance it has now); ``inf`` if neither (see :func:`pair_contact_accelerated`).
    [OURS]"""
    rr = rx * rx + ry * ry + rz * rz
    # the first peak: the zeros of f'' (a quadratic) inside (0, h) split it into pieces where
    # f' is monotone (scalars: kernels do not allocate, see hsgran._jit)
    qa, qb, qc = 12.0 * c4, 6.0 * c3, 2.0 * c2
    q1 = q2 = h
    disc = qb * qb - 4.0 * qa * qc
    if disc > 0.0:
        sq = math.sqrt(disc)
        lo_q = min((-qb - sq) / (2.0 * qa), (-qb + sq) / (2.0 * qa))
        hi_q = max((-qb - sq) / (2.0 * qa), (-qb + sq) / (2.0 * qa))
        q1 = lo_q if 0.0 < lo_q < h else h
        q2 = hi_q if 0.0 < hi_q < h else h
        q1, q2 = min(q1, q2), max(q1, q2)
    lo = 0.0
    for hi in (q1, q2, h):
        flo = _dpoly(c4, c3, c2, c1, lo)
        fhi = _dpoly(c4, c3, c2, c1, hi)
        if hi > lo and flo > 0.0 >= fhi:
            top = _dpoly_root(c4, c3, c2, c1, lo, hi, flo, fhi)
            # an excursion lost in the rounding of |d|²: met at its peak (f, measured from the
            # displacement, resolves far smaller ones than the positions do)
            rise = top * (c1 + top * (c2 + top * (c3 + top * c4)))
            if rise <= DISTANCE_ROUNDING_ULPS * ROUNDOFF * rr:
                return top
            # a larger one: where it comes back to the distance it has now (f from it: f(0) =
            # 0), or never before the horizon
            return _first_fall(rx, ry, rz, wx, wy, wz, ax, ay, az, 0.0, sgn, c4, c3, c2, c1, h,
                               True)
        lo = max(lo, hi)
    return NEVER


@njit
def cylinder_contact_time(qx, qy, qz, ux, uy, uz, gx, gy, gz, rho, side, horizon, v_sum=0.0,
                          x_sum=0.0):
    """Time until a sphere in flight touches a cylinder (docs/walls.md, "Cylinders").

    Only the parts perpendicular to the axis matter: the centre's offset q from the axis moves
    as q + uτ + ½gτ², and the sphere touches when |q| = ρ, with ρ = R − r inside the cylinder
    and R + r outside. f(τ) = ∓(|q(τ)|² − ρ²) is a quartic, searched as for two spheres with
    different accelerations (:func:`pair_contact_accelerated`).

    Args:
        qx, qy, qz: The centre's offset from the axis, perpendicular to it [m].
        ux, uy, uz: Its velocity, perpendicular to the axis [m/s].
        gx, gy, gz: Its acceleration, perpendicular to the axis [m/s²].
        rho: The distance from the axis at contact [m].
        side: +1 for a sphere inside the cylinder, −1 outside.
        horizon: Only contacts up to this delay [s] are wanted (finite or ``inf``).
        v_sum, x_sum: Speed and position scales of the rounding (:func:`approach_noise`).

    Returns:
        Delay τ ≥ 0 [s] of the contact, or ``inf`` if none before the horizon.
    """
    sgn = -side  # f > 0 while the sphere is clear of the surface
    s2 = rho * rho
    c4 = sgn * 0.25 * (gx * gx + gy * gy + gz * gz)
    c3 = sgn * (ux * gx + uy * gy + uz * gz)
    c2 = sgn * (ux * ux + uy * uy + uz * uz + qx * gx + qy * gy + qz * gz)
    c1 = sgn * 2.0 * (qx * ux + qy * uy + qz * uz)
    c0 = sgn * (qx * qx + qy * qy + qz * qz - s2)
    touching = c0 <= TOUCHING_REL * s2
    if touching:
        # as for two spheres (pair_contact_accelerated): a contact now if approaching beyond
        # rounding, or pressed against the surface (f'' < 0: gravity or the curvature of the
        # path pushes the centre through it) with no separation to speak of
        noise = 2.0 * approach_noise(rho, v_sum, x_sum)
        if c1 < -noise or (c1 <= noise and pressed(c4, c3, c2, s2)):
            return 0.0
    if c4 == 0.0:
        # no acceleration across the axis: |q + uτ| = ρ, a quadratic a τ² + 2 b τ + c = 0
        if side < 0.0:
            return pair_contact_before(qx, qy, qz, ux, uy, uz, rho, horizon, v_sum, x_sum)
        a = ux * ux + uy * uy + uz * uz
        if a == 0.0:
            return NEVER
        b = qx * ux + qy * uy + qz * uz
        c = min(qx * qx + qy * qy + qz * qz - s2, 0.0)
        s = math.sqrt(b * b - a * c)
        tau = -c / (b + s) if b >= 0.0 else (s - b) / a
        if touching and tau <= 0.0:
            return NEVER
        return tau if tau <= horizon else NEVER
    h = root_horizon(abs(c4), c3, c2, c1, c0, horizon)
    tau = _first_fall(qx, qy, qz, ux, uy, uz, gx, gy, gz, gap_at_start(qx, qy, qz, rho), sgn,
                      c4, c3, c2, c1, h, touching)
    if tau == NEVER and c0 < 0.0:  # overlapping (see pair_contact_accelerated)
        return _way_back(qx, qy, qz, ux, uy, uz, gx, gy, gz, sgn, c4, c3, c2, c1, h)
    return tau
