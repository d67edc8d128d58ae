"""Observables summed exactly from the events (layer 5; compiled kernels used by
:mod:`hsgran._loop` and :mod:`hsgran._settling`; docs/observables.md).

With ``[output] observables = true`` the loop sums, over each frame interval, three things no
sampling of frames can give:

- the moment of the contact impulses, Σ b ⊗ J [kg m²/s]: for every impulse J a sphere takes at
  a contact, b is the branch vector from the contact point to the sphere's centre. A pair
  collision (impulse J on i, −J on j, contact point on the line of centres) adds r_ij ⊗ J with
  r_ij = x_i − x_j (minimum image); a plane adds R n ⊗ J. Divided by the volume and the
  interval, its negative is the collisional (contact) part of the stress (Allen & Tildesley,
  *Computer Simulation of Liquids*, 2nd ed., §2.4 and §3.7; the branch vectors of Love–Weber
  for the walls);
- the impulse each plane takes from the spheres [N s] (its time-average force), and
- the number of pair and plane collisions.

**Supports.** With gravity a sphere at rest or sliding on a plane, or asleep on another sphere,
is held by a force the event loop never computes. It is found from each sphere's momentum
ledger instead: the impulse sphere j took from its supports since its ledger was last booked is
m v(t) − m g t − ``led[j]``, where ``led[j]`` holds m v − m g t at the last booking plus the
collision impulses since. A booking (:func:`book_support`) hands that impulse to the plane at
the root of j's support chain (a sleeper's support, and its support's, down to a plane) and
adds its moment along the chain. Bookings happen at every frame, before a sphere's collision,
and before sleepers wake. Their sum is exact (it is Newton's second law); which plane gets it
is exact for every sphere whose support did not change within the interval, and otherwise that
of the support at the booking. Support that reaches no plane (a chain ending on a sphere in
flight, or in the opt-in cluster treatment) is booked to a last row, "unresolved".
"""

from __future__ import annotations

from hsgran._flight import min_image, wall_normal
from hsgran._jit import njit
from hsgran._state import OB_MOMENT, OB_N_PAIR, OB_N_WALL, OB_WALL, S_R, S_T, S_V
from hsgran.onplane import MS_FLIGHT


@njit(inline="always")
def observing(dyn):
    """Whether the observables are summed (their arrays are empty otherwise)."""
    return dyn.led.shape[0] > 0


@njit(inline="always")
def _add_moment(obs, bx, by, bz, jx, jy, jz):
    """Add b ⊗ J to the interval's moment (row-major 3 × 3)."""
    obs[OB_MOMENT + 0] += bx * jx
    obs[OB_MOMENT + 1] += bx * jy
    obs[OB_MOMENT + 2] += bx * jz
    obs[OB_MOMENT + 3] += by * jx
    obs[OB_MOMENT + 4] += by * jy
    obs[OB_MOMENT + 5] += by * jz
    obs[OB_MOMENT + 6] += bz * jx
    obs[OB_MOMENT + 7] += bz * jy
    obs[OB_MOMENT + 8] += bz * jz


@njit(inline="always")
def _add_to_wall(obs, w, jx, jy, jz):
    """Plane w (or the unresolved row for w < 0) takes the impulse −J [N s] of a sphere that
    took J from it."""
    row = OB_WALL + 3 * w if w >= 0 else obs.shape[0] - 3
    obs[row] -= jx
    obs[row + 1] -= jy
    obs[row + 2] -= jz


@njit
def book_support(j, t, flight, dyn, walls, space):
    """Book the impulse sphere j took from its supports since its last booking (see the
    module's docstring): to the plane at the root of its support chain, with the moment of each
    link. Sphere j's stored state may be at any time up to t [s]."""
    st, acc, mplane = flight.st, flight.acc, flight.mplane
    led, obs, gravity = dyn.led, dyn.obs, space.gravity
    m = 1.0 / dyn.inv_m[j]
    dt = t - st[j, S_T]
    s0 = m * (st[j, S_V] + acc[j, 0] * dt - gravity[0] * t) - led[j, 0]
    s1 = m * (st[j, S_V + 1] + acc[j, 1] * dt - gravity[1] * t) - led[j, 1]
    s2 = m * (st[j, S_V + 2] + acc[j, 2] * dt - gravity[2] * t) - led[j, 2]
    led[j, 0] += s0
    led[j, 1] += s1
    led[j, 2] += s2
    if s0 == 0.0 and s1 == 0.0 and s2 == 0.0:
        return
    # down the chain of sleepers (each at rest, so its stored position is its position at t)
    cur = j
    links = 0
    while mplane[cur] <= -2 and links < st.shape[0]:
        b = -2 - mplane[cur]
        bx = min_image(st[cur, 0] - st[b, 0], 0, space.box_len, space.periodic)
        by = min_image(st[cur, 1] - st[b, 1], 1, space.box_len, space.periodic)
        bz = min_image(st[cur, 2] - st[b, 2], 2, space.box_len, space.periodic)
        _add_moment(obs, bx, by, bz, s0, s1, s2)
        cur = b
        links += 1
    w = mplane[cur]
    if w >= 0:
        r = st[cur, S_R]
        nx, ny, nz = wall_normal(walls, w, st[cur, 0], st[cur, 1], st[cur, 2])
        _add_moment(obs, r * nx, r * ny, r * nz, s0, s1, s2)
    _add_to_wall(obs, w, s0, s1, s2)


