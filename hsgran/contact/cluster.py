"""Contacts of a cluster solved together: non-smooth Gauss–Seidel (layer 2; compiled kernels).

Where several spheres and walls touch at one instant, the impulses of all their contacts, or
the forces of all their resting contacts, are found together instead of one pair at a time
(docs/enduring-contact.md, "Clusters of contacts"). The one solver here serves both levels:

- **impulses** (a simultaneous impact, Moreau–Jean contact dynamics: Moreau 1988, Jean 1999):
  the unknowns are the contact impulses P_k [N s]; the relative velocities after them obey, per
  contact k, the Signorini condition with Newton's restitution,
  ``0 ≤ P_n,k ⊥ u_n,k⁺ + e_k min(u_n,k⁻, 0) ≥ 0``, and Coulomb's cone ``|P_t,k| ≤ μ_k P_n,k``
  with the tangential impulse opposing the slip (maximal dissipation);
- **forces** (resting contacts, Baraff 1994): the unknowns are the contact forces [N]; the
  relative normal accelerations obey ``0 ≤ F_n,k ⊥ a_n,k ≥ 0``; a contact that does not slip
  keeps ``|F_t,k| ≤ μ_k F_n,k`` (static friction), one that slips gets ``F_t,k = −μ_k F_n,k ŝ_k``
  along its slip direction ŝ_k (kinetic friction).

Both are the same problem in the solver's terms: body "velocities" (velocities, or
accelerations) change by the contact "impulses" (impulses, or forces) through the inverse masses
and inverse moments of inertia, and each contact's normal part must end at or above a target.
Gauss–Seidel visits the contacts in turn and solves each one's local problem exactly with the
others held (the local Delassus matrix of two spheres is diagonal in the contact frame), then
projects onto the cone (Jean 1999; Acary & Brogliato 2008, ch. 13). Rolling resistance is a
torque at each contact bounded by μ_r R* P_n (docs/model.md §5.1), solved the same way.

Conventions: contact k joins body ``ca[k]`` (a) and body ``cb[k]`` (b, or −1 for an immovable
body: a wall, or a sphere held where it is); ``cn[k]`` is the unit normal from b to a; the
contact point is at −R_a n from a's centre and at +R_b n from b's (``crb[k]`` = R_b, 0 for a
wall); ``cvb[k]`` is the immovable body's velocity at the contact point. Every array is
local to the cluster; the caller maps bodies to spheres.
"""

from __future__ import annotations

import math

from hsgran._jit import njit

#: Sweeps of Gauss–Seidel after which the solver stops even if it has not converged. Clusters of
#: a pile (tens to a few hundred contacts) converge in tens to hundreds of sweeps; chains of
#: contacts along one line (Newton's cradle, a column) are the slowest case, needing sweeps of
#: the order of the square of their length.
MAX_SWEEPS = 20000
#: Sweeps that friction and rolling couples get before :func:`solve_polished` freezes them and
#: polishes the normal impulses alone [-]. Where a cluster holds a slowly slipping mode (spheres
#: creeping at the edge of their cones), Gauss–Seidel approaches the tangential solution only
#: as 1/sweeps: on a 30-sphere impact cluster of a pour, the normal velocities were 8e-7 m/s
#: from their targets after 200 sweeps and 3e-8 m/s after 2000, where a normal-only polish
#: reached 5e-14 m/s in about 100 sweeps. Cut at 200, the tangential residue (1e-5 m/s) kept a
#: 60-sphere pile creeping: it never came to rest; at 2000 it comes to rest as with converged
#: friction (docs/enduring-contact.md).
FRICTION_SWEEPS = 2000
#: At most this many rounds of (normal polish, cones clipped) in :func:`solve_polished` [-]:
#: each clip changes a tangential impulse by what the polish before it changed the normal one
#: (0.15 % of the cone in the pour's cluster above), and a last polish follows the last clip.
POLISH_ROUNDS = 3
#: Sweeps after which a solve that may stop short (``stall`` of :func:`solve`) first asks
#: whether it still converges, and again at every doubling of its sweeps [-].
STALL_SWEEPS = 128
#: A solve has stalled when the smallest change of a sweep since the last check is not below
#: this fraction of the smallest one in the span before it [-]. Gauss–Seidel on a problem
#: with a solution converges linearly (a contracting map near it), so each span, at least as
#: long as all before it, shrinks the change by a constant factor; where the frictional
#: problem has no solution (a body pressed against a fixed wall by a boundary that moves
#: into it, wedged within its friction angle), the impulses grow by the same amount every
#: sweep and the change does not shrink at all. Of 134 solves of a 14° chute's bed (hand-over
#: clusters of 2–250 spheres) that took more than 1,500 sweeps, 93 stall (88 at the first
#: comparison, 256 sweeps; 5 at 512), none of the 13 that converge within FRICTION_SWEEPS;
#: a column of 80 spheres, whose convergence is slow (sweeps ∝ length²), does not stall.
STALL_FACTOR = 0.9


