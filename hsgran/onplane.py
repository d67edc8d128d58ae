"""A sphere in enduring contact with a plane under gravity: sliding, rolling, rest (layer 2).

MODEL §5.3 gives the closed form on a horizontal plate: sliding under Coulomb friction until
the slip vanishes (the instant C), then rolling against rolling friction until rest (C′). Here
the same rigid-body equations are written for a plane of any tilt, in 3-D vector form, as
*segments* of constant linear acceleration ``a`` and angular acceleration ``α``: within a segment
the centre follows x0 + v0 τ + ½ a τ² and the spin ω0 + α τ, exactly, so the event loop treats
an on-plane sphere like a flying one with another acceleration. A segment ends at a scheduled
transition (its ``code``):

- ``END_SLIP``: the slip along the segment's slip direction vanishes (C): the sphere rolls on;
- ``END_SPIN``: the rolling part of the spin passes through zero while sliding (convention A
  with backspin: the rolling torque turns round, MODEL §5.3);
- ``END_STOP``: the velocity along the rolling direction reaches zero (C′): rest, or rolling
  back down an incline steeper than the rolling friction holds.

Symbols (SI): n unit plane normal (towards the sphere), g gravity [m/s²], g_n = −g·n > 0 the
normal load per unit mass, g_t = g + g_n n its tangential part, R radius [m], k = I/(mR²) = 2/5,
μ_s sliding friction, μ_r rolling friction (torque μ_r R F_n, §5.1), slip u = v − R ω × n.

- sliding (u ≠ 0, û = u/|u|): a = g_t − μ_s g_n û, α = [μ_s g_n (n × û) − χ μ_r g_n n_ω]/(k R)
  with n_ω the direction of the rolling spin ω − (ω·n)n, χ = 1 under convention A (rolling
  torque also while sliding) and 0 under B [MODEL §5.3; which one the paper used is OURS];
- rolling (u = 0, v̂ = v/|v|): a = [g_t − μ_r g_n v̂]/(1 + k), α = n × a / R; it needs the friction
  force |a − g_t| ≤ μ_s g_n, else the sphere slides (on an incline: tan θ ≤ (1 + k)/k μ_s);
- rest (v = 0, ω = 0): kept while |g_t| ≤ μ_r g_n (the rolling torque holds the sphere) and
  |g_t| ≤ μ_s g_n (friction holds the contact point); else it starts rolling down the fall
  line, or sliding if friction cannot hold it (only possible with μ_r > μ_s).

Exactness [OURS]: the directions (û, n_ω, v̂) are frozen within a segment. When slip, spin and
velocity stay on one line — the paper's sphere on a plate, with any backspin or topspin, and
motion along the fall line of an incline — that is exact, and a trajectory is the closed form
to rounding. Off that line (a sphere launched across an incline, or with a sideways spin) the
directions turn continuously in reality and are updated only at the segment ends here; each
segment still ends when its slip or speed has run out, so the state machine always progresses.
"""

from __future__ import annotations

import math

from hsgran._jit import njit

MS_FLIGHT = 0  #: free flight (parabola under gravity)
MS_SLIDING = 1  #: on a plane, slipping at the contact point
MS_ROLLING = 2  #: on a plane, rolling without slip
MS_REST = 3  #: on a plane, at rest
#: Output only (trajectory frames): at rest on another sphere. The engine keeps such a sphere as
#: ``MS_REST`` with its support sphere in place of a plane.
MS_ASLEEP = 4
#: Moving with the constant accelerations a cluster of resting contacts gives it (hsgran._cluster):
#: sliding or rolling on spheres or on several walls at once.
MS_SUPPORTED = 5
MOTION_STATE_NAMES = ("flight", "sliding", "rolling", "rest", "asleep", "supported")
#: Output only (trajectory frames): the sphere has left the system through an outlet
#: (docs/open-systems.md); not an index of MOTION_STATE_NAMES.
MS_ABSENT = -1

END_NONE = 0  #: the segment lasts until something hits the sphere
END_SLIP = 1  #: the slip vanishes (C): snap to rolling
END_SPIN = 2  #: the rolling spin passes through zero (convention A, backspin)
END_STOP = 3  #: the speed along the rolling direction vanishes (C′)
#: the contacts of a cluster are solved again (hsgran._cluster): the segment's constant
#: accelerations have lasted as long as they may, or a support moved
END_RESOLVE = 4

