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

import numpy as np

from hsgran._jit import njit
from hsgran.motion import ROUNDOFF

#: Sweeps of Gauss–Seidel after which the solver stops even if it has not converged. Clusters of
#: a pile (tens to a few hundred contacts) converge in tens to hundreds of sweeps; chains of
#: contacts along one line (Newton's cradle, a column) are the slowest case, needing sweeps of
#: the order of the square of their length.
MAX_SWEEPS = 20000
#: Sweeps that friction and rolling couples get before :func:`solve_polished` freezes them and
#: polishes the normal impulses [-]. Where a cluster holds a slowly slipping mode (spheres
#: creeping at the edge of their cones), Gauss–Seidel approaches the tangential solution only
#: as 1/sweeps: on a 30-sphere impact cluster of a pour, the normal velocities were 8e-7 m/s
#: from their targets after 200 sweeps and 3e-8 m/s after 2000, where a normal-only polish
#: reached 5e-14 m/s in about 100 sweeps. Cut at 200, the tangential residue (1e-5 m/s) kept a
#: 60-sphere pile creeping: it never came to rest; at 2000 it comes to rest as with converged
#: friction (docs/enduring-contact.md).
FRICTION_SWEEPS = 2000
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
#: a column of 80 spheres, whose convergence is slow (sweeps ∝ length²), does not stall with
#: plain sweeps (``memory`` 0). (With the acceleration, which takes it sooner to where only
#: the slowest mode is left, it does stall at 256 sweeps, its change lowered by 2 % in the
#: span: a cold force solve to 1e-14 of its accelerations that plain sweeps do not finish
#: within MAX_SWEEPS either; in the engine a stall grows the cluster or freezes friction.)
STALL_FACTOR = 0.9
#: Anderson acceleration of the sweeps (Anderson 1965; Walker & Ni 2011, SIAM J. Numer. Anal.
#: 49, 1715): a solve not converged after ANDERSON_AFTER sweeps goes on from the combination of
#: its last ANDERSON_MEMORY sweeps' results whose change is least, in the least-squares sense,
#: projected back onto the cones, instead of from the last result alone; every such point is
#: followed by a plain sweep, and the convergence test is the plain sweep's, so what a solve
#: returns meets the same conditions as before. On the bed of a 14° chute (250–360 spheres,
#: 350–430 frictional contacts, the force problem of one segment, cold) the sweeps fell from
#: 473–2,548 to 81–119; a run of the chute with its bed in constrained motion took 2.9 times
#: less CPU (docs/enduring-contact.md, "Anderson acceleration").
ANDERSON_MEMORY = 5
#: Sweeps of plain Gauss–Seidel before the acceleration starts [-]: small clusters, which converge
#: in tens of sweeps, are solved as before (bit for bit) and pay nothing for it.
ANDERSON_AFTER = 32
#: The history of combinations is dropped, and built again from plain sweeps, where a sweep's
#: change (squared, in velocity units) exceeds this multiple of the least so far [-]: the
#: safeguard against the least-squares combination leading away, as it may where the map is not
#: smooth (a contact entering or leaving its cone; Zhang, O'Donoghue & Boyd 2020, SIAM J.
#: Optim. 30, 3170).
ANDERSON_RESTART = 4.0
#: Regularisation of the least-squares problem, relative to the trace of its matrix [-]: the
#: changes of successive sweeps become nearly parallel as they converge.
ANDERSON_REG = 1e-12
#: The acceleration ends, and plain sweeps finish the solve, once this many sweeps in a row
#: have not lowered the least change so far [-]: near a solution met to the last digits the
#: combinations, which rebuild the bodies' velocities from all impulses, stop gaining on
#: rounding (a column of 40 spheres solved to 1e-14 of its accelerations), and where the
#: problem has no solution, plain sweeps show it to the stall test, which starts its spans
#: afresh. (Asking instead that the least change halve every ten sweeps ended it too soon in
#: a chute's bed, whose frictional solves gain unevenly: 3.2 times the sweeps.)
ANDERSON_PATIENCE = 2 * ANDERSON_MEMORY
#: A combination is dropped (and the history with it) where one of its impulses, in the
#: velocity it makes, is so large that a change of ``tol`` would be less than
#: ANDERSON_RESOLVE units in its last place (ROUNDOFF of it) [-]: the change test could no longer
#: see that such a point is not a solution. (Where the problem has no solution, the
#: least-squares combination ran off to impulses 10¹¹ times the real ones, at which a sweep's
#: changes vanished in rounding and the test passed.)
ANDERSON_RESOLVE = 1.0
#: A combination is dropped (and the history with it) where its largest impulse, in the
#: velocity it makes, exceeds this multiple of the largest of the plain sweep it extrapolates
#: from [-]. Where the sweeps drift at a constant rate along impulses that change no velocity
#: (a sphere wedged between two partners whose normals, tilted by friction, are opposite: a
#: self-equilibrated pair of forces of any size meets both contacts), successive changes are
#: equal and the secant runs off: on a sphere wedged between a wall and a resting sphere
#: (normals 162° apart, μ = 0.62) one combination multiplied the impulses by 3,500, a
#: pre-stress that the next steps' warm starts carried into the bed and that friction, solved
#: to its sweeps' accuracy, turned into motion: that pour into a jammed wedge (corpus scene
#: 0-17) woke, flew apart and settled again until 0.8 s and took 80.9 s of CPU; with the
#: combination dropped there it is at rest by 0.4 s after 21.8 s. Converging solves grow
#: their impulses gradually: a column's load reaches its base one contact per sweep, and by
#: ANDERSON_AFTER sweeps the largest impulse is a fair part of its end value.
ANDERSON_GROWTH = 10.0


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


@njit(inline="always")
def _weights(k, ca, cb, crb, inv_m, inv_i, rad, rotation):
    """Contact k's local Delassus weights: what a unit normal impulse, and a unit tangential
    one, change its relative velocity by [1/kg] (diagonal in the contact frame for two
    spheres)."""
    a = ca[k]
    b = cb[k]
    inv_mb = inv_m[b] if b >= 0 else 0.0
    w_n = inv_m[a] + inv_mb
    w_t = w_n
    if rotation:
        w_t += inv_i[a] * rad[a] * rad[a]
        if b >= 0:
            w_t += inv_i[b] * crb[k] * crb[k]
    return w_n, w_t


# long: one Gauss–Seidel sweep's local solve (normal, Coulomb cone, rolling couple) shares the
# contact's frame and the old impulses; split, they would travel back and forth as tuples
@njit
def _sweep(nc, ca, cb, cn, crb, cvb, target, mu, slip, mur, reff, rslip, inv_m, inv_i, rad, v,
           w, pn, pt, hr, rotation, friction, rolling):
    """One sweep of non-smooth Gauss–Seidel over the contacts (the arguments as in
    :func:`solve`); returns the largest change of a contact's impulse in it, in the velocity it
    makes [m/s] (for a rolling couple: R* times the angular velocity)."""
    change = 0.0
    for k in range(nc):
        a = ca[k]
        b = cb[k]
        nx, ny, nz = cn[k, 0], cn[k, 1], cn[k, 2]
        w_n, w_t = _weights(k, ca, cb, crb, inv_m, inv_i, rad, rotation)
        if w_n == 0.0:
            continue
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
    return change


@njit
def _scales(nc, ca, cb, crb, reff, inv_m, inv_i, rad, rotation, scale):
    """Per contact, what turns its normal impulse, tangential impulse and rolling couple into
    the velocities they make [m/(N s)] (as :func:`_sweep` weighs its changes): the
    acceleration's unknowns in comparable units, into ``scale`` (nc, 3). A contact between
    immovable bodies gets 0."""
    for k in range(nc):
        scale[k, 0] = scale[k, 1] = scale[k, 2] = 0.0
        a = ca[k]
        b = cb[k]
        w_n, w_t = _weights(k, ca, cb, crb, inv_m, inv_i, rad, rotation)
        if w_n == 0.0:
            continue
        scale[k, 0] = w_n
        scale[k, 1] = w_t
        scale[k, 2] = (inv_i[a] + (inv_i[b] if b >= 0 else 0.0)) * reff[k]