@njit(inline="always")
def _contact_velocity(k, ca, cb, cn, crb, cvb, rad, v, w, rotation):
    """Relative velocity (a with respect to b) of contact k's material points [m/s]."""
    a = ca[k]
    b = cb[k]
    nx, ny, nz = cn[k, 0], cn[k, 1], cn[k, 2]
    ux, uy, uz = v[a, 0], v[a, 1], v[a, 2]
    if rotation:  # ω_a × (−R_a n)
        ra = rad[a]
        ux -= ra * (w[a, 1] * nz - w[a, 2] * ny)
        uy -= ra * (w[a, 2] * nx - w[a, 0] * nz)
        uz -= ra * (w[a, 0] * ny - w[a, 1] * nx)
    if b >= 0:
        ux -= v[b, 0]
        uy -= v[b, 1]
        uz -= v[b, 2]
        if rotation:  # − ω_b × (R_b n)
            rb = crb[k]
            ux -= rb * (w[b, 1] * nz - w[b, 2] * ny)
            uy -= rb * (w[b, 2] * nx - w[b, 0] * nz)
            uz -= rb * (w[b, 0] * ny - w[b, 1] * nx)
    else:
        ux -= cvb[k, 0]
        uy -= cvb[k, 1]
        uz -= cvb[k, 2]
    return ux, uy, uz


@njit(inline="always")
def _apply(k, dx, dy, dz, ca, cb, cn, crb, inv_m, inv_i, rad, v, w, rotation):
    """Apply the impulse change d to contact k: +d on a, −d on b; the torque on either is
    −R (n × d) (on a: (−R_a n) × d; on b: (R_b n) × (−d))."""
    a = ca[k]
    b = cb[k]
    nx, ny, nz = cn[k, 0], cn[k, 1], cn[k, 2]
    tx = ny * dz - nz * dy
    ty = nz * dx - nx * dz
    tz = nx * dy - ny * dx
    v[a, 0] += inv_m[a] * dx
    v[a, 1] += inv_m[a] * dy
    v[a, 2] += inv_m[a] * dz
    if rotation:
        s = inv_i[a] * rad[a]
        w[a, 0] -= s * tx
        w[a, 1] -= s * ty
        w[a, 2] -= s * tz
    if b >= 0:
        v[b, 0] -= inv_m[b] * dx
        v[b, 1] -= inv_m[b] * dy
        v[b, 2] -= inv_m[b] * dz
        if rotation:
            s = inv_i[b] * crb[k]
            w[b, 0] -= s * tx
            w[b, 1] -= s * ty
            w[b, 2] -= s * tz


@njit(inline="always")
def cap(x, y, z, limit):
    """(x, y, z) scaled down to length ``limit`` if longer."""
    m = math.sqrt(x * x + y * y + z * z)
    if m > limit:
        s = limit / m if m > 0.0 else 0.0
        return x * s, y * s, z * s
    return x, y, z


@njit(inline="always")
def _apply_couple(k, dx, dy, dz, ca, cb, inv_i, w):
    """Apply the rolling couple change d to contact k: +d on a's spin, −d on b's."""
    a = ca[k]
    b = cb[k]
    w[a, 0] += inv_i[a] * dx
    w[a, 1] += inv_i[a] * dy
    w[a, 2] += inv_i[a] * dz
    if b >= 0:
        w[b, 0] -= inv_i[b] * dx
        w[b, 1] -= inv_i[b] * dy
        w[b, 2] -= inv_i[b] * dz