CONVENTION_A = 1.0  #: χ = 1: rolling torque acts while sliding as well
CONVENTION_B = 0.0  #: χ = 0: rolling torque acts only while rolling

#: A slip below this fraction of the surface speed scale |v| + R|ω| (+ g_n × 1 s for a sphere at
#: rest) is rolling: 1e-12 is ~1e4 ulp, above the round-off of a transition computed from the
#: closed form, and far below any slip that matters (a 1 m/s sphere slips 1 pm/s).
ROLL_SLIP_REL = 1e-12
#: A rolling sphere slower than the load g_n gives in this time [s] is at rest (and starts
#: down the fall line where the slope is steeper than rolling friction holds): 1e-11 m/s on a
#: level plane, far below any speed that matters (a settled pile's 1e-6 m/s) and far above
#: the round-off a stop leaves across the rolling direction (~1e-16 of the speed before it),
#: which otherwise ends each following segment at the same instant (:func:`plane_segment`).
ROLL_REST_TIME = 1e-12

NEVER = math.inf


@njit(inline="always")
def load_and_pull(nx, ny, nz, g):
    """(g_n, g_t): gravity's load −g·n [m/s²] on a plane of unit normal n (pointing to the
    sphere) and its pull along the plane, g_t = g + g_n n (MODEL §5.3)."""
    gn = -(g[0] * nx + g[1] * ny + g[2] * nz)
    return gn, g[0] + gn * nx, g[1] + gn * ny, g[2] + gn * nz


@njit(inline="always")
def holds_still(gts, gn, mu_s, mu_r):
    """Whether a plane holds a sphere at rest against the pull |g_t| = ``gts`` along it under
    the load ``gn`` [m/s²] (MODEL §5.3): the rolling torque against the slope and friction at
    the contact point, |g_t| ≤ min(μ_r, μ_s) g_n; frictionless, only a level plane."""
    if mu_s <= 0.0:
        return gts == 0.0
    return gts <= min(mu_r, mu_s) * gn


@njit(inline="always")
def _cross(ax, ay, az, bx, by, bz):
    return ay * bz - az * by, az * bx - ax * bz, ax * by - ay * bx


