"""A fixed-time-step soft-sphere integrator for many spheres: the DEM stand-in.

It runs an hsgran :class:`~hsgran.scene.Scene` the way a soft-sphere DEM code would, so that
hsgran's event-driven answer and its cost can be compared with fixed-step integration at the
DEM-customary fractions of the contact time (t_c/20, t_c/50):

* velocity Verlet (as LAMMPS' ``fix nve/sphere``): half kick, drift, forces from the new
  positions and half-step velocities, half kick;
* neighbours from a linked-cell grid rebuilt every step (cells at least one largest diameter
  wide, so only the 27 surrounding cells can hold a partner); periodic axes wrap;
* normal force: Hertz (MODEL §3.1, E* and R* from the pair row), plus the restitution dashpot
  of :func:`hsgran.dem.law.dashpot_force` when the pair prescribes e_n (the coefficient is
  calibrated so that one binary impact gives exactly that e_n), the total clamped at ≥ 0;
* tangential force (with ``friction``): history-free Coulomb, F_t = −min(μ F_n, (m_t*/τ) |u|) û
  (LAMMPS' ``tangential linear_nohistory`` form). τ = ``SLIP_TIME_FRACTION`` t_c is a short
  relaxation time, so a sticking contact stops slipping well within the contact, as the
  impulse model's rigid sticking assumes (MODEL §4.2);
* planes are walls with the same law (R* = R of the sphere).

Only what hsgran's scenes of the many-particle comparison need is supported: gravity, rotation,
friction, fixed restitution or elastic Hertz. The staged plastic law and adhesion need a
per-contact history (δ_max) and are only in the single-contact reference (:mod:`.single`);
rolling resistance is not modelled here. Such scenes are refused.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass

import numpy as np

from hsgran._jit import njit
from hsgran.contact.normal import hertz_contact_time
from hsgran.dem.single import dashpot_coefficient
from hsgran.errors import InputError
from hsgran.materials import P_E_FIXED, P_E_STAR, P_MU_S, SOLID_SPHERE_INERTIA

#: Slip relaxation time of the history-free friction as a fraction of the contact time t_c:
#: short enough that a sticking contact stops slipping within a tenth of the contact, long
#: enough that the explicit update stays stable (dt/τ = 0.5 at t_c/20; stability needs < 2).
SLIP_TIME_FRACTION = 0.1
#: Verlet-list skin as a fraction of the smallest radius: pairs closer than R_i + R_j + skin are
#: listed and the list is rebuilt once a sphere has moved half the skin. A larger skin means
#: fewer rebuilds but more listed pairs; a quarter radius is the usual compromise.
SKIN_FRACTION = 0.25


@njit
def _cell_index(x, lo, cs, ncell, periodic, box_len, k):
    """Cell coordinate of position ``x`` along axis ``k`` (clamped on non-periodic axes)."""
    c = math.floor((x - lo[k]) / cs[k])
    if periodic[k]:
        c %= ncell[k]
    elif c < 0:
        c = 0
    elif c >= ncell[k]:
        c = ncell[k] - 1
    return c


@njit
def _contact(i, j_or_wall, nx, ny, nz, d, vrel_x, vrel_y, vrel_z, r_eff, m_eff, m_t, e_star,
             mu, coef, inv_tau, friction, out):
    """Normal and tangential force on sphere i at one contact (out: F (3), torque arm factor).

    Args:
        nx, ny, nz: Unit normal from the partner to sphere i.
        d: Overlap [m].
        vrel_*: Relative contact-point velocity (i minus partner) [m/s].
        r_eff, m_eff, m_t: R* [m], m* [kg], m_t* [kg].
        e_star, mu, coef: E* [Pa], μ_s [-], dashpot coefficient [-].
        inv_tau: 1/τ of the history-free friction [1/s].
        friction: Tangential force on/off.
        out: (fx, fy, fz, ftx, fty, ftz) written: total force on i and its tangential part.
    """
    vn = vrel_x * nx + vrel_y * ny + vrel_z * nz
    sd = math.sqrt(d)
    fn = (4.0 / 3.0) * e_star * math.sqrt(r_eff) * d * sd  # MODEL §3.1
    if coef > 0.0:
        s_n = 2.0 * e_star * math.sqrt(r_eff) * sd
        fn += coef * math.sqrt(m_eff * s_n) * (-vn)
        if fn < 0.0:
            fn = 0.0
    ftx = fty = ftz = 0.0
    if friction:
        ux = vrel_x - vn * nx
        uy = vrel_y - vn * ny
        uz = vrel_z - vn * nz
        u = math.sqrt(ux * ux + uy * uy + uz * uz)
        if u > 0.0:
            ft = min(mu * fn, m_t * inv_tau * u)
            ftx = -ft * ux / u
            fty = -ft * uy / u
            ftz = -ft * uz / u
    out[0] = fn * nx + ftx
    out[1] = fn * ny + fty
    out[2] = fn * nz + ftz
    out[3] = ftx
    out[4] = fty
    out[5] = ftz
    return d / r_eff


@njit
def _build_neighbours(pos, radius, lo, box_len, periodic, cs, ncell, head, nxt, cell_of, skin,
                      nb_start, nb_list, pos_ref):
    """Verlet neighbour list: every pair j > i closer than R_i + R_j + skin, found through a
    linked-cell grid. Returns the number of entries, or −1 if ``nb_list`` is too short."""
    n = pos.shape[0]
    nc = ncell[0] * ncell[1] * ncell[2]
    for c in range(nc):
        head[c] = -1
    for i in range(n):
        cx = _cell_index(pos[i, 0], lo, cs, ncell, periodic, box_len, 0)
        cy = _cell_index(pos[i, 1], lo, cs, ncell, periodic, box_len, 1)
        cz = _cell_index(pos[i, 2], lo, cs, ncell, periodic, box_len, 2)
        cell_of[i, 0] = cx
        cell_of[i, 1] = cy
        cell_of[i, 2] = cz
        c = (cx * ncell[1] + cy) * ncell[2] + cz
        nxt[i] = head[c]
        head[c] = i
        for k in range(3):
            pos_ref[i, k] = pos[i, k]
    m = 0
    cap = nb_list.shape[0]
    for i in range(n):
        nb_start[i] = m
        for ox in range(-1, 2):
            cx = cell_of[i, 0] + ox
            if periodic[0]:
                cx %= ncell[0]
            elif cx < 0 or cx >= ncell[0]:
                continue
            for oy in range(-1, 2):
                cy = cell_of[i, 1] + oy
                if periodic[1]:
                    cy %= ncell[1]
                elif cy < 0 or cy >= ncell[1]:
                    continue
                for oz in range(-1, 2):
                    cz = cell_of[i, 2] + oz
                    if periodic[2]:
                        cz %= ncell[2]
                    elif cz < 0 or cz >= ncell[2]:
                        continue
                    j = head[(cx * ncell[1] + cy) * ncell[2] + cz]
                    while j >= 0:
                        if j > i:
                            dx = _wrap(pos[i, 0] - pos[j, 0], periodic[0], box_len[0])
                            dy = _wrap(pos[i, 1] - pos[j, 1], periodic[1], box_len[1])
                            dz = _wrap(pos[i, 2] - pos[j, 2], periodic[2], box_len[2])
                            cut = radius[i] + radius[j] + skin
                            if dx * dx + dy * dy + dz * dz < cut * cut:
                                if m >= cap:
                                    return -1
                                nb_list[m] = j
                                m += 1
                        j = nxt[j]
    nb_start[n] = m
    return m


@njit(inline="always")
def _wrap(dx, periodic, length):
    """Minimum-image difference along one axis."""
    if periodic:
        return dx - length * round(dx / length)
    return dx


@njit
def _forces(pos, vel, omg, force, torque, radius, mass, mat, e_star, mu, coef, inv_tau,
            planes_p, planes_n, planes_mat, gravity, box_len, periodic, nb_start, nb_list,
            rotation, friction, buf):
    """Forces and torques of every contact and gravity; returns the largest overlap / R*."""
    n = pos.shape[0]
    for i in range(n):
        for k in range(3):
            force[i, k] = mass[i] * gravity[k]
            torque[i, k] = 0.0
    worst = 0.0
    for i in range(n):
        ri = radius[i]
        for q in range(nb_start[i], nb_start[i + 1]):
            j = nb_list[q]
            dx = _wrap(pos[i, 0] - pos[j, 0], periodic[0], box_len[0])
            dy = _wrap(pos[i, 1] - pos[j, 1], periodic[1], box_len[1])
            dz = _wrap(pos[i, 2] - pos[j, 2], periodic[2], box_len[2])
            rj = radius[j]
            dist2 = dx * dx + dy * dy + dz * dz
            sig = ri + rj
            if dist2 < sig * sig:
                dist = math.sqrt(dist2)
                nx = dx / dist
                ny = dy / dist
                nz = dz / dist
                # ΔV = (V_i − V_j) − (R_i ω_i + R_j ω_j) × n (MODEL §2)
                sx = ri * omg[i, 0] + rj * omg[j, 0]
                sy = ri * omg[i, 1] + rj * omg[j, 1]
                sz = ri * omg[i, 2] + rj * omg[j, 2]
                vx = vel[i, 0] - vel[j, 0] - (sy * nz - sz * ny)
                vy = vel[i, 1] - vel[j, 1] - (sz * nx - sx * nz)
                vz = vel[i, 2] - vel[j, 2] - (sx * ny - sy * nx)
                r_eff = ri * rj / sig
                m_eff = mass[i] * mass[j] / (mass[i] + mass[j])
                m_t = m_eff / (1.0 + 1.0 / SOLID_SPHERE_INERTIA)
                mi = mat[i]
                mj = mat[j]
                ov = _contact(i, j, nx, ny, nz, sig - dist, vx, vy, vz, r_eff, m_eff, m_t,
                              e_star[mi, mj], mu[mi, mj], coef[mi, mj], inv_tau, friction, buf)
                worst = max(worst, ov)
                for k in range(3):
                    force[i, k] += buf[k]
                    force[j, k] -= buf[k]
                if rotation:
                    # torque −R n × F_t on both spheres
                    tx = ny * buf[5] - nz * buf[4]
                    ty = nz * buf[3] - nx * buf[5]
                    tz = nx * buf[4] - ny * buf[3]
                    torque[i, 0] -= ri * tx
                    torque[i, 1] -= ri * ty
                    torque[i, 2] -= ri * tz
                    torque[j, 0] -= rj * tx
                    torque[j, 1] -= rj * ty
                    torque[j, 2] -= rj * tz
        for w in range(planes_p.shape[0]):
            nx = planes_n[w, 0]
            ny = planes_n[w, 1]
            nz = planes_n[w, 2]
            gap = ((pos[i, 0] - planes_p[w, 0]) * nx + (pos[i, 1] - planes_p[w, 1]) * ny
                   + (pos[i, 2] - planes_p[w, 2]) * nz)
            if gap < ri:
                vx = vel[i, 0] - ri * (omg[i, 1] * nz - omg[i, 2] * ny)
                vy = vel[i, 1] - ri * (omg[i, 2] * nx - omg[i, 0] * nz)
                vz = vel[i, 2] - ri * (omg[i, 0] * ny - omg[i, 1] * nx)
                mi = mat[i]
                mw = planes_mat[w]
                ov = _contact(i, -1, nx, ny, nz, ri - gap, vx, vy, vz, ri, mass[i],
                              mass[i] / (1.0 + 1.0 / SOLID_SPHERE_INERTIA), e_star[mi, mw],
                              mu[mi, mw], coef[mi, mw], inv_tau, friction, buf)
                worst = max(worst, ov)
                for k in range(3):
                    force[i, k] += buf[k]
                if rotation:
                    torque[i, 0] -= ri * (ny * buf[5] - nz * buf[4])
                    torque[i, 1] -= ri * (nz * buf[3] - nx * buf[5])
                    torque[i, 2] -= ri * (nx * buf[4] - ny * buf[3])
    return worst


@njit
def _moved_too_far(pos, pos_ref, periodic, box_len, half_skin):
    """True when some sphere moved more than half the skin since the list was built."""
    lim = half_skin * half_skin
    for i in range(pos.shape[0]):
        dx = _wrap(pos[i, 0] - pos_ref[i, 0], periodic[0], box_len[0])
        dy = _wrap(pos[i, 1] - pos_ref[i, 1], periodic[1], box_len[1])
        dz = _wrap(pos[i, 2] - pos_ref[i, 2], periodic[2], box_len[2])
        if dx * dx + dy * dy + dz * dz > lim:
            return True
    return False


@njit
def _advance(pos, vel, omg, force, torque, radius, mass, inv_i, mat, e_star, mu, coef, inv_tau,
             planes_p, planes_n, planes_mat, gravity, lo, box_len, periodic, cs, ncell, head,
             nxt, cell_of, rotation, friction, buf, skin, nb_start, nb_list, pos_ref, stats,
             dt, n_steps):
    """``n_steps`` velocity-Verlet steps; ``force``/``torque`` hold the forces of the current
    positions on entry and on return. ``stats``: [largest overlap / R*, list builds]. Returns
    False if the neighbour list outgrew ``nb_list`` (the caller enlarges it and repeats)."""
    n = pos.shape[0]
    h = 0.5 * dt
    for _ in range(n_steps):
        for i in range(n):
            im = 1.0 / mass[i]
            for k in range(3):
                vel[i, k] += force[i, k] * im * h
                pos[i, k] += vel[i, k] * dt
                if periodic[k]:
                    if pos[i, k] < lo[k]:
                        pos[i, k] += box_len[k]
                    elif pos[i, k] >= lo[k] + box_len[k]:
                        pos[i, k] -= box_len[k]
            if rotation:
                for k in range(3):
                    omg[i, k] += torque[i, k] * inv_i[i] * h
        if _moved_too_far(pos, pos_ref, periodic, box_len, 0.5 * skin):
            if _build_neighbours(pos, radius, lo, box_len, periodic, cs, ncell, head, nxt,
                                 cell_of, skin, nb_start, nb_list, pos_ref) < 0:
                return False
            stats[1] += 1.0
        ov = _forces(pos, vel, omg, force, torque, radius, mass, mat, e_star, mu, coef, inv_tau,
                     planes_p, planes_n, planes_mat, gravity, box_len, periodic, nb_start,
                     nb_list, rotation, friction, buf)
        stats[0] = max(stats[0], ov)
        for i in range(n):
            im = 1.0 / mass[i]
            for k in range(3):
                vel[i, k] += force[i, k] * im * h
            if rotation:
                for k in range(3):
                    omg[i, k] += torque[i, k] * inv_i[i] * h
    return True


@dataclass
class FixedStepRun:
    """Result of :func:`run_fixed_step` (SI units).

    Attributes:
        time: Frame times [s] (F,).
        kinetic_translational, kinetic_rotational, potential: Energies at the frames [J] (F,).
        position, velocity: State at the last frame [m], [m/s] (N, 3).
        dt: Time step [s].
        contact_time: The contact duration t_c that dt is a fraction of [s].
        steps: Steps taken.
        cpu_time: CPU seconds of the integration (``time.process_time``; compile excluded).
        wall_time: Wall seconds of the integration.
        max_overlap: Largest overlap divided by R* seen [-].
        list_builds: Neighbour-list rebuilds.
    """

    time: np.ndarray
    kinetic_translational: np.ndarray
    kinetic_rotational: np.ndarray
    potential: np.ndarray
    position: np.ndarray
    velocity: np.ndarray
    dt: float
    contact_time: float
    steps: int
    cpu_time: float
    wall_time: float
    max_overlap: float
    list_builds: int


def scene_contact_time(scene, speed: float) -> float:
    """Shortest elastic Hertz contact duration t_c [s] of the scene's sphere–sphere and
    sphere–wall pairs at impact speed ``speed`` [m/s] (MODEL §3.1), smallest spheres.

    DEM practice sets dt as a fraction of t_c at the largest expected impact speed; the
    smallest sphere with the stiffest partner gives the shortest contact.
    """
    table = scene.pair_table()
    mats = sorted(set(int(m) for m in scene.material))
    masses = scene.mass()
    best = math.inf
    for m in mats:
        sel = scene.material == m
        r = float(scene.radius[sel].min())
        mass = float(masses[sel].min())
        best = min(best, float(hertz_contact_time(speed, 0.5 * mass, 0.5 * r,
                                                  table[m, m, P_E_STAR])))
        for p in scene.planes:
            best = min(best, float(hertz_contact_time(speed, mass, r,
                                                      table[m, p.material, P_E_STAR])))
    return best


def _check_scene(scene) -> None:
    eff = scene.effects
    table = scene.pair_table()
    used = sorted(set(int(m) for m in scene.material))
    fixed = all(table[m, k, P_E_FIXED] >= 0.0 for m in used
                for k in used + [p.material for p in scene.planes])
    if eff.plasticity and not fixed:
        raise InputError("the fixed-step integrator has no per-contact history: the staged "
                         "plastic law needs one (use a fixed restitution)", "effects")
    for name in ("adhesion", "rolling_resistance"):
        if getattr(eff, name):
            raise InputError(f"effect '{name}' is not modelled by the fixed-step integrator",
                             "effects")
    driven = [w.key for w in scene.walls if getattr(w, "motion", None) is not None
              or not hasattr(w, "normal") or hasattr(w, "kind")]
    if driven:
        raise InputError("the fixed-step integrator has fixed planes only (a moving plane, a "
                         "cylinder, a finite wall or a fixed sphere is not modelled)",
                         driven[0])


def run_fixed_step(scene, *, dt: float, until: float, frame_interval: float,
                   contact_time: float = math.nan) -> FixedStepRun:
    """Integrate a scene with fixed time steps (soft-sphere DEM) up to ``until``.

    Args:
        scene: An hsgran scene (same initial state as ``Simulation(scene)``).
        dt: Time step [s].
        until: End time [s].
        frame_interval: Energies are sampled at multiples of this [s] (rounded to whole steps).
        contact_time: The t_c that ``dt`` was derived from, recorded in the result [s]; it also
            sets the friction relaxation time τ (default: dt × 20).

    Returns:
        :class:`FixedStepRun`.

    Raises:
        InputError: the scene needs physics this integrator does not have.
    """
    _check_scene(scene)
    eff = scene.effects
    t_c = contact_time if math.isfinite(contact_time) else 20.0 * dt
    table = scene.pair_table()
    e_star = np.ascontiguousarray(np.nan_to_num(table[:, :, P_E_STAR]))
    mu = np.ascontiguousarray(np.nan_to_num(table[:, :, P_MU_S]))
    coef = np.zeros_like(e_star)
    for a in range(table.shape[0]):
        for b in range(table.shape[1]):
            e = table[a, b, P_E_FIXED]
            if math.isfinite(e) and e >= 0.0:
                coef[a, b] = dashpot_coefficient(float(e))
    pos = np.ascontiguousarray(scene.position, dtype=np.float64).copy()
    vel = np.ascontiguousarray(scene.velocity, dtype=np.float64).copy()
    omg = np.ascontiguousarray(scene.angular_velocity, dtype=np.float64).copy()
    radius = np.ascontiguousarray(scene.radius, dtype=np.float64)
    mass = np.ascontiguousarray(scene.mass(), dtype=np.float64)
    inv_i = 1.0 / (SOLID_SPHERE_INERTIA * mass * radius**2)
    mat = np.ascontiguousarray(scene.material, dtype=np.int64)
    planes = list(scene.planes)
    planes_p = np.array([p.point for p in planes], dtype=np.float64).reshape(-1, 3)
    planes_n = np.array([p.normal for p in planes], dtype=np.float64).reshape(-1, 3)
    planes_mat = np.array([p.material for p in planes], dtype=np.int64)
    gravity = np.ascontiguousarray(scene.gravity, dtype=np.float64)
    periodic = np.array(scene.periodic, dtype=np.bool_)
    if scene.box_lower is not None:
        lo = np.asarray(scene.box_lower, dtype=np.float64).copy()
        hi = np.asarray(scene.box_upper, dtype=np.float64).copy()
    else:
        lo = (pos - radius[:, None]).min(axis=0)
        hi = (pos + radius[:, None]).max(axis=0)
    box_len = hi - lo
    skin = SKIN_FRACTION * float(radius.min())
    # a cell at least one listing cut-off wide, so every listed partner is in the 27 cells around
    ncell = np.maximum(1, np.floor(box_len / (2.0 * radius.max() + skin)).astype(np.int64))
    if np.any(periodic & (ncell < 3)):
        raise InputError("a periodic axis needs at least 3 cells of one largest diameter", "box")
    cs = box_len / ncell
    head = np.full(int(np.prod(ncell)), -1, dtype=np.int64)
    nxt = np.full(len(pos), -1, dtype=np.int64)
    cell_of = np.zeros((len(pos), 3), dtype=np.int64)
    force = np.zeros_like(pos)
    torque = np.zeros_like(pos)
    buf = np.zeros(6)
    inv_tau = 1.0 / (SLIP_TIME_FRACTION * t_c)
    rotation, friction = bool(eff.rotation), bool(eff.rotation and eff.friction)
    inertia = SOLID_SPHERE_INERTIA * mass * radius**2

    def sample():
        kt = 0.5 * float(np.sum(mass[:, None] * vel * vel))
        kr = 0.5 * float(np.sum(inertia[:, None] * omg * omg))
        return kt, kr, -float(np.sum(mass[:, None] * pos * gravity[None, :]))

    # a packing bound on the partners within reach: the list can never overflow
    reach = 2.0 * float(radius.max()) + skin + float(radius.min())
    capacity = len(pos) * max(1, math.ceil((reach / float(radius.min())) ** 3))
    nb_start = np.zeros(len(pos) + 1, dtype=np.int64)
    nb_list = np.zeros(capacity, dtype=np.int64)
    pos_ref = np.zeros_like(pos)
    stats = np.zeros(2)
    common = (radius, mass, inv_i, mat, e_star, mu, coef, inv_tau, planes_p, planes_n,
              planes_mat, gravity, lo, box_len, periodic, cs, ncell, head, nxt, cell_of,
              rotation, friction, buf, skin, nb_start, nb_list, pos_ref, stats)
    # neighbours and forces at t = 0, then a one-step call on copies that compiles (or loads)
    # the kernel untimed
    _build_neighbours(pos, radius, lo, box_len, periodic, cs, ncell, head, nxt, cell_of, skin,
                      nb_start, nb_list, pos_ref)
    _forces(pos, vel, omg, force, torque, radius, mass, mat, e_star, mu, coef, inv_tau, planes_p,
            planes_n, planes_mat, gravity, box_len, periodic, nb_start, nb_list, rotation,
            friction, buf)
    saved = (pos_ref.copy(), nb_start.copy(), nb_list.copy())
    _advance(pos.copy(), vel.copy(), omg.copy(), force.copy(), torque.copy(), *common, dt, 1)
    pos_ref[:], nb_start[:], nb_list[:] = saved
    stats[:] = 0.0
    per_frame = max(1, round(frame_interval / dt))
    total = math.ceil(until / dt - 1e-9)
    times, kts, krs, pes = [0.0], *([v] for v in sample())
    steps = 0
    cpu0, wall0 = time.process_time(), time.perf_counter()
    while steps < total:
        k = min(per_frame, total - steps)
        if not _advance(pos, vel, omg, force, torque, *common, dt, k):
            raise RuntimeError("neighbour list overflow: the packing bound is wrong")
        steps += k
        kt, kr, pe = sample()
        times.append(steps * dt)
        kts.append(kt)
        krs.append(kr)
        pes.append(pe)
    cpu, wall = time.process_time() - cpu0, time.perf_counter() - wall0
    return FixedStepRun(np.array(times), np.array(kts), np.array(krs), np.array(pes), pos, vel,
                        dt, t_c, steps, cpu, wall, float(stats[0]),
                        int(stats[1]))