@njit(inline="always")
def _rolling_step(k, ca, cb, cn, inv_i, w, hr, rslip, limit):
    """Rolling resistance at contact k: the torque ("impulse" of angular kind) on a is hr[k],
    −hr[k] on b, tangential, of length at most ``limit`` (μ_r R* P_n), opposing the rolling part
    of the relative angular velocity (or along −rslip[k] if that is set: kinetic). Returns the
    length of its change."""
    a = ca[k]
    b = cb[k]
    nx, ny, nz = cn[k, 0], cn[k, 1], cn[k, 2]
    inv_b = inv_i[b] if b >= 0 else 0.0
    wsum = inv_i[a] + inv_b
    if wsum == 0.0:
        return 0.0
    ox, oy, oz = w[a, 0], w[a, 1], w[a, 2]
    if b >= 0:
        ox -= w[b, 0]
        oy -= w[b, 1]
        oz -= w[b, 2]
    on = ox * nx + oy * ny + oz * nz
    ox -= on * nx
    oy -= on * ny
    oz -= on * nz
    if rslip[k, 0] != 0.0 or rslip[k, 1] != 0.0 or rslip[k, 2] != 0.0:
        hx, hy, hz = -limit * rslip[k, 0], -limit * rslip[k, 1], -limit * rslip[k, 2]
    else:
        hx, hy, hz = cap(hr[k, 0] - ox / wsum, hr[k, 1] - oy / wsum, hr[k, 2] - oz / wsum,
                          limit)
    dx, dy, dz = hx - hr[k, 0], hy - hr[k, 1], hz - hr[k, 2]
    hr[k, 0], hr[k, 1], hr[k, 2] = hx, hy, hz
    _apply_couple(k, dx, dy, dz, ca, cb, inv_i, w)
    return math.sqrt(dx * dx + dy * dy + dz * dz)


@njit
def start(nc, ca, cb, cn, crb, inv_m, inv_i, rad, v, w, pn, pt, hr, rotation):
    """Warm start: apply the contacts' starting impulses ``pn`` n + ``pt`` and rolling couples
    ``hr`` (those of an earlier solve; the arguments as in :func:`solve`) to the bodies'
    ``v``, ``w``, before :func:`solve` goes on from them. Starting from the solution of a
    nearby problem, Gauss–Seidel needs fewer sweeps (Jean 1999; Acary & Brogliato 2008, ch.
    13: the impulses of the previous step as the first iterate)."""
    for k in range(nc):
        _apply(k, pn[k] * cn[k, 0] + pt[k, 0], pn[k] * cn[k, 1] + pt[k, 1],
               pn[k] * cn[k, 2] + pt[k, 2], ca, cb, cn, crb, inv_m, inv_i, rad, v, w, rotation)
        if rotation:
            _apply_couple(k, hr[k, 0], hr[k, 1], hr[k, 2], ca, cb, inv_i, w)


@njit
def _worst(nc, ca, cb, cn, crb, cvb, target, rad, v, w, rotation):
    """The largest amount by which a contact's relative normal velocity is below its target."""
    worst = -math.inf
    for k in range(nc):
        ux, uy, uz = _contact_velocity(k, ca, cb, cn, crb, cvb, rad, v, w, rotation)
        worst = max(worst, target[k] - (ux * cn[k, 0] + uy * cn[k, 1] + uz * cn[k, 2]))
    return worst


