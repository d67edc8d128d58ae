"""Contact times of free flight (hsgran.motion): the quadratic and quartic roots, and how touching
spheres are told apart from approaching ones at the rounding level (MODEL-independent kinematics;
docs/enduring-contact.md)."""

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from hsgran.motion import (
    NEVER,
    approach_noise,
    pair_contact_accelerated,
    pair_contact_before,
    upward_root,
)

#: Contact times here are roots of well-conditioned polynomials; rounding only.
ROOT_RTOL = 1e-9


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