@njit
def plane_segment(v, w, n, g, radius, inertia, mu_s, mu_r, chi, snap, sdir, speed_floor=0.0):
    """The motion segment of a sphere on a plane from its current state.

    Args:
        v: Velocity [m/s] (3,), in the plane (modified in place when snapped).
        w: Angular velocity [rad/s] (3,) (modified in place when snapped).
        n: Unit plane normal (3,), pointing to the sphere; −g·n must be > 0.
        g: Gravity [m/s²] (3,).
        radius: R [m].
        inertia: k = I/(m R²) [-] (2/5 for a solid sphere).
        mu_s: Sliding friction μ_s [-] (0 without the friction effect).
        mu_r: Rolling friction μ_r [-] (0 without rolling resistance).
        chi: Rolling-torque convention while sliding (:data:`CONVENTION_A` or ``_B``).
        snap: The transition that just ended the previous segment (``END_*``): its quantity is
            set to exactly zero first, so the closed form is followed without drift.
        sdir: (3,) direction of the previous segment (for ``snap``); receives the new one.
        speed_floor: Added to the speed scale of the rolling test [m/s]: velocities relative to
            a moving surface carry the rounding of the surface's speed (hsgran._cylinder).

    Returns:
        (state, ax, ay, az, alx, aly, alz, duration [s], end code).

    References:
        MODEL §5.1, §5.3.
    """
    nx, ny, nz = n[0], n[1], n[2]
    gn, gtx, gty, gtz = load_and_pull(nx, ny, nz, g)
    k = inertia
    if snap == END_SLIP:
        # rolling from now on: ω's rolling part follows v exactly (keep the spin about n)
        wn = w[0] * nx + w[1] * ny + w[2] * nz
        cx, cy, cz = _cross(nx, ny, nz, v[0], v[1], v[2])
        w[0] = wn * nx + cx / radius
        w[1] = wn * ny + cy / radius
        w[2] = wn * nz + cz / radius
    elif snap == END_SPIN:
        d = w[0] * sdir[0] + w[1] * sdir[1] + w[2] * sdir[2]
        w[0] -= d * sdir[0]
        w[1] -= d * sdir[1]
        w[2] -= d * sdir[2]
    elif snap == END_STOP:
        d = v[0] * sdir[0] + v[1] * sdir[1] + v[2] * sdir[2]
        v[0] -= d * sdir[0]
        v[1] -= d * sdir[1]
        v[2] -= d * sdir[2]
        wn = w[0] * nx + w[1] * ny + w[2] * nz
        cx, cy, cz = _cross(nx, ny, nz, v[0], v[1], v[2])
        w[0] = wn * nx + cx / radius
        w[1] = wn * ny + cy / radius
        w[2] = wn * nz + cz / radius
    # slip u = v − R ω × n
    cx, cy, cz = _cross(w[0], w[1], w[2], nx, ny, nz)
    ux = v[0] - radius * cx
    uy = v[1] - radius * cy
    uz = v[2] - radius * cz
    us = math.sqrt(ux * ux + uy * uy + uz * uz)
    vs = math.sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2])
    ws = math.sqrt(w[0] * w[0] + w[1] * w[1] + w[2] * w[2])
    scale = vs + radius * ws + speed_floor
    if mu_s <= 0.0:
        # frictionless: the sphere glides under the tangential pull, its spin unchanged
        if vs == 0.0 and gtx == 0.0 and gty == 0.0 and gtz == 0.0:
            return MS_REST, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, NEVER, END_NONE
        return MS_SLIDING, gtx, gty, gtz, 0.0, 0.0, 0.0, NEVER, END_NONE

    if us > ROLL_SLIP_REL * scale:
        return _sliding(v, w, nx, ny, nz, gn, gtx, gty, gtz, ux / us, uy / us, uz / us, us,
                        vs, ws, radius, k, mu_s, mu_r, chi, sdir)

    # rolling (or at rest): make the no-slip condition exact
    wn = w[0] * nx + w[1] * ny + w[2] * nz
    cx, cy, cz = _cross(nx, ny, nz, v[0], v[1], v[2])
    w[0] = wn * nx + cx / radius
    w[1] = wn * ny + cy / radius
    w[2] = wn * nz + cz / radius
    gts = math.sqrt(gtx * gtx + gty * gty + gtz * gtz)
    if vs <= ROLL_REST_TIME * gn:
        # a rolling speed the load would give in ROLL_REST_TIME is none: the round-off a stop
        # (END_STOP) leaves across the rolling direction, which, taken as a direction, ends
        # the next segment 1e-34 s later with a smaller residue, and so on down to underflow
        # (a corpus sphere rolling into the corner of an incline and a wall: ~250 stops at
        # one instant after each of its bounces, 51 million in 1.1 s). [OURS] (Also the
        # exact zero state of a sphere at rest, v = 0 and ω about n only.)
        v[0] = 0.0
        v[1] = 0.0
        v[2] = 0.0
        w[0] = wn * nx
        w[1] = wn * ny
        w[2] = wn * nz
        vs = 0.0
    if vs > 0.0:
        dx, dy, dz = v[0] / vs, v[1] / vs, v[2] / vs
    else:
        if holds_still(gts, gn, mu_s, mu_r):
            # at rest: the rolling torque holds the sphere against the slope, and friction the
            # contact point (in the exact zero state set above)
            return MS_REST, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, NEVER, END_NONE
        dx, dy, dz = gtx / gts, gty / gts, gtz / gts  # starts rolling down the fall line
    c = 1.0 / (1.0 + k)
    ax = c * (gtx - mu_r * gn * dx)
    ay = c * (gty - mu_r * gn * dy)
    az = c * (gtz - mu_r * gn * dz)
    fx = ax - gtx
    fy = ay - gty
    fz = az - gtz
    fs = math.sqrt(fx * fx + fy * fy + fz * fz)
    if fs > mu_s * gn:
        # friction cannot keep it rolling: it slips in the direction opposite to the friction
        # it would need (ω was made rolling above: its size is taken again)
        ws = math.sqrt(w[0] * w[0] + w[1] * w[1] + w[2] * w[2])
        return _sliding(v, w, nx, ny, nz, gn, gtx, gty, gtz, -fx / fs, -fy / fs, -fz / fs, 0.0,
                        vs, ws, radius, k, mu_s, mu_r, chi, sdir)
    alx, aly, alz = _cross(nx, ny, nz, ax, ay, az)
    along = ax * dx + ay * dy + az * dz
    sdir[0] = dx
    sdir[1] = dy
    sdir[2] = dz
    duration = vs / -along if (along < 0.0 and vs > 0.0) else NEVER
    return (MS_ROLLING, ax, ay, az, alx / radius, aly / radius, alz / radius, duration,
            END_STOP if duration < NEVER else END_NONE)