# long: one Gauss–Seidel sweep's local solve (normal, Coulomb cone, rolling couple) shares the
# contact's frame and the old impulses; split, they would travel back and forth as tuples
@njit
def solve(nc, ca, cb, cn, crb, cvb, target, mu, slip, mur, reff, rslip, inv_m, inv_i, rad, v,
          w, pn, pt, hr, rotation, friction, rolling, tol, max_sweeps=MAX_SWEEPS, stall=False):
    """Solve the contacts of a cluster together by non-smooth Gauss–Seidel (see the module).

    Args:
        nc: Number of contacts (the first nc rows of the contact arrays are used).
        ca, cb: (≥nc,) int bodies of each contact (cb −1: immovable, see ``cvb``).
        cn: (≥nc, 3) unit normal from b to a.
        crb: (≥nc,) radius of b [m] (0 for a wall).
        cvb: (≥nc, 3) velocity of the immovable body at the contact point [m/s] (or its
            acceleration [m/s²] at the force level).
        target: (≥nc,) lower bound of the relative normal velocity after the solve [m/s]
            (−e min(u_n⁻, 0) for an impact; 0 for a resting contact [m/s²]).
        mu: (≥nc,) sliding friction coefficient [-].
        slip: (≥nc, 3) unit slip direction of a contact that slips (kinetic friction), or
            zeros (static: the tangential part is projected onto the cone).
        mur, reff: (≥nc,) rolling friction coefficient [-] and rolling radius R* [m].
        rslip: (≥nc, 3) unit direction of the relative rolling of a contact that rolls
            (kinetic rolling couple), or zeros.
        inv_m, inv_i, rad: (nb,) inverse mass [1/kg], inverse moment of inertia [1/(kg m²)]
            and radius [m] of each body.
        v, w: (nb, 3) velocities [m/s] and angular velocities [rad/s] (or accelerations
            [m/s²] and angular accelerations [rad/s²]), updated in place.
        pn, pt, hr: (≥nc,), (≥nc, 3), (≥nc, 3) normal and tangential impulse [N s] (or force
            [N]) and rolling couple [N m s] (or torque [N m]) of each contact, updated in
            place (zeros to start cold; to start warm, the values of an earlier solve, applied
            to ``v`` and ``w`` first by :func:`start`).
        rotation, friction, rolling: Which parts are solved (the scene's effects).
        tol: Converged when no contact's impulse changed in a sweep by more than it takes to
            change the contact's relative velocity by ``tol`` [m/s] (or acceleration [m/s²];
            for a rolling couple, R* times the relative angular velocity), and no contact's
            normal velocity is more than ``tol`` below its target.
        max_sweeps: Stop after this many sweeps even if not converged.
        stall: Stop where the solve has stalled (STALL_FACTOR): the problem has no solution
            that Gauss–Seidel reaches.

    Returns:
        (sweeps, worst, stalled): sweeps done; the largest amount by which a contact's
        relative normal velocity ends below its target (≤ 0 when every contact is
        satisfied) [m/s]; whether it stopped for a stall.
    """
    sweeps = 0
    check = STALL_SWEEPS
    least = math.inf  # the smallest change since the last check
    before = math.inf  # ... in the span before it
    for sweep in range(max_sweeps):
        sweeps = sweep + 1
        change = 0.0
        for k in range(nc):
            a = ca[k]
            b = cb[k]
            nx, ny, nz = cn[k, 0], cn[k, 1], cn[k, 2]
            inv_mb = inv_m[b] if b >= 0 else 0.0
            w_n = inv_m[a] + inv_mb
            if w_n == 0.0:
                continue
            w_t = w_n
            if rotation:
                w_t += inv_i[a] * rad[a] * rad[a]
                if b >= 0:
                    w_t += inv_i[b] * crb[k] * crb[k]
            ux, uy, uz = _contact_velocity(k, ca, cb, cn, crb, cvb, rad, v, w, rotation)
            un = ux * nx + uy * ny + uz * nz
            p_old = pn[k]
            p_new = max(0.0, p_old + (target[k] - un) / w_n)
            dx = (p_new - p_old) * nx
            dy = (p_new - p_old) * ny
            dz = (p_new - p_old) * nz
            pn[k] = p_new
            if friction:
                tx, ty, tz = pt[k, 0], pt[k, 1], pt[k, 2]
                if slip[k, 0] != 0.0 or slip[k, 1] != 0.0 or slip[k, 2] != 0.0:
                    qx = -mu[k] * p_new * slip[k, 0]
                    qy = -mu[k] * p_new * slip[k, 1]
                    qz = -mu[k] * p_new * slip[k, 2]
                else:
                    # the slip this contact's normal change leaves is the same as before it
                    # (two spheres: the normal impulse does not turn them)
                    sx = ux - un * nx
                    sy = uy - un * ny
                    sz = uz - un * nz
                    qx, qy, qz = cap(tx - sx / w_t, ty - sy / w_t, tz - sz / w_t,
                                      mu[k] * p_new)
                pt[k, 0], pt[k, 1], pt[k, 2] = qx, qy, qz
                dx += qx - tx
                dy += qy - ty
                dz += qz - tz
            _apply(k, dx, dy, dz, ca, cb, cn, crb, inv_m, inv_i, rad, v, w, rotation)
            change = max(change, math.sqrt(dx * dx + dy * dy + dz * dz) * w_t)
            if rolling and rotation and mur[k] > 0.0:
                limit = mur[k] * reff[k] * p_new
                inv_b = inv_i[b] if b >= 0 else 0.0
                change = max(change, _rolling_step(k, ca, cb, cn, inv_i, w, hr, rslip, limit)
                             * (inv_i[a] + inv_b) * reff[k])
        if change <= tol and _worst(nc, ca, cb, cn, crb, cvb, target, rad, v, w,
                                    rotation) <= tol:
            break
        least = min(least, change)
        if stall and sweeps == check:
            if least > STALL_FACTOR * before:
                return sweeps, _worst(nc, ca, cb, cn, crb, cvb, target, rad, v, w, rotation), \
                    True
            before = least
            least = math.inf
            check *= 2
    worst = _worst(nc, ca, cb, cn, crb, cvb, target, rad, v, w, rotation)
    return sweeps, worst, False