@njit
def _pack(nc, pn, pt, hr, scale, stride, x):
    """The impulses as one vector x (``stride`` entries per contact: the normal impulse; with
    friction or rolling (4) the tangential impulse; with rolling (7) the rolling couple), in
    velocity units."""
    for k in range(nc):
        o = stride * k
        x[o] = pn[k] * scale[k, 0]
        if stride > 1:
            for j in range(3):
                x[o + 1 + j] = pt[k, j] * scale[k, 1]
        if stride > 4:
            for j in range(3):
                x[o + 4 + j] = hr[k, j] * scale[k, 2]


# long: the inverse of _pack with each contact's projection onto its cone, then the bodies'
# velocities from the impulses; split, the eight kinds of contact data would travel twice
@njit
def _unpack(nc, x, scale, stride, ca, cb, cn, crb, mu, slip, mur, reff, rslip, inv_m, inv_i,
            rad, v0, w0, v, w, pn, pt, hr, rotation, friction, rolling):
    """Impulses from the vector x (:func:`_pack`), projected onto what each contact allows
    (P_n ≥ 0; P_t in the Coulomb cone, or along −slip for a contact that slips; the rolling
    couple within μ_r R* P_n, or along −rslip), and the bodies' velocities ``v``, ``w`` they
    make from those without contacts, ``v0``, ``w0`` (the first ``v0.shape[0]`` bodies: those
    of the contacts)."""
    for k in range(nc):
        if scale[k, 0] == 0.0:
            continue
        o = stride * k
        p = max(0.0, x[o] / scale[k, 0])
        pn[k] = p
        if friction:
            if slip[k, 0] != 0.0 or slip[k, 1] != 0.0 or slip[k, 2] != 0.0:
                for j in range(3):
                    pt[k, j] = -mu[k] * p * slip[k, j]
            else:
                s = scale[k, 1]
                pt[k, 0], pt[k, 1], pt[k, 2] = cap(x[o + 1] / s, x[o + 2] / s, x[o + 3] / s,
                                                   mu[k] * p)
        if rolling and rotation and mur[k] > 0.0:
            limit = mur[k] * reff[k] * p
            if rslip[k, 0] != 0.0 or rslip[k, 1] != 0.0 or rslip[k, 2] != 0.0:
                for j in range(3):
                    hr[k, j] = -limit * rslip[k, j]
            else:
                s = scale[k, 2]
                hr[k, 0], hr[k, 1], hr[k, 2] = cap(x[o + 4] / s, x[o + 5] / s, x[o + 6] / s,
                                                   limit)
    for i in range(v0.shape[0]):
        for j in range(3):
            v[i, j] = v0[i, j]
            w[i, j] = w0[i, j]
    start(nc, ca, cb, cn, crb, inv_m, inv_i, rad, v, w, pn, pt, hr, rotation)


@njit(inline="always")
def _bodies(nc, ca, cb):
    """How many bodies the first nc contacts join (one more than the largest body index): the
    caller's arrays may hold many more rows (the scratch of the largest cluster)."""
    nbody = 0
    for k in range(nc):
        nbody = max(nbody, ca[k] + 1, cb[k] + 1)
    return nbody


@njit
def _free(nc, ca, cb, cn, crb, inv_m, inv_i, rad, v, w, pn, pt, hr, rotation, v0, w0):
    """The velocities of the contacts' bodies (the first ``v0.shape[0]``) without the contacts'
    impulses, into ``v0``, ``w0``: ``v``, ``w`` less what ``pn``, ``pt``, ``hr`` make (the
    inverse of :func:`start`)."""
    for i in range(v0.shape[0]):
        for j in range(3):
            v0[i, j] = v[i, j]
            w0[i, j] = w[i, j]
    for k in range(nc):
        _apply(k, -(pn[k] * cn[k, 0] + pt[k, 0]), -(pn[k] * cn[k, 1] + pt[k, 1]),
               -(pn[k] * cn[k, 2] + pt[k, 2]), ca, cb, cn, crb, inv_m, inv_i, rad, v0, w0,
               rotation)
        if rotation:
            _apply_couple(k, -hr[k, 0], -hr[k, 1], -hr[k, 2], ca, cb, inv_i, w0)


@njit(allocates=True)
def _combine(hist, x, g, f, dg, df, gram):
    """Anderson's combination (type II): with the last ``hist`` differences of the sweeps'
    results ``dg`` and of their changes ``df`` (rows), and their Gram matrix ``gram``, the
    coefficients γ minimising |f − Δf γ| give the next point x = g − Δg γ."""
    a = np.empty((hist, hist))
    rhs = np.empty(hist)
    trace = 0.0
    for p in range(hist):
        for q in range(hist):
            a[p, q] = gram[p, q]
        trace += gram[p, p]
        rhs[p] = np.dot(df[p], f)
    for p in range(hist):
        a[p, p] += ANDERSON_REG * max(trace, 1e-300)
    gamma = np.linalg.solve(a, rhs)
    x[:] = g
    for p in range(hist):
        for i in range(x.shape[0]):  # (in place: no temporary per term)
            x[i] -= gamma[p] * dg[p, i]


@njit(inline="always")
def _tested_sweep(sweeps, check, least, before, stall, tol, nc, ca, cb, cn, crb, cvb, target,
                  mu, slip, mur, reff, rslip, inv_m, inv_i, rad, v, w, pn, pt, hr, rotation,
                  friction, rolling):
    """Sweep number ``sweeps`` (:func:`_sweep`, the arguments as in :func:`solve`) and the
    stopping tests after it: returns (0 go on, 1 converged, 2 stalled; the stall test's state
    ``check``, ``least``, ``before`` carried on; and where it stops, the largest shortfall of
    a normal velocity, as :func:`solve` returns it)."""
    change = _sweep(nc, ca, cb, cn, crb, cvb, target, mu, slip, mur, reff, rslip, inv_m, inv_i,
                    rad, v, w, pn, pt, hr, rotation, friction, rolling)
    if change <= tol:
        worst = _worst(nc, ca, cb, cn, crb, cvb, target, rad, v, w, rotation)
        if worst <= tol:
            return 1, check, least, before, worst
    least = min(least, change)
    if stall and sweeps == check:
        if least > STALL_FACTOR * before:
            return 2, check, least, before, _worst(nc, ca, cb, cn, crb, cvb, target, rad, v, w,
                                                   rotation)
        before = least
        least = math.inf
        check *= 2
    return 0, check, least, before, 0.0