@njit
def _sliding(v, w, nx, ny, nz, gn, gtx, gty, gtz, ex, ey, ez, us, vs, ws, radius, k, mu_s, mu_r,
             chi, sdir):
    """Sliding segment with slip direction e = û and slip speed ``us`` [m/s]; ``vs`` = |v| [m/s]
    and ``ws`` = |ω| [rad/s] are the caller's."""
    ax = gtx - mu_s * gn * ex
    ay = gty - mu_s * gn * ey
    az = gtz - mu_s * gn * ez
    # friction torque (−R n) × (−μ_s m g_n û) / I = μ_s g_n (n × û) / (k R)
    fx, fy, fz = _cross(nx, ny, nz, ex, ey, ez)
    q = gn / (k * radius)
    alx = mu_s * q * fx
    aly = mu_s * q * fy
    alz = mu_s * q * fz
    # rolling spin: ω − (ω·n) n
    wn = w[0] * nx + w[1] * ny + w[2] * nz
    rx = w[0] - wn * nx
    ry = w[1] - wn * ny
    rz = w[2] - wn * nz
    rs = math.sqrt(rx * rx + ry * ry + rz * rz)
    t_spin = NEVER
    ox = oy = oz = 0.0
    if chi > 0.0 and mu_r > 0.0:
        # the rolling spin is measured against the whole spin: ω − (ω·n) n carries the rounding
        # of |ω|, the spin about n included, and its direction, divided by a rolling spin near
        # that rounding, leaves the plane by as much; snapped along such a direction
        # (END_SPIN), a spin about n of 1.4e-9 rad/s left a rolling spin of 4e-18 rad/s, whose
        # end came 3e-20 s later, for ever (a corpus polygon at 0.1996 s). So the direction is
        # put back in the plane, and a rolling spin within ROLL_SLIP_REL of |v|/R + |ω| is
        # none. [OURS]
        if rs > ROLL_SLIP_REL * (vs / radius + ws):
            ox, oy, oz = rx / rs, ry / rs, rz / rs
            on = ox * nx + oy * ny + oz * nz
            ox, oy, oz = ox - on * nx, oy - on * ny, oz - on * nz
            os = math.sqrt(ox * ox + oy * oy + oz * oz)
            ox, oy, oz = ox / os, oy / os, oz / os
            mr = mu_r
        else:
            ox, oy, oz = fx, fy, fz  # no rolling spin yet: it will grow along the friction torque
            # a resisting couple can stop the spin from growing, not turn it backwards: at
            # most the friction torque (matters only with μ_r > μ_s) [OURS]
            mr = min(mu_r, mu_s)
        alx -= chi * mr * q * ox
        aly -= chi * mr * q * oy
        alz -= chi * mr * q * oz
        spin_rate = alx * ox + aly * oy + alz * oz
        if rs > 0.0 and spin_rate < 0.0 and (rx * ox + ry * oy + rz * oz) > 0.0:
            t_spin = rs / -spin_rate
    # du/dt = a − R α × n, followed along û
    cx, cy, cz = _cross(alx, aly, alz, nx, ny, nz)
    slip_rate = (ax - radius * cx) * ex + (ay - radius * cy) * ey + (az - radius * cz) * ez
    # (a slip starting from zero because friction cannot keep the sphere rolling grows: a
    # rate below zero then is the rounding of a pull at the limit of friction, and ending the
    # segment at once would snap it to rolling and back here at the same instant, for ever)
    t_slip = us / -slip_rate if slip_rate < 0.0 and us > 0.0 else NEVER
    if t_spin < t_slip:
        sdir[0] = ox
        sdir[1] = oy
        sdir[2] = oz
        return MS_SLIDING, ax, ay, az, alx, aly, alz, t_spin, END_SPIN
    sdir[0] = ex
    sdir[1] = ey
    sdir[2] = ez
    return (MS_SLIDING, ax, ay, az, alx, aly, alz, t_slip,
            END_SLIP if t_slip < NEVER else END_NONE)