@njit
def _clip_cones(nc, ca, cb, cn, crb, mu, mur, reff, inv_m, inv_i, rad, v, w, pn, pt, hr,
                rotation, friction, rolling):
    """Bring every tangential impulse back into its cone (|P_t| ≤ μ P_n) and every rolling
    couple within μ_r R* P_n, applying the changes to ``v`` and ``w`` (the arguments as in
    :func:`solve`). Returns the largest change of a tangential impulse [N s] (a rolling
    couple only turns the spheres, which no contact's normal velocity feels)."""
    most = 0.0
    for k in range(nc):
        if friction:
            tx, ty, tz = pt[k, 0], pt[k, 1], pt[k, 2]
            qx, qy, qz = cap(tx, ty, tz, mu[k] * pn[k])
            if qx != tx or qy != ty or qz != tz:
                pt[k, 0], pt[k, 1], pt[k, 2] = qx, qy, qz
                _apply(k, qx - tx, qy - ty, qz - tz, ca, cb, cn, crb, inv_m, inv_i, rad, v, w,
                       rotation)
                most = max(most, math.sqrt((qx - tx) ** 2 + (qy - ty) ** 2 + (qz - tz) ** 2))
        if rolling and rotation:
            hx, hy, hz = hr[k, 0], hr[k, 1], hr[k, 2]
            gx, gy, gz = cap(hx, hy, hz, mur[k] * reff[k] * pn[k])
            if gx != hx or gy != hy or gz != hz:
                hr[k, 0], hr[k, 1], hr[k, 2] = gx, gy, gz
                _apply_couple(k, gx - hx, gy - hy, gz - hz, ca, cb, inv_i, w)
    return most


@njit
def solve_polished(nc, ca, cb, cn, crb, cvb, target, mu, slip, mur, reff, rslip, inv_m, inv_i,
                   rad, v, w, pn, pt, hr, rotation, friction, rolling, tol,
                   friction_sweeps=FRICTION_SWEEPS, grow=False):
    """:func:`solve` (the same arguments and results) with friction and rolling couples given
    at most ``friction_sweeps`` sweeps; if they have not converged by then, they are frozen and
    the normal impulses alone are solved to ``tol`` (a convex problem, on which Gauss–Seidel
    converges), then the cones clipped where the new normal impulses no longer hold the
    frozen tangential ones, up to POLISH_ROUNDS times. The normal conditions (what keeps
    contacts from closing) are then met to ``tol``; friction is Coulomb's, at the accuracy the
    tangential sweeps reached.

    With ``grow`` (the caller can solve a larger cluster instead, where the stall may come
    from what it holds immovable), a solve that stalls (:func:`solve`; with friction or
    without: bodies pressed head-on between immovable partners that close on each other
    have no solution either) stops there and returns ``stalled`` True, the impulses
    unfinished; without it, a friction solve's stall freezes the tangential impulses as the
    end of the friction sweeps does, and a frictionless solve runs to MAX_SWEEPS. Returns
    (sweeps, worst, stalled) as :func:`solve`."""
    tangential = friction or rolling
    sweeps, worst, stalled = solve(nc, ca, cb, cn, crb, cvb, target, mu, slip, mur, reff, rslip,
                                   inv_m, inv_i, rad, v, w, pn, pt, hr, rotation, friction,
                                   rolling, tol, friction_sweeps if tangential else MAX_SWEEPS,
                                   tangential or grow)
    if stalled and grow:
        return sweeps, worst, True
    if not tangential or (sweeps < friction_sweeps and not stalled):
        return sweeps, worst, False  # converged (or nothing tangential to freeze)
    for _ in range(POLISH_ROUNDS):
        more, worst, _ = solve(nc, ca, cb, cn, crb, cvb, target, mu, slip, mur, reff, rslip,
                               inv_m, inv_i, rad, v, w, pn, pt, hr, rotation, False, False, tol)
        sweeps += more
        if _clip_cones(nc, ca, cb, cn, crb, mu, mur, reff, inv_m, inv_i, rad, v, w, pn, pt, hr,
                       rotation, friction, rolling) == 0.0:
            break
    else:
        more, worst, _ = solve(nc, ca, cb, cn, crb, cvb, target, mu, slip, mur, reff, rslip,
                               inv_m, inv_i, rad, v, w, pn, pt, hr, rotation, False, False, tol)
        sweeps += more
    return sweeps, worst, False