# long: the solve's loop again, with the acceleration's state; split, a dozen arrays would
# travel between the parts
@njit(allocates=True)
def _accelerated(nc, ca, cb, cn, crb, cvb, target, mu, slip, mur, reff, rslip, inv_m, inv_i,
                 rad, v, w, pn, pt, hr, rotation, friction, rolling, tol, max_sweeps, stall,
                 memory, sweeps, check, least, before):
    """:func:`solve` from its sweep ``sweeps`` on (with its stall test's state), each plain
    sweep followed by Anderson's combination of the last ``memory`` (ANDERSON_MEMORY; type
    II, with the restart ANDERSON_RESTART); returns what :func:`solve` does."""
    # per contact: P_n; with friction (or rolling) P_t; with rolling the couple
    stride = 1 + (3 if friction or rolling else 0) + (3 if rolling and rotation else 0)
    n = stride * nc
    scale = np.empty((nc, 3))
    _scales(nc, ca, cb, crb, reff, inv_m, inv_i, rad, rotation, scale)
    x, g, f = np.empty(n), np.empty(n), np.empty(n)
    g_old, f_old = np.empty(n), np.empty(n)
    dg, df = np.empty((memory, n)), np.empty((memory, n))
    gram = np.empty((memory, memory))
    # the contacts' bodies only: the caller's arrays may hold many more rows (the scratch of
    # the largest cluster), which the acceleration's every combination would otherwise copy
    nbody = _bodies(nc, ca, cb)
    v0, w0 = np.empty((nbody, 3)), np.empty((nbody, 3))
    _free(nc, ca, cb, cn, crb, inv_m, inv_i, rad, v, w, pn, pt, hr, rotation, v0, w0)
    _pack(nc, pn, pt, hr, scale, stride, x)
    hist = 0  # differences remembered
    slot = 0  # where the next goes
    best = math.inf  # the least squared change so far
    since = 0  # sweeps since it was last lowered
    active = True
    first = True
    while sweeps < max_sweeps:
        sweeps += 1
        verdict, check, least, before, worst = _tested_sweep(
            sweeps, check, least, before, stall, tol, nc, ca, cb, cn, crb, cvb, target, mu, slip,
            mur, reff, rslip, inv_m, inv_i, rad, v, w, pn, pt, hr, rotation, friction, rolling)
        if verdict:
            return sweeps, worst, verdict == 2
        if not active:
            continue
        _pack(nc, pn, pt, hr, scale, stride, g)
        f2 = 0.0
        for i in range(n):
            f[i] = g[i] - x[i]
            f2 += f[i] * f[i]
        since = 0 if f2 < best else since + 1
        if since >= ANDERSON_PATIENCE:
            # plain sweeps from here on, their stall test on plain sweeps alone
            active = False
            least = before = math.inf
            continue
        if f2 > ANDERSON_RESTART * best:
            hist = 0
            slot = 0
        elif not first:
            for i in range(n):
                dg[slot, i] = g[i] - g_old[i]
                df[slot, i] = f[i] - f_old[i]
            for q in range(max(hist, slot + 1)):
                gram[slot, q] = np.dot(df[slot], df[q])
                gram[q, slot] = gram[slot, q]
            slot = (slot + 1) % memory
            hist = min(hist + 1, memory)
        first = False
        best = min(best, f2)
        for i in range(n):
            g_old[i] = g[i]
            f_old[i] = f[i]
        if hist == 0:
            x[:] = g
            continue
        _combine(hist, x, g, f, dg, df, gram)
        largest = 0.0
        plain = 0.0
        for i in range(n):
            if not abs(x[i]) <= largest:  # (a NaN, from a singular least-squares problem, too)
                largest = abs(x[i])
            plain = max(plain, abs(g[i]))
        if not (largest * ROUNDOFF <= ANDERSON_RESOLVE * tol
                and largest <= ANDERSON_GROWTH * plain):
            # beyond what the change test can see, or run off: go on from the plain sweep's result
            hist = 0
            slot = 0
            x[:] = g
            continue
        _unpack(nc, x, scale, stride, ca, cb, cn, crb, mu, slip, mur, reff, rslip, inv_m, inv_i,
                rad, v0, w0, v, w, pn, pt, hr, rotation, friction, rolling)
        _pack(nc, pn, pt, hr, scale, stride, x)
    return sweeps, _worst(nc, ca, cb, cn, crb, cvb, target, rad, v, w, rotation), False


@njit
def solve(nc, ca, cb, cn, crb, cvb, target, mu, slip, mur, reff, rslip, inv_m, inv_i, rad, v,
          w, pn, pt, hr, rotation, friction, rolling, tol, max_sweeps=MAX_SWEEPS, stall=False,
          memory=ANDERSON_MEMORY):
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
        memory: Sweeps that Anderson's combination remembers after ANDERSON_AFTER sweeps
            (ANDERSON_MEMORY; :func:`_accelerated`); 0 for plain Gauss–Seidel throughout.

    Returns:
        (sweeps, worst, stalled): sweeps done; the largest amount by which a contact's
        relative normal velocity ends below its target (≤ 0 when every contact is
        satisfied) [m/s]; whether it stopped for a stall.
    """
    sweeps = 0
    check = STALL_SWEEPS
    least = math.inf  # the smallest change since the last check
    before = math.inf  # ... in the span before it
    while sweeps < max_sweeps:
        if memory > 0 and nc > 1 and sweeps == ANDERSON_AFTER:
            return _accelerated(nc, ca, cb, cn, crb, cvb, target, mu, slip, mur, reff, rslip,
                                inv_m, inv_i, rad, v, w, pn, pt, hr, rotation, friction,
                                rolling, tol, max_sweeps, stall, memory, sweeps, check, least,
                                before)
        sweeps += 1
        verdict, check, least, before, worst = _tested_sweep(
            sweeps, check, least, before, stall, tol, nc, ca, cb, cn, crb, cvb, target, mu, slip,
            mur, reff, rslip, inv_m, inv_i, rad, v, w, pn, pt, hr, rotation, friction, rolling)
        if verdict:
            return sweeps, worst, verdict == 2
    return sweeps, _worst(nc, ca, cb, cn, crb, cvb, target, rad, v, w, rotation), False


#: Lawson & Hanson's NNLS (:func:`_nnls`) takes at most this many steps per contact [-]
#: (their limit, 3n; a step joins a contact to the set that carries, or lets one go): on the
#: stalled wedge step of corpus 0-79 (307 contacts) it took 44 from the impulses the finish
#: began with, 251 from none.
NNLS_STEPS_PER_CONTACT = 3
#: A contact joins the NNLS's set only where the part of its column orthogonal to the set's
#: is above this fraction of the column's norm [-]; below, it depends on them as far as
#: double precision tells (Gram–Schmidt leaves ~1e-16 of each column; the margin covers the
#: growth of that with the set's size), and its least-squares problem would be singular. Such
#: a contact stays out (and, if short, the finish is short by as much).
NNLS_DEPENDENT_REL = 1e-12
#: Gram–Schmidt orthogonalises a column against the set a second time where the first pass
#: took away more than this fraction of its norm [-] (Kahan and Parlett's "twice is enough",
#: in Parlett 1980, "The symmetric eigenvalue problem": after a second pass the column is
#: orthogonal to working precision; where the first kept more than half, it is already).
REORTHOGONALISE_BELOW = 0.5
#: Largest set of contacts the finish solves directly [-]: its NNLS keeps a dense QR
#: factorisation of (3 bodies + 1) rows by up to as many columns as contacts, which costs
#: about their number squared times the bodies' (1,500: about a second), so a larger stalled
#: solve keeps what the sweeps reached.
REFINE_MAX = 1500


#: Iterations of the projected conjugate gradients that first try to finish a normal solve
#: (:func:`_mprgp`), per contact, and at least MPRGP_MIN [-]: conjugate gradients meet a
#: problem of n unknowns in n iterations (in exact arithmetic, on a fixed set of active
#: contacts); on corpus 0-39's bed (525 contacts, from the friction sweeps' impulses, 1e-6 m/s
#: short) they met every contact to 1e-12 m/s in 141 iterations, 2 ms, where the dense finish
#: took 60–200 ms. (From no impulse a column's contacts join one at a time, about 4n
#: iterations; what the limit leaves unmet, the dense finish takes.)
MPRGP_PER_CONTACT = 4
MPRGP_MIN = 200
#: The proportioning test's Γ of MPRGP [-] (Dostál & Schöberl 2005): a step leaves the face
#: of the active contacts when the gradient pushing contacts off their bounds exceeds Γ times
#: the reduced free gradient; 1 is the value their analysis and experiments use.
MPRGP_GAMMA = 1.0
#: The expansion step's length, as a fraction of 2/‖W‖ (Dostál & Schöberl 2005 ask for a
#: length in (0, 2/‖W‖]; ‖W‖ is bounded by Gershgorin's row sums of the Jacobi-scaled
#: Delassus matrix) [-].
MPRGP_STEP = 0.95


@njit(inline="always")
def _scaled_product(nc, ca, cb, cn, inv_m, s, x, dv, y):
    """y = S W S x, W the normal Delassus matrix (:func:`_delassus`), S = diag(s), through the
    bodies' velocity changes ``dv`` (scratch, one row per body)."""
    for i in range(dv.shape[0]):
        dv[i, 0] = dv[i, 1] = dv[i, 2] = 0.0
    for k in range(nc):
        a, b = ca[k], cb[k]
        p = x[k] * s[k]
        for j in range(3):
            dv[a, j] += inv_m[a] * p * cn[k, j]
            if b >= 0:
                dv[b, j] -= inv_m[b] * p * cn[k, j]
    for k in range(nc):
        a, b = ca[k], cb[k]
        u = 0.0
        for j in range(3):
            u += (dv[a, j] - (dv[b, j] if b >= 0 else 0.0)) * cn[k, j]
        y[k] = u * s[k]