@njit(inline="always")
def momentum(j, st, inv_m):
    """Momentum m v [kg m/s] of sphere j from its stored velocity."""
    m = 1.0 / inv_m[j]
    return m * st[j, S_V], m * st[j, S_V + 1], m * st[j, S_V + 2]


@njit
def before_pair(i, j, t, flight, dyn, walls, space, grav_on):
    """Before a collision of spheres i and j at time t [s] (both advanced to t): book their
    supports so far, and return their momenta [kg m/s] and the share w_i of i's momentum change
    in the contact's impulse (for :func:`book_pair`). J on i is −Δp_j when only j is in flight
    (i passes part of the blow on to its supports), Δp_i when only i is, and the antisymmetric
    part (Δp_i − Δp_j)/2 otherwise: w_i = 0, 1, ½."""
    if grav_on:
        book_support(i, t, flight, dyn, walls, space)
        book_support(j, t, flight, dyn, walls, space)
        free_i = flight.mstate[i] == MS_FLIGHT
        free_j = flight.mstate[j] == MS_FLIGHT
        wi = 0.0 if free_j and not free_i else (1.0 if free_i and not free_j else 0.5)
    else:
        wi = 0.5
    return momentum(i, flight.st, dyn.inv_m), momentum(j, flight.st, dyn.inv_m), wi


@njit
def before_wall(i, t, flight, dyn, walls, space, grav_on):
    """Before a collision of sphere i with a plane at time t [s]: book its supports so far and
    return its momentum [kg m/s] (for :func:`book_wall`)."""
    if grav_on:
        book_support(i, t, flight, dyn, walls, space)
    return momentum(i, flight.st, dyn.inv_m)


@njit
def book_pair(i, j, pi, pj, wi, bx, by, bz, flight, dyn, grav_on):
    """A pair collision of spheres i and j at one instant: ``pi``, ``pj``, ``wi`` from
    :func:`before_pair`, (bx, by, bz) = x_i − x_j [m]. What else a sphere's momentum changed
    by is support: it stays in the sphere's ledger for its next booking."""
    st, obs, led = flight.st, dyn.obs, dyn.led
    qi = momentum(i, st, dyn.inv_m)
    qj = momentum(j, st, dyn.inv_m)
    jx = wi * (qi[0] - pi[0]) - (1.0 - wi) * (qj[0] - pj[0])
    jy = wi * (qi[1] - pi[1]) - (1.0 - wi) * (qj[1] - pj[1])
    jz = wi * (qi[2] - pi[2]) - (1.0 - wi) * (qj[2] - pj[2])
    _add_moment(obs, bx, by, bz, jx, jy, jz)
    obs[OB_N_PAIR] += 1.0
    if grav_on:
        led[i, 0] += jx
        led[i, 1] += jy
        led[i, 2] += jz
        led[j, 0] -= jx
        led[j, 1] -= jy
        led[j, 2] -= jz


@njit
def book_wall(i, w, pi, flight, dyn, walls, grav_on):
    """A collision of sphere i with plane w: ``pi`` from :func:`before_wall`. Its whole
    momentum change is the plane's impulse (a landing after the rebound included)."""
    st, obs, led = flight.st, dyn.obs, dyn.led
    qi = momentum(i, st, dyn.inv_m)
    jx, jy, jz = qi[0] - pi[0], qi[1] - pi[1], qi[2] - pi[2]
    r = st[i, S_R]
    n = walls.planes_n
    _add_moment(obs, r * n[w, 0], r * n[w, 1], r * n[w, 2], jx, jy, jz)
    _add_to_wall(obs, w, jx, jy, jz)
    obs[OB_N_WALL] += 1.0
    if grav_on:
        led[i, 0] += jx
        led[i, 1] += jy
        led[i, 2] += jz


@njit
def close_interval(f, t, flight, dyn, walls, space, out, grav_on):
    """Frame f at time t [s] closes an interval: book every sphere's supports, move the sums to
    the frame buffer and start the next interval from zero."""
    obs = dyn.obs
    if grav_on:
        for j in range(flight.st.shape[0]):
            book_support(j, t, flight, dyn, walls, space)
    for k in range(obs.shape[0]):
        out.fr_obs[f, k] = obs[k]
        obs[k] = 0.0