@njit(inline="always")
def _scaled_gradient(nc, ca, cb, cn, inv_m, s, q, x, dv, g):
    """g = S W S x + S q: the gradient of the Jacobi-scaled normal problem at x (computed
    afresh, :func:`_mprgp`)."""
    _scaled_product(nc, ca, cb, cn, inv_m, s, x, dv, g)
    for k in range(nc):
        g[k] += q[k] * s[k]


@njit(inline="always")
def _curvature(nc, ca, cb, cn, inv_m, s, d, g, dv, wd):
    """For a direction d of the scaled problem: W d (into ``wd``), dᵀWd and gᵀd, which give the
    step along d that minimises the quadratic (:func:`_mprgp`)."""
    _scaled_product(nc, ca, cb, cn, inv_m, s, d, dv, wd)
    dwd = 0.0
    gd = 0.0
    for k in range(nc):
        dwd += d[k] * wd[k]
        gd += g[k] * d[k]
    return dwd, gd


@njit(inline="always")
def _free_gradient(nc, x, g, p):
    """The gradient's part on the contacts that carry an impulse (MPRGP's free gradient φ)."""
    for k in range(nc):
        p[k] = g[k] if x[k] > 0.0 else 0.0


# long: one algorithm (MPRGP) with its three kinds of step sharing the iterate, gradient and
# direction; split, each would take them all
@njit(allocates=True)
def _mprgp(nc, ca, cb, cn, inv_m, q, lam, tol):
    """The normal impulses ``lam`` [N s] (updated in place, from where they are) that minimise
    ½ λᵀWλ + qᵀλ over λ ≥ 0, W the normal Delassus matrix and q the contacts' normal
    velocities without normal impulses less their targets [m/s] (:func:`refine_normals`): the
    normal problem with the tangential impulses held, whose optimality conditions are the
    contacts' Signorini conditions. Dostál's MPRGP (modified proportioning with reduced
    gradient projections; Dostál & Schöberl 2005, Comput. Optim. Appl. 30, 23; Dostál 2009,
    "Optimal quadratic programming algorithms", ch. 5): conjugate gradients on the face of
    the contacts that carry an impulse, a projected expansion step where a gradient step would
    leave the bounds, and a proportioning step releasing the contacts that pull where they
    dominate; on the Jacobi-scaled problem (each contact's unknown in the velocity it makes).
    Conjugate gradients converge as the square root of the condition number, where
    Gauss–Seidel converges as the condition number itself. Stops where the natural residual
    (:func:`_natural_residual`) is within ``tol`` [m/s] or after MPRGP_PER_CONTACT iterations
    per contact (a problem with no solution, whose minimum is −∞). Returns the iterations."""
    nbody = _bodies(nc, ca, cb)
    s = np.zeros(nc)  # λ = s x
    rows = np.zeros(nbody)  # per body: Σ s over its contacts (Gershgorin's bound)
    for k in range(nc):
        a, b = ca[k], cb[k]
        d = inv_m[a] + (inv_m[b] if b >= 0 else 0.0)
        if d > 0.0:
            s[k] = 1.0 / math.sqrt(d)
        rows[a] += s[k]
        if b >= 0:
            rows[b] += s[k]
    bound = 0.0
    for k in range(nc):
        a, b = ca[k], cb[k]
        bound = max(bound, s[k] * (inv_m[a] * rows[a] + (inv_m[b] * rows[b] if b >= 0 else 0.0)))
    if bound == 0.0:
        return 0
    step = MPRGP_STEP * 2.0 / bound
    x, g, p, wp, d = np.zeros(nc), np.zeros(nc), np.zeros(nc), np.zeros(nc), np.zeros(nc)
    dv = np.empty((nbody, 3))
    for k in range(nc):
        x[k] = lam[k] / s[k] if s[k] > 0.0 else 0.0
    _scaled_gradient(nc, ca, cb, cn, inv_m, s, q, x, dv, g)
    _free_gradient(nc, x, g, p)
    most = max(MPRGP_MIN, MPRGP_PER_CONTACT * nc)
    it = 0
    exact = True  # g computed afresh (not by the recurrence) since the last step
    while True:
        res = 0.0
        chopped = 0.0  # |β|², the chopped gradient: contacts at 0 that pull
        reduced = 0.0  # φ̃ᵀφ, the reduced free gradient
        for k in range(nc):
            if s[k] == 0.0:
                continue
            if x[k] > 0.0:
                res = max(res, abs(g[k]) / s[k])
                reduced += (min(x[k] / step, g[k]) if g[k] > 0.0 else g[k]) * g[k]
            elif g[k] < 0.0:
                res = max(res, -g[k] / s[k])
                chopped += g[k] * g[k]
        if res <= tol and not exact:
            # confirm on the gradient computed afresh (the recurrence drifts by rounding)
            _scaled_gradient(nc, ca, cb, cn, inv_m, s, q, x, dv, g)
            _free_gradient(nc, x, g, p)
            exact = True
            continue
        if res <= tol or it >= most:
            break
        it += 1
        exact = False
        if chopped <= MPRGP_GAMMA * MPRGP_GAMMA * reduced:
            pwp, gp = _curvature(nc, ca, cb, cn, inv_m, s, p, g, dv, wp)
            if not pwp > 0.0:
                _free_gradient(nc, x, g, p)
                break
            cg = gp / pwp
            feasible = math.inf
            for k in range(nc):
                if p[k] > 0.0:
                    feasible = min(feasible, x[k] / p[k])
            if cg <= feasible:  # conjugate gradient step
                for k in range(nc):
                    x[k] -= cg * p[k]
                    g[k] -= cg * wp[k]
                _free_gradient(nc, x, g, d)
                beta = 0.0
                for k in range(nc):
                    beta += d[k] * wp[k]
                beta /= pwp
                for k in range(nc):
                    p[k] = d[k] - beta * p[k]
            else:  # expansion: to the bound, then a projected gradient step
                for k in range(nc):
                    x[k] -= feasible * p[k]
                    g[k] -= feasible * wp[k]
                for k in range(nc):
                    x[k] = max(x[k] - step * g[k], 0.0) if x[k] > 0.0 else 0.0
                _scaled_gradient(nc, ca, cb, cn, inv_m, s, q, x, dv, g)
                _free_gradient(nc, x, g, p)
                exact = True
        else:  # proportioning: release the contacts at 0 that pull
            for k in range(nc):
                d[k] = min(g[k], 0.0) if x[k] <= 0.0 else 0.0
            dwd, gd = _curvature(nc, ca, cb, cn, inv_m, s, d, g, dv, wp)
            if not dwd > 0.0:
                break
            a = gd / dwd
            for k in range(nc):
                x[k] -= a * d[k]
                g[k] -= a * wp[k]
            _free_gradient(nc, x, g, p)
    for k in range(nc):
        lam[k] = x[k] * s[k]
    return it


@njit(inline="always")
def _push_normals(nc, ca, cb, cn, inv_m, pn, v, sign):
    """Add ``sign`` times the velocity changes [m/s] of the normal impulses ``pn`` [N s] to the
    bodies' velocities ``v`` (−1: take them away)."""
    for k in range(nc):
        a, b = ca[k], cb[k]
        for j in range(3):
            v[a, j] += sign * inv_m[a] * pn[k] * cn[k, j]
            if b >= 0:
                v[b, j] -= sign * inv_m[b] * pn[k] * cn[k, j]


@njit(inline="always")
def _natural_residual(nc, lam, g):
    """Residual [m/s] of normal impulses ``lam`` whose contacts' velocities less their targets are
    ``g``: the largest shortfall (−g), or excess (g) of a contact that carries an impulse; and
    the largest shortfall alone."""
    res = 0.0
    short = 0.0
    for k in range(nc):
        short = max(short, -g[k])
        res = max(res, abs(g[k]) if lam[k] > 0.0 else -g[k])
    return res, short


@njit(allocates=True)
def _scored(nc, ca, cb, cn, inv_m, lam, q, best, best_lam, short):
    """The gradient W λ + q at normal impulses ``lam`` and its natural residual
    (:func:`_natural_residual`); ``lam`` is copied to ``best_lam`` where that residual is below
    ``best``, with ``short``, its largest shortfall. Returns (gradient, residual, best,
    short)."""
    g = _normal_gradient(nc, ca, cb, cn, inv_m, lam, q)
    res, worst = _natural_residual(nc, lam, g)
    if res < best:
        best_lam[:] = lam
        return g, res, res, worst
    return g, res, best, short


@njit(inline="always")
def _ldp_column(k, ca, cb, cn, root, h, e, rows):
    """Column k of the NNLS matrix E = [G; hᵀ] of :func:`_nnls` into ``e`` (dense, 3 bodies + 1
    rows; G's column k is contact k's normal at its bodies' rows, times their √(1/(m w₀)) in
    ``root``, + at body a, − at body b, so that GᵀG is the scaled Delassus matrix); the rows it
    fills go to ``rows``. Returns their number (7 between two bodies, 4 against an immovable
    partner)."""
    e[:] = 0.0
    a, b = ca[k], cb[k]
    count = 0
    for j in range(3):
        e[3 * a + j] = root[a] * cn[k, j]
        rows[count] = 3 * a + j
        count += 1
    if b >= 0:
        for j in range(3):
            e[3 * b + j] = -root[b] * cn[k, j]
            rows[count] = 3 * b + j
            count += 1
    last = e.shape[0] - 1
    e[last] = h[k]
    rows[count] = last
    return count + 1


@njit(allocates=True)
def _qr_join(m, qt, r, e, rows, count):
    """Append column ``e`` (nonzero at its ``count`` ``rows``) to the QR factorisation of the
    set's m columns (``qt``: Qᵀ, a row per column; ``r``: R) by classical Gram–Schmidt, with a
    second pass where the first took more than REORTHOGONALISE_BELOW of it. Returns False, the
    set's factors unchanged, where what is left is within NNLS_DEPENDENT_REL of its norm."""
    norm0 = 0.0
    for t in range(count):
        norm0 += e[rows[t]] ** 2
    norm0 = math.sqrt(norm0)
    for p in range(m):  # the first pass: e is sparse
        x = 0.0
        for t in range(count):
            x += qt[p, rows[t]] * e[rows[t]]
        r[p, m] = x
    if m > 0:
        e -= np.dot(r[:m, m].copy(), qt[:m])
    d = math.sqrt(np.dot(e, e))
    if d < REORTHOGONALISE_BELOW * norm0 and m > 0:
        x = np.dot(qt[:m], e)
        e -= np.dot(x, qt[:m])
        r[:m, m] += x
        d = math.sqrt(np.dot(e, e))
    if not d > NNLS_DEPENDENT_REL * norm0:
        return False
    qt[m] = e / d
    r[m, m] = d
    return True


@njit(allocates=True)
def _qr_drop(m, order, qt, r, p):
    """Remove the set's column at position p from its QR factorisation (m columns; ``order``:
    the contacts of the positions): R loses column p, and Givens rotations of R's rows (and of
    Q's columns) take the subdiagonal that leaves (the deletion of a column from a QR
    factorisation: Golub & Van Loan, "Matrix computations", on updating factorisations)."""
    for c in range(p, m - 1):
        order[c] = order[c + 1]
        for i in range(c + 2):
            r[i, c] = r[i, c + 1]
    for i in range(p, m - 1):
        a, b = r[i, i], r[i + 1, i]
        rho = math.hypot(a, b)
        c, s = a / rho, b / rho
        for k in range(i, m - 1):
            x, y = r[i, k], r[i + 1, k]
            r[i, k] = c * x + s * y
            r[i + 1, k] = -s * x + c * y
        r[i + 1, i] = 0.0
        upper = qt[i].copy()
        qt[i] = c * upper + s * qt[i + 1]
        qt[i + 1] = -s * upper + c * qt[i + 1]


@njit(inline="always")
def _qr_least_squares(m, qt, r, z):
    """The least-squares solution z of E_P z ≈ f on the set's m columns, f the last unit vector
    (so Qᵀf is Q's last row): back substitution in R."""
    last = qt.shape[1] - 1
    for p in range(m - 1, -1, -1):
        z[p] = (qt[p, last] - np.dot(r[p, p + 1:m], z[p + 1:m])) / r[p, p]


@njit(inline="always")
def _ldp_impulses(nc, u, h, scale, w0, lam):
    """The normal impulses [N s] of the NNLS solution u (:func:`_nnls`): λ = u / (1 − hᵀu) in the
    scaled units, times scale / w₀; False (``lam`` as it was) where 1 − hᵀu ≤ 0: the NNLS
    residual vanishes, and the problem has no solution."""
    hu = 0.0
    for k in range(nc):
        hu += h[k] * u[k]
    if not 1.0 - hu > 0.0:
        return False
    for k in range(nc):
        lam[k] = u[k] / (1.0 - hu) * scale / w0
    return True


@njit(allocates=True)
def _nnls(nc, ca, cb, cn, inv_m, q, lam, tol):
    """The normal problem of :func:`_mprgp` (the same arguments; ``lam`` [N s] updated, from
    where it is) by Lawson & Hanson's NNLS on its least-distance form (Lawson & Hanson 1974,
    "Solving least squares problems", ch. 23, algorithms LDP and NNLS). The velocities that
    meet every contact with the least change of kinetic energy are the solution (its
    optimality conditions are the contacts' Signorini conditions); in y = √M Δv scaled by
    √w₀ (w₀ the largest diagonal entry of W) they are the shortest y with Gᵀy ≥ h, where
    GᵀG = W / w₀ and h = −q / max|q| (a least-distance problem). LDP solves that through the
    non-negative least squares min ‖E u − f‖ over u ≥ 0, E = [G; hᵀ] (:func:`_ldp_column`)
    and f the last unit vector: the impulses are u / (1 − hᵀu) in the scaled units
    (:func:`_ldp_impulses`), and the NNLS gradient Eᵀ(f − E u) is −(1 − hᵀu) times the
    contacts' scaled velocities less their targets. NNLS keeps a set of contacts that carry,
    whose least-squares problem it solves on a QR factorisation of their columns updated as
    contacts join and leave (:func:`_qr_join`, :func:`_qr_drop`): it joins the contact most
    short, and where the least-squares solution would take an impulse below zero it steps back
    to where the first one reaches zero, and that contact leaves the set. The solves are on
    the QR factors of E, not on W's normal equations, so they hold where W is singular (a
    bed's redundant contacts), to rounding of the set's conditioning, not of its square. Warm:
    the set starts as the contacts that carry in ``lam``. Stops where no contact is short by
    more than ``tol`` [m/s], or after NNLS_STEPS_PER_CONTACT steps per contact. Returns the
    steps taken (−1: nothing to solve; −2: the problem has no solution)."""
    nbody = _bodies(nc, ca, cb)
    w0 = 0.0
    scale = 0.0
    for k in range(nc):
        w0 = max(w0, _delassus(k, k, ca, cb, cn, inv_m))
        scale = max(scale, abs(q[k]))
    if not (scale > 0.0 and w0 > 0.0):
        return -1
    root = np.empty(nbody)
    for i in range(nbody):
        root[i] = math.sqrt(inv_m[i] / w0)
    h = np.empty(nc)
    hmu = 0.0
    for k in range(nc):
        h[k] = -q[k] / scale
        hmu += h[k] * lam[k] * w0 / scale
    u = np.zeros(nc)  # from λ: u = μ / (1 + hᵀμ), μ = λ w₀ / scale
    if 1.0 + hmu > 0.0:
        for k in range(nc):
            u[k] = lam[k] * w0 / scale / (1.0 + hmu)
    n = 3 * nbody + 1
    room = min(n, nc)
    qt = np.zeros((room, n))
    r = np.zeros((room, room))
    e = np.empty(n)
    rows = np.empty(7, dtype=np.int64)
    order = np.empty(room, dtype=np.int64)  # the contact at each position of the set
    inset = np.zeros(nc, dtype=np.bool_)
    barred = np.zeros(nc, dtype=np.bool_)  # dependent, or would carry nothing when joined
    m = 0
    for k in range(nc):
        if u[k] > 0.0:
            count = _ldp_column(k, ca, cb, cn, root, h, e, rows)
            if m < room and _qr_join(m, qt, r, e, rows, count):
                order[m] = k
                inset[k] = True
                m += 1
            else:
                u[k] = 0.0
    z = np.empty(room)
    steps = 0
    solve = m > 0
    limit = NNLS_STEPS_PER_CONTACT * nc
    while steps < limit:
        steps += 1
        while solve:  # least squares on the set, stepping back where it leaves u ≥ 0
            _qr_least_squares(m, qt, r, z)
            alpha = math.inf
            hit = -1
            for p in range(m):
                if z[p] <= 0.0:
                    k = order[p]
                    a = u[k] / (u[k] - z[p])
                    if a < alpha:
                        alpha = a
                        hit = p
            if hit < 0:
                for p in range(m):
                    u[order[p]] = z[p]
                break
            for p in range(m):
                k = order[p]
                u[k] += alpha * (z[p] - u[k])
            u[order[hit]] = 0.0
            for p in range(m - 1, -1, -1):
                k = order[p]
                if u[k] <= 0.0:
                    u[k] = 0.0
                    inset[k] = False
                    _qr_drop(m, order, qt, r, p)
                    m -= 1
            steps += 1
            if steps >= limit:
                break
        if not _ldp_impulses(nc, u, h, scale, w0, lam):
            return -2
        g = _normal_gradient(nc, ca, cb, cn, inv_m, lam, q)
        join = -1
        most = tol
        for k in range(nc):
            if not inset[k] and not barred[k] and -g[k] > most:
                most = -g[k]
                join = k
        if join < 0:
            break
        count = _ldp_column(join, ca, cb, cn, root, h, e, rows)
        solve = m < room and _qr_join(m, qt, r, e, rows, count)
        if solve:
            order[m] = join
            _qr_least_squares(m + 1, qt, r, z)
            solve = z[m] > 0.0  # (rounding: joined, it would carry nothing)
        if solve:
            inset[join] = True
            m += 1
        else:
            barred[join] = True
    if not _ldp_impulses(nc, u, h, scale, w0, lam):
        return -2
    return steps


@njit(allocates=True)
def refine_normals(nc, ca, cb, cn, cvb, target, inv_m, v, pn, tol):
    """:func:`refined`'s largest shortfall of a normal velocity afterwards [m/s]."""
    return refined(nc, ca, cb, cn, cvb, target, inv_m, v, pn, tol)[0]


@njit(allocates=True)
def refined(nc, ca, cb, cn, cvb, target, inv_m, v, pn, tol):
    """Finish a normal solve that Gauss–Seidel could not (the arguments as in :func:`solve`; the
    tangential impulses and rolling couples as they are, in ``v``): projected conjugate gradients
    (:func:`_mprgp`), and where those do not meet ``tol``, Lawson & Hanson's NNLS (:func:`_nnls`)
    from where they got to, on the contacts' normal impulses alone. Gauss–Seidel converges slowly
    where a bed's contacts are redundant (a row of spheres jammed between two walls): its Delassus
    matrix W then has zero eigenvalues, and the sweeps stall some 1e-8 m/s short of the targets;
    conjugate gradients converge faster but can stall as well where many contacts are on the edge
    of carrying (a wedge's bed). The residual is each contact's shortfall and, where it carries an
    impulse, its excess (complementarity, :func:`_natural_residual`); the impulses with the least
    residual are kept (:func:`_scored`). ``v`` and ``pn`` are updated where the residual ends below
    where it began. Returns the largest shortfall of a normal velocity afterwards [m/s] and the
    NNLS steps taken (0 where the conjugate gradients met ``tol``, or the set exceeds
    REFINE_MAX)."""
    nbody = _bodies(nc, ca, cb)
    # the velocities without the normal impulses, and q
    v0 = np.empty((nbody, 3))
    for i in range(nbody):
        for j in range(3):
            v0[i, j] = v[i, j]
    _push_normals(nc, ca, cb, cn, inv_m, pn, v0, -1.0)
    q = np.empty(nc)
    for k in range(nc):
        a, b = ca[k], cb[k]
        u = 0.0
        for j in range(3):
            vb = v0[b, j] if b >= 0 else cvb[k, j]
            u += (v0[a, j] - vb) * cn[k, j]
        q[k] = u - target[k]
    lam = pn[:nc].copy()
    g = _normal_gradient(nc, ca, cb, cn, inv_m, lam, q)
    begin, short = _natural_residual(nc, lam, g)
    best_lam = lam.copy()
    _mprgp(nc, ca, cb, cn, inv_m, q, lam, tol)
    _, _, best, short = _scored(nc, ca, cb, cn, inv_m, lam, q, begin, best_lam, short)
    steps = 0
    if best > tol and nc <= REFINE_MAX:
        lam[:] = best_lam  # (where the conjugate gradients found no better, from the start)
        steps = _nnls(nc, ca, cb, cn, inv_m, q, lam, tol)
        _, _, best, short = _scored(nc, ca, cb, cn, inv_m, lam, q, best, best_lam, short)
    if best < begin:
        for k in range(nc):
            pn[k] = best_lam[k]
        for i in range(nbody):
            for j in range(3):
                v[i, j] = v0[i, j]
        _push_normals(nc, ca, cb, cn, inv_m, pn, v, 1.0)
    return short, steps


@njit(inline="always")
def _delassus(kp, kr, ca, cb, cn, inv_m):
    """Entry (kp, kr) of the normal Delassus matrix: what a unit normal impulse at contact kr
    changes contact kp's relative normal velocity by [1/kg] (normal impulses do not turn
    spheres)."""
    dot = cn[kp, 0] * cn[kr, 0] + cn[kp, 1] * cn[kr, 1] + cn[kp, 2] * cn[kr, 2]
    e = 0.0
    ap, bp, ar, br = ca[kp], cb[kp], ca[kr], cb[kr]
    if ap == ar:
        e += inv_m[ap]
    if bp >= 0 and bp == br:
        e += inv_m[bp]
    if ap == br:
        e -= inv_m[ap]
    if bp >= 0 and bp == ar:
        e -= inv_m[bp]
    return e * dot


@njit(allocates=True)
def _normal_gradient(nc, ca, cb, cn, inv_m, lam, q):
    """W λ + q: each contact's normal velocity with the normal impulses λ, less its target."""
    nbody = _bodies(nc, ca, cb)
    dv = np.zeros((nbody, 3))
    for k in range(nc):
        a, b = ca[k], cb[k]
        for j in range(3):
            dv[a, j] += inv_m[a] * lam[k] * cn[k, j]
            if b >= 0:
                dv[b, j] -= inv_m[b] * lam[k] * cn[k, j]
    g = np.empty(nc)
    for k in range(nc):
        a, b = ca[k], cb[k]
        u = 0.0
        for j in range(3):
            u += (dv[a, j] - (dv[b, j] if b >= 0 else 0.0)) * cn[k, j]
        g[k] = u + q[k]
    return g


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


#: At most this many rounds of (normal polish, cones clipped) where the proportional polish of
#: :func:`_polish` has no solution, and of (direct finish, cones clipped) in
#: :func:`_finish_frozen` [-]: each clip changes a tangential impulse by what the polish or
#: finish before it changed the normal one (0.15 % of the cone in a pour's cluster), and a
#: last polish or finish follows the last clip.
POLISH_ROUNDS = 3


@njit
def _polish_frozen(nc, ca, cb, cn, crb, cvb, target, mu, slip, mur, reff, rslip, inv_m, inv_i,
                   rad, v, w, pn, pt, hr, rotation, friction, rolling, tol, stall):
    """The normal impulses solved to ``tol`` against the tangential impulses and rolling couples
    as they are, then the cones clipped where the new normal impulses no longer hold them, and
    polished again, at most POLISH_ROUNDS times (the arguments as in :func:`solve`). Returns
    :func:`solve`'s (sweeps, worst, stalled)."""
    sweeps = 0
    for _ in range(POLISH_ROUNDS):
        more, worst, stalled = solve(nc, ca, cb, cn, crb, cvb, target, mu, slip, mur, reff,
                                     rslip, inv_m, inv_i, rad, v, w, pn, pt, hr, rotation, False,
                                     False, tol, MAX_SWEEPS, stall)
        sweeps += more
        if stalled or _clip_cones(nc, ca, cb, cn, crb, mu, mur, reff, inv_m, inv_i, rad, v, w,
                                  pn, pt, hr, rotation, friction, rolling) == 0.0:
            return sweeps, worst, stalled
    more, worst, stalled = solve(nc, ca, cb, cn, crb, cvb, target, mu, slip, mur, reff, rslip,
                                 inv_m, inv_i, rad, v, w, pn, pt, hr, rotation, False, False, tol,
                                 MAX_SWEEPS, stall)
    return sweeps + more, worst, stalled


# long: the proportional polish, and the way back to where it began when it has no solution;
# split, the saved impulses and velocities would travel between the parts
@njit(allocates=True)
def _polish(nc, ca, cb, cn, crb, cvb, target, mu, slip, mur, reff, rslip, inv_m, inv_i, rad, v,
            w, pn, pt, hr, rotation, friction, rolling, tol, stall):
    """The normal impulses solved to ``tol`` with each tangential impulse held in proportion to
    its contact's normal impulse (the arguments as in :func:`solve`): the ratio |P_t|/P_n and
    the direction that the friction sweeps reached are kept, so that a change of a normal
    impulse moves its contact's friction with it, as sliding friction does (the Coulomb
    impulse of a contact at its cone's edge is μ P_n), and no tangential impulse leaves its
    cone. Normal impulses do not turn the spheres, and rolling couples are felt by no
    contact's normal velocity: those are clipped to μ_r R* P_n afterwards. Where friction
    held in proportion locks the bodies (the problem has no solution: a body wedged by a
    boundary that moves into it, :func:`solve`'s stall), the polish starts again from where
    it began with the tangential impulses fixed instead (:func:`_polish_frozen`), which the
    normal impulses can always meet. Returns :func:`solve`'s (sweeps, worst, stalled).

    (Polishing against tangential impulses held fixed, then clipping the cones where the new
    normal impulses no longer hold them, needs a polish after each clip: on a wedge's bed of
    525 contacts, 40–80 of them at their cones' edge, four polishes of 70–115 sweeps each,
    where the proportional one takes 140–160 sweeps.)"""
    if not friction:
        return _polish_frozen(nc, ca, cb, cn, crb, cvb, target, mu, slip, mur, reff, rslip,
                              inv_m, inv_i, rad, v, w, pn, pt, hr, rotation, friction, rolling,
                              tol, stall)
    ratio = np.zeros(nc)
    along = np.zeros((nc, 3))  # −P_t/|P_t|: the kinetic branch of _sweep keeps P_t = ratio P_n
    for k in range(nc):
        m = math.sqrt(pt[k, 0] ** 2 + pt[k, 1] ** 2 + pt[k, 2] ** 2)
        if m > 0.0 and pn[k] > 0.0:
            ratio[k] = m / pn[k]
            for j in range(3):
                along[k, j] = -pt[k, j] / m
    nbody = _bodies(nc, ca, cb)
    v0, w0 = v[:nbody].copy(), w[:nbody].copy()
    pn0, pt0 = pn[:nc].copy(), pt[:nc].copy()
    sweeps, worst, stalled = solve(nc, ca, cb, cn, crb, cvb, target, ratio, along, mur, reff,
                                   rslip, inv_m, inv_i, rad, v, w, pn, pt, hr, rotation, True,
                                   False, tol, MAX_SWEEPS, True)
    if stalled:
        v[:nbody] = v0
        w[:nbody] = w0
        pn[:nc] = pn0
        pt[:nc] = pt0
        more, worst, stalled = _polish_frozen(nc, ca, cb, cn, crb, cvb, target, mu, slip, mur,
                                              reff, rslip, inv_m, inv_i, rad, v, w, pn, pt, hr,
                                              rotation, friction, rolling, tol, stall)
        return sweeps + more, worst, stalled
    if rolling:
        _clip_cones(nc, ca, cb, cn, crb, ratio, mur, reff, inv_m, inv_i, rad, v, w, pn, pt, hr,
                    rotation, False, rolling)
    return sweeps, worst, stalled


@njit(allocates=True)
def _finish_frozen(nc, ca, cb, cn, crb, cvb, target, mu, mur, reff, inv_m, inv_i, rad, v, w, pn,
                   pt, hr, rotation, friction, rolling, tol):
    """The normal impulses finished directly with the tangential impulses and rolling couples
    frozen (:func:`refine_normals`), then the cones clipped where the new normal impulses no
    longer hold them and finished again, at most POLISH_ROUNDS times (the arguments as in
    :func:`solve`). Each clip changes a tangential impulse by less than the round before it
    changed the normal ones (on corpus 0-39's bed, 476 contacts: 1.5e-9, 1.6e-10, 1.4e-11 N s),
    and a finish follows each clip. Where a bed's normal problem converges slowly under
    Gauss–Seidel, this takes a few conjugate-gradient solves in place of the proportional
    polish's sweeps (that bed: 11 ms in place of 31 ms for the step's solve, the normals met
    to 7.5e-13 m/s in place of 3.5e-13, the cones to 2.3e-12 N s in place of 1.5e-9). Returns
    the largest shortfall of a normal velocity afterwards [m/s]; where that is above ``tol``,
    the impulses and velocities are put back as they were (a normal impulse the finish took
    towards zero under a tangential one it has not clipped yet would give the proportional
    polish that follows a ratio |P_t|/P_n far outside the cone: corpus 0-6's bed of 56
    contacts ran off to 1e300 and stopped the run)."""
    nbody = _bodies(nc, ca, cb)
    v0, w0 = v[:nbody].copy(), w[:nbody].copy()
    pn0, pt0, hr0 = pn[:nc].copy(), pt[:nc].copy(), hr[:nc].copy()
    worst = refine_normals(nc, ca, cb, cn, cvb, target, inv_m, v, pn, tol)
    for _ in range(POLISH_ROUNDS):
        if worst > tol or _clip_cones(nc, ca, cb, cn, crb, mu, mur, reff, inv_m, inv_i, rad, v,
                                      w, pn, pt, hr, rotation, friction, rolling) == 0.0:
            break
        worst = refine_normals(nc, ca, cb, cn, cvb, target, inv_m, v, pn, tol)
    if worst > tol:
        v[:nbody] = v0
        w[:nbody] = w0
        pn[:nc] = pn0
        pt[:nc] = pt0
        hr[:nc] = hr0
    return worst


#: Sweeps that a frictionless solve which may be finished directly (``polish_stall`` of
#: :func:`solve_polished`, the engine's steps) gets before it is [-]: without friction and
#: rolling couples the normal impulses are the whole problem, a convex one that the direct
#: finish (:func:`refined`) meets to ``tol``. Where Gauss–Seidel converges in fewer sweeps (most
#: clusters) nothing changes; where it converges slowly without stalling (a frictionless bed of
#: redundant contacts) it no longer runs on to its stall test's verdict or MAX_SWEEPS. On eight
#: steps of corpus 0-228's sliding bed (782 contacts) the solve took 3–56 ms after 128 sweeps,
#: against 4–62 ms when the sweeps ran to their stall (231–512 sweeps) and 3–82 ms after 256;
#: on two steps of 0-192's bed (1,036 and 1,041 contacts), whose sweeps stall at 1,024–2,048
#: and go to the same finish, 0.5–1.6 s against 1.5–3.1 s (docs/enduring-contact.md,
#: "Frictionless beds").
DIRECT_AFTER = STALL_SWEEPS


@njit(allocates=True)
def _frictionless_direct(nc, ca, cb, cn, crb, cvb, target, mu, slip, mur, reff, rslip, inv_m,
                         inv_i, rad, v, w, pn, pt, hr, rotation, tol):
    """The start of :func:`solve_polished` for a frictionless cluster with ``polish_stall``
    (the arguments as in :func:`solve`): DIRECT_AFTER sweeps, then, where they have not met
    ``tol``, the direct finish (:func:`refined`). Returns (sweeps, worst, met): where ``met``
    is False the finish did not meet ``tol`` either, and the caller's sweeps go on from
    there."""
    sweeps, worst, stalled = solve(nc, ca, cb, cn, crb, cvb, target, mu, slip, mur, reff, rslip,
                                   inv_m, inv_i, rad, v, w, pn, pt, hr, rotation, False, False,
                                   tol, DIRECT_AFTER, True)
    if sweeps < DIRECT_AFTER and not stalled:
        return sweeps, worst, True
    worst = refine_normals(nc, ca, cb, cn, cvb, target, inv_m, v, pn, tol)
    return sweeps, worst, worst <= tol


@njit(allocates=True)
def solve_polished(nc, ca, cb, cn, crb, cvb, target, mu, slip, mur, reff, rslip, inv_m, inv_i,
                   rad, v, w, pn, pt, hr, rotation, friction, rolling, tol,
                   friction_sweeps=FRICTION_SWEEPS, grow=False, polish_stall=False):
    """:func:`solve` (the same arguments and results) with friction and rolling couples given
    at most ``friction_sweeps`` sweeps; if they have not converged by then, the normal
    impulses are solved to ``tol`` with each tangential impulse held in proportion to its
    normal impulse and the rolling couples clipped (:func:`_polish`): the normal conditions
    (what keeps contacts from closing) are then met to ``tol`` and every impulse is within
    its cone; friction is Coulomb's, at the accuracy the tangential sweeps reached.

    With ``grow`` (the caller can solve a larger cluster instead, where the stall may come
    from what it holds immovable), a solve that stalls (:func:`solve`; with friction or
    without: bodies pressed head-on between immovable partners that close on each other
    have no solution either) stops there and returns ``stalled`` True, the impulses
    unfinished; without it, a friction solve's stall freezes the tangential impulses as the
    end of the friction sweeps does, and a frictionless solve runs to MAX_SWEEPS. With
    ``polish_stall`` the normal polish stops where it stalls too (a normal problem with no
    solution: targets that bodies held between immovable partners cannot all meet; or one on
    which Gauss–Seidel converges too slowly, a bed of redundant contacts) and is finished
    directly (:func:`refine_normals`, with the tangential impulses fixed, then the cones
    clipped and finished again), and a frictionless solve gets DIRECT_AFTER sweeps before it
    is (:func:`_frictionless_direct`); ``worst`` then says how far they are from it. With
    ``polish_stall`` frozen friction's normals are finished directly first
    (:func:`_finish_frozen`), and polished in proportion only where that does not meet
    ``tol``; the normals are then met to ``tol``, but a tangential impulse
    may end outside its cone by what the finish's last round changed its normal impulse (the
    rounds end with a finish, not a clip: on six steps of corpus 0-64's bed of ~700 contacts,
    0 to 17 contacts beyond 1.001 μ P_n, at most 1.064 μ P_n and 3.5e-11 N s, the next step's
    sweeps projecting them back; docs/enduring-contact.md, "Where a frozen step's time
    goes"). Returns (sweeps, worst, stalled) as :func:`solve`, and whether the tangential
    impulses were frozen before they converged (friction and rolling then hold only to the
    accuracy their sweeps reached)."""
    tangential = friction or rolling
    first = 0  # sweeps before the direct finish of a frictionless solve
    if not tangential and polish_stall and not grow:
        first, worst, met = _frictionless_direct(nc, ca, cb, cn, crb, cvb, target, mu, slip, mur,
                                                 reff, rslip, inv_m, inv_i, rad, v, w, pn, pt,
                                                 hr, rotation, tol)
        if met:
            return first, worst, False, False
    sweeps, worst, stalled = solve(nc, ca, cb, cn, crb, cvb, target, mu, slip, mur, reff, rslip,
                                   inv_m, inv_i, rad, v, w, pn, pt, hr, rotation, friction,
                                   rolling, tol,
                                   (friction_sweeps if tangential else MAX_SWEEPS) - first,
                                   tangential or grow or polish_stall)
    sweeps += first
    if stalled and grow:
        return sweeps, worst, True, False
    if not tangential or (sweeps < friction_sweeps and not stalled):
        if stalled and polish_stall and worst > tol:
            worst = refine_normals(nc, ca, cb, cn, cvb, target, inv_m, v, pn, tol)
        return sweeps, worst, stalled, False  # converged (or nothing tangential to freeze)
    if polish_stall:
        worst = _finish_frozen(nc, ca, cb, cn, crb, cvb, target, mu, mur, reff, inv_m, inv_i,
                               rad, v, w, pn, pt, hr, rotation, friction, rolling, tol)
        if worst <= tol:
            return sweeps, worst, False, True
    more, worst, stalled = _polish(nc, ca, cb, cn, crb, cvb, target, mu, slip, mur, reff, rslip,
                                   inv_m, inv_i, rad, v, w, pn, pt, hr, rotation, friction,
                                   rolling, tol, polish_stall)
    sweeps += more
    if stalled and polish_stall and worst > tol:
        # the normals with friction frozen: finished directly, then the cones clipped where
        # the new normal impulses no longer hold the frozen ones, and finished again
        worst = refine_normals(nc, ca, cb, cn, cvb, target, inv_m, v, pn, tol)
        if _clip_cones(nc, ca, cb, cn, crb, mu, mur, reff, inv_m, inv_i, rad, v, w, pn, pt, hr,
                       rotation, friction, rolling) > 0.0:
            worst = refine_normals(nc, ca, cb, cn, cvb, target, inv_m, v, pn, tol)
    return sweeps, worst, stalled and polish_stall, True
