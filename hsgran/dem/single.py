"""One sphere–wall impact integrated through the contact with a fixed time step (soft sphere).

This is the time-resolved reference of the impulse model: the same contact law
(:mod:`hsgran.dem.law`, built on MODEL §3–§5 and the pair row of
:func:`hsgran.materials.pair_row`) advanced by velocity Verlet, the scheme of LAMMPS' and
LIGGGHTS' granular integrators: half kick, drift, forces from the new overlap and the
half-step velocities, half kick. The contact starts with the surfaces touching and ends when
the force has vanished with the surfaces separating (δ ≤ δ_res after the peak).

Frame (as :func:`hsgran.impact.oblique_velocity`): wall normal +z, the sphere moves towards +x,
the spin ω about +y is positive in the forward-rolling sense, contact-point slip u = v_t − R ω.

Where the impulse model claims equivalence (MODEL §3.5–3.9: the normal law integrated in
energy; §4.2: rigid-body friction), the outcomes here converge to it as dt → 0 at the order of
the scheme; where it does not (a tangential spring, a restitution dashpot), they are DEM
practice and the differences are findings of docs/accuracy-cost.md.
"""

from __future__ import annotations

import functools
import math
import time
from dataclasses import dataclass

import numpy as np

from hsgran._jit import njit
from hsgran.contact.adhesion import line_force
from hsgran.contact.normal import hertz_contact_time
from hsgran.dem.law import (
    adhesion_force,
    coulomb_force,
    dashpot_force,
    kuwabara_kono_force,
    loading_force,
    mindlin_force,
    rolling_torque,
    unloading_curve,
    unloading_force,
)
from hsgran.effects import Effects
from hsgran.errors import InputError, check_positive
from hsgran.materials import (
    P_E_STAR,
    P_MU_R,
    P_MU_S,
    P_VISC,
    SOLID_SPHERE_INERTIA,
    Contact,
    Material,
    effective_shear_modulus,
    pair_row,
    solid_sphere_mass,
)

TANGENTIAL_COULOMB = 0  #: Coulomb friction with rigid sticking (the impulse model's assumption)
TANGENTIAL_MINDLIN = 1  #: Mindlin spring k_t = 8 G* a with a Coulomb cap (DEM practice)
TANGENTIAL_MODELS = {"coulomb": TANGENTIAL_COULOMB, "mindlin": TANGENTIAL_MINDLIN}

#: Default time steps per contact duration: t_c/100 is finer than the DEM custom (t_c/20–t_c/50)
#: and gives e_n to ~1e-4 (second order, see tests/dem).
DEFAULT_STEPS_PER_CONTACT = 100.0
#: Steps allowed per contact as a multiple of the nominal count: a plastic or damped contact
#: lasts longer than the elastic Hertz t_c that sets dt, but not 50 times longer.
MAX_STEPS_FACTOR = 50
#: Time steps per contact of the integration that calibrates the dashpot: its e_n error is then
#: ~1e-6, far below the printed digits of any prescribed restitution.
CALIBRATION_STEPS = 2000.0
#: Bisection tolerance on the dashpot coefficient [-].
CALIBRATION_TOL = 1e-9
#: Upper bracket of the dashpot coefficient: gives e_n ≈ 0.003, below any restitution used.
CALIBRATION_MAX_COEF = 10.0

# indices of the output array of the compiled kernel
O_VN = 0  #: normal velocity after (positive = rebounding) [m/s]
O_VT = 1  #: tangential centre velocity after [m/s]
O_W = 2  #: spin about +y after [rad/s]
O_STEPS = 3  #: time steps taken [-]
O_T_CONTACT = 4  #: contact duration (first to last step with a force) [s]
O_D_MAX = 5  #: maximum overlap [m]
O_CAPTURED = 6  #: 1 if the sphere was captured (adhesion) [-]
O_D_RES = 7  #: residual plastic deformation [m]
O_F_MAX = 8  #: peak normal force [N]
O_SIZE = 9


@njit
def _impact(v0, vt0, w0, radius, mass, inertia, r_eff, row, f0, g_star, coef, visc, dt, plasticity,
            adhesion, friction, rolling, tangential, max_steps, out):
    """Velocity-Verlet integration of one sphere–wall contact (see module notes).

    Args:
        v0: Normal approach speed (> 0) [m/s].
        vt0, w0: Tangential centre velocity [m/s] and spin about +y [rad/s] before.
        radius, mass, inertia: Sphere R [m], m [kg], I [kg m²].
        r_eff: R* [m] (the sphere radius for a flat wall).
        row: Pair row.
        f0: Adhesion line force [N/m] (used only with ``adhesion``).
        g_star: Effective shear modulus G* [Pa] (Mindlin only).
        coef: Dashpot coefficient (0: none).
        visc: Dissipative constant A [s] of the viscoelastic (Kuwabara–Kono) force (0: none).
        dt: Time step [s].
        plasticity, adhesion, friction, rolling: Effect flags.
        tangential: ``TANGENTIAL_*`` code.
        max_steps: Step limit.
        out: Output array of size ``O_SIZE`` (written).
    """
    e_star = row[P_E_STAR]
    mu = row[P_MU_S]
    mu_r = row[P_MU_R]
    m_t = 1.0 / (1.0 / mass + radius * radius / inertia)
    d = 0.0
    dd = v0  # dδ/dt, approach rate
    vt = vt0
    w = w0
    xi = 0.0
    fn = 0.0
    ft = 0.0
    tq = 0.0
    d_max = 0.0
    f_max = 0.0
    unloading = False
    r_p = r_eff
    d_res = 0.0
    captured = False
    t_last = 0.0
    steps = 0
    h = 0.5 * dt
    while steps < max_steps:
        # half kick with the forces of the previous step
        dd -= fn / mass * h
        vt += ft / mass * h
        w += (-radius * ft + tq) / inertia * h
        # drift
        d += dd * dt
        steps += 1
        # forces at the new overlap, half-step velocities
        if not unloading:
            if d >= d_max:
                d_max = d
            else:
                unloading = True
                r_p, d_res = unloading_curve(d_max, r_eff, row, plasticity)
        if unloading and dd > 0.0 and d > d_res:
            # approaching again during recovery: adhesion has won (MODEL §3.8 capture)
            captured = True
            break
        a = 0.0
        if unloading:
            fel, a = unloading_force(d, r_p, d_res, e_star)
            if adhesion and a > 0.0:
                fel -= adhesion_force(a, f0)
        else:
            fel = loading_force(d, r_eff, row, plasticity)
            if d > 0.0:
                a = math.sqrt(r_eff * d)
        if coef > 0.0 or visc > 0.0:
            if coef > 0.0:
                fel += dashpot_force(dd, d, r_eff, mass, e_star, coef)
            if visc > 0.0:
                fel += kuwabara_kono_force(dd, d, r_eff, e_star, visc)
            if fel < 0.0:
                fel = 0.0  # a dashpot may not pull the surfaces together
        fn = fel
        if fn > f_max:
            f_max = fn
        fc = fn if fn > 0.0 else 0.0  # Coulomb and rolling limits use the compressive part
        ft = 0.0
        tq = 0.0
        if a > 0.0:
            t_last = steps * dt
            if friction:
                slip = vt - radius * w
                if tangential == TANGENTIAL_MINDLIN:
                    xi += slip * dt
                    ft, xi = mindlin_force(xi, 8.0 * g_star * a, mu, fc)
                else:
                    ft = coulomb_force(slip, m_t, mu, fc, dt)
            if rolling:
                tq = rolling_torque(w, inertia, mu_r, r_eff, fc, dt)
        else:
            xi = 0.0
        # half kick with the new forces
        dd -= fn / mass * h
        vt += ft / mass * h
        w += (-radius * ft + tq) / inertia * h
        if unloading and d <= d_res and dd < 0.0:
            break
    out[O_VN] = 0.0 if captured else -dd
    out[O_VT] = vt
    out[O_W] = w
    out[O_STEPS] = steps
    out[O_T_CONTACT] = t_last
    out[O_D_MAX] = d_max
    out[O_CAPTURED] = 1.0 if captured else 0.0
    out[O_D_RES] = d_res
    out[O_F_MAX] = f_max


@njit
def _impact_batch(v0, vt0, w0, radius, mass, inertia, r_eff, row, f0, g_star, coef, visc, dt,
                  plasticity, adhesion, friction, rolling, tangential, max_steps, out):
    """:func:`_impact` over arrays of initial states (v0, vt0, w0, dt, max_steps: shape (K,);
    out: (K, O_SIZE)); one compiled call, so the cost per impact can be timed."""
    for k in range(v0.shape[0]):
        _impact(v0[k], vt0[k], w0[k], radius, mass, inertia, r_eff, row, f0, g_star, coef, visc,
                dt[k], plasticity, adhesion, friction, rolling, tangential, max_steps[k], out[k])


@dataclass(frozen=True)
class ResolvedImpact:
    """Outcome of one time-resolved sphere–wall impact (SI units; angles in degrees)."""

    e_n: float  #: normal restitution v_n′/v_n [-]
    e_t: float  #: tangential restitution of the centre v_t′/v_t (NaN without v_t) [-]
    velocity_after: np.ndarray  #: centre velocity after, wall frame of oblique_velocity [m/s]
    spin_after: float  #: spin about +y after [rad/s]
    rebound_angle: float  #: centre rebound angle from the normal [deg]
    captured: bool  #: adhesion held the sphere
    contact_time: float  #: duration of the force [s]
    delta_max: float  #: maximum overlap [m]
    residual_deformation: float  #: δ_res [m]
    force_max: float  #: peak normal force [N]
    energy_lost: float  #: kinetic energy lost (translation + rotation) [J]
    steps: int  #: time steps taken [-]
    dt: float  #: time step [s]
    hertz_time: float  #: elastic Hertz duration at this speed, the unit of dt [s]


class _Setup:
    """The numbers one impact (or a batch of them) needs, checked once."""

    def __init__(self, sphere, wall, radius, contact, effects, tangential):
        if sphere.rigid or not math.isfinite(sphere.density):
            raise InputError(f"material '{sphere.name}' is rigid: it can be a wall, not a sphere",
                             "sphere")
        if tangential not in TANGENTIAL_MODELS:
            raise InputError(f"must be one of {', '.join(TANGENTIAL_MODELS)}, got "
                             f"{tangential!r}", "tangential")
        self.effects = Effects.all() if effects is None else effects
        self.contact = Contact() if contact is None else contact
        self.radius = check_positive(radius, "radius")
        self.mass = solid_sphere_mass(sphere.density, self.radius)
        self.inertia = SOLID_SPHERE_INERTIA * self.mass * self.radius**2
        self.row = pair_row(sphere, wall, self.contact)
        self.e_star = float(self.row[P_E_STAR])
        self.g_star = effective_shear_modulus(sphere, wall)
        eff = self.effects
        fixed = self.contact.restitution is not None
        # as in the impulse model, a prescribed restitution bypasses §3.1-3.8, adhesion included
        self.plasticity = bool(eff.plasticity) and not fixed
        self.adhesion = bool(eff.adhesion) and not fixed
        self.friction = bool(eff.rotation and eff.friction)
        self.rolling = bool(eff.rotation and eff.rolling_resistance)
        self.tangential = TANGENTIAL_MODELS[tangential]
        self.f0 = float(line_force(self.row, self.radius)) if self.adhesion else 0.0
        self.coef = dashpot_coefficient(self.contact.restitution) if fixed else 0.0
        # like the impulse model, a prescribed restitution bypasses the viscous force too
        self.visc = (float(self.row[P_VISC]) if eff.viscoelastic_damping and not fixed
                     else 0.0)

    def hertz_time(self, v0: float) -> float:
        return float(hertz_contact_time(v0, self.mass, self.radius, self.e_star))

    def kernel_args(self):
        return (self.radius, self.mass, self.inertia, self.radius, self.row, self.f0,
                self.g_star, self.coef, self.visc)

    def flags(self):
        return (self.plasticity, self.adhesion, self.friction, self.rolling, self.tangential)


def _result(setup: _Setup, v0, vt0, w0, out, dt, t_h) -> ResolvedImpact:
    vn1, vt1, w1 = float(out[O_VN]), float(out[O_VT]), float(out[O_W])
    m, inertia = setup.mass, setup.inertia
    ke0 = 0.5 * m * (v0 * v0 + vt0 * vt0) + 0.5 * inertia * w0 * w0
    ke1 = 0.5 * m * (vn1 * vn1 + vt1 * vt1) + 0.5 * inertia * w1 * w1
    return ResolvedImpact(
        e_n=vn1 / v0, e_t=vt1 / vt0 if vt0 != 0.0 else math.nan,
        velocity_after=np.array([vt1, 0.0, vn1]), spin_after=w1,
        rebound_angle=math.degrees(math.atan2(vt1, vn1)) if vn1 > 0.0 else math.nan,
        captured=bool(out[O_CAPTURED]), contact_time=float(out[O_T_CONTACT]),
        delta_max=float(out[O_D_MAX]), residual_deformation=float(out[O_D_RES]),
        force_max=float(out[O_F_MAX]), energy_lost=ke0 - ke1, steps=int(out[O_STEPS]), dt=dt,
        hertz_time=t_h)


def _initial(speed, angle_deg, spin):
    speed = check_positive(speed, "speed")
    if not 0.0 <= angle_deg < 90.0:
        raise InputError(f"must be in [0, 90) degrees from the wall normal, got {angle_deg!r}",
                         "angle")
    th = math.radians(angle_deg)
    return speed * math.cos(th), speed * math.sin(th), float(spin)


def resolved_wall_impact(sphere: Material, wall: Material, radius: float, speed: float,
                         angle_deg: float = 0.0, spin: float = 0.0, *,
                         contact: Contact | None = None, effects: Effects | None = None,
                         steps_per_contact: float = DEFAULT_STEPS_PER_CONTACT,
                         tangential: str = "coulomb") -> ResolvedImpact:
    """Integrate one sphere–wall impact through the contact.

    Args:
        sphere, wall: Materials (the wall may be elastic or rigid; it does not move).
        radius: Sphere radius [m].
        speed: Impact speed [m/s].
        angle_deg: Impact angle from the wall normal [deg], in [0, 90).
        spin: Initial spin about +y (n × t̂), positive = topspin [rad/s].
        contact: Pair properties (as :func:`hsgran.impact.sphere_wall_impact`).
        effects: Enabled effects (default: all).
        steps_per_contact: dt = t_c / this, with t_c the elastic Hertz duration at the normal
            impact speed (MODEL §3.1), the DEM custom for choosing a time step [-].
        tangential: ``"coulomb"`` (rigid sticking, the impulse model's assumption) or
            ``"mindlin"`` (tangential spring k_t = 8 G* a with a Coulomb cap).

    Returns:
        :class:`ResolvedImpact`.

    Raises:
        InputError: non-physical input.

    References:
        MODEL §3 (normal law), §3.8 (adhesion), §4 (friction), §5.1 (rolling torque).
    """
    setup = _Setup(sphere, wall, radius, contact, effects, tangential)
    v0, vt0, w0 = _initial(speed, angle_deg, spin)
    steps_per_contact = check_positive(steps_per_contact, "steps_per_contact")
    t_h = setup.hertz_time(v0)
    dt = t_h / steps_per_contact
    out = np.zeros(O_SIZE)
    _impact(v0, vt0, w0, *setup.kernel_args(), dt, *setup.flags(),
            int(MAX_STEPS_FACTOR * steps_per_contact) + 10, out)
    return _result(setup, v0, vt0, w0, out, dt, t_h)


@dataclass(frozen=True)
class ResolvedPairImpact:
    """Outcome of one time-resolved impact of two spheres (SI units). Frame: the normal n from
    sphere 2 to sphere 1 is +z, the relative tangential velocity is along +x before, spins are
    about +y."""

    velocity_1: np.ndarray  #: centre velocity of sphere 1 after [m/s]
    velocity_2: np.ndarray  #: centre velocity of sphere 2 after [m/s]
    spin_1: float  #: spin of sphere 1 about +y after [rad/s]
    spin_2: float  #: spin of sphere 2 about +y after [rad/s]
    e_n: float  #: normal restitution of the relative velocity [-]
    steps: int  #: time steps taken [-]


def resolved_pair_impact(material_1: Material, material_2: Material, radius_1: float,
                         radius_2: float, speed: float, angle_deg: float = 0.0, *,
                         velocity_2=(0.0, 0.0, 0.0), spins=(0.0, 0.0),
                         contact: Contact | None = None, effects: Effects | None = None,
                         steps_per_contact: float = DEFAULT_STEPS_PER_CONTACT,
                         tangential: str = "coulomb") -> ResolvedPairImpact:
    """Integrate one impact of two spheres through the contact.

    The contact forces act on the relative motion only, so the pair is integrated as one body
    of mass m* = m1 m2/(m1 + m2) on a wall, whose tangential mass matches the pair's,
    1/m_t = 1/m1 + 1/m2 + R1²/I1 + R2²/I2 (MODEL §4.1: a lever arm R* and inertia
    R*²/(1/m_t − 1/m*)); each sphere then takes ±the impulse.

    Args:
        material_1, material_2, radius_1, radius_2: The spheres [m].
        speed: Relative speed of sphere 1 with respect to sphere 2 [m/s].
        angle_deg: Its angle from −n [deg], in [0, 90).
        velocity_2: Sphere 2's velocity before [m/s] (sphere 1's is velocity_2 plus the
            relative velocity).
        spins: Spins of spheres 1 and 2 about +y before [rad/s].
        Other arguments: as :func:`resolved_wall_impact`.
    """
    setup = _Setup(material_1, material_2, radius_1, contact, effects, tangential)
    v0, vt0, _ = _initial(speed, angle_deg, 0.0)
    r2 = check_positive(radius_2, "radius_2")
    if material_2.rigid or not math.isfinite(material_2.density):
        raise InputError(f"material '{material_2.name}' is rigid: it can be a wall, not a "
                         "sphere", "material_2")
    m1 = setup.mass
    m2 = solid_sphere_mass(material_2.density, r2)
    i1 = SOLID_SPHERE_INERTIA * m1 * radius_1**2
    i2 = SOLID_SPHERE_INERTIA * m2 * r2**2
    m_eff = m1 * m2 / (m1 + m2)
    r_eff = radius_1 * r2 / (radius_1 + r2)
    inv_mt = 1.0 / m1 + 1.0 / m2 + radius_1**2 / i1 + r2**2 / i2
    inertia = r_eff**2 / (inv_mt - 1.0 / m_eff)
    w_rel = (radius_1 * spins[0] + r2 * spins[1]) / r_eff  # slip u = v_t − (R1 ω1 + R2 ω2)
    t_h = float(hertz_contact_time(v0, m_eff, r_eff, setup.e_star))
    dt = t_h / check_positive(steps_per_contact, "steps_per_contact")
    out = np.zeros(O_SIZE)
    _impact(v0, vt0, w_rel, r_eff, m_eff, inertia, r_eff, setup.row,
            float(line_force(setup.row, r_eff)) if setup.adhesion else 0.0, setup.g_star,
            setup.coef, setup.visc, dt, *setup.flags(),
            int(MAX_STEPS_FACTOR * steps_per_contact) + 10, out)
    j_n = m_eff * (out[O_VN] + v0)  # on sphere 1, along +z
    j_t = m_eff * (out[O_VT] - vt0)  # on sphere 1, along +x
    u2 = np.asarray(velocity_2, dtype=float)
    u1 = u2 + np.array([vt0, 0.0, -v0])
    jv = np.array([j_t, 0.0, j_n])
    return ResolvedPairImpact(
        velocity_1=u1 + jv / m1, velocity_2=u2 - jv / m2,
        spin_1=spins[0] - radius_1 * j_t / i1, spin_2=spins[1] - r2 * j_t / i2,
        e_n=float(out[O_VN]) / v0, steps=int(out[O_STEPS]))


def timed_wall_impacts(sphere: Material, wall: Material, radius: float, speeds, angles_deg,
                       *, contact: Contact | None = None, effects: Effects | None = None,
                       steps_per_contact: float = DEFAULT_STEPS_PER_CONTACT,
                       tangential: str = "coulomb", repeat: int = 3):
    """Integrate a batch of impacts in one compiled call and time it.

    Args:
        speeds, angles_deg: Impact speeds [m/s] and angles [deg], equal lengths.
        repeat: The batch is run this many times; the CPU time is the fastest run.
        Other arguments: as :func:`resolved_wall_impact`.

    Returns:
        (list of :class:`ResolvedImpact`, CPU seconds per impact (``time.process_time``)).
    """
    setup = _Setup(sphere, wall, radius, contact, effects, tangential)
    init = [_initial(s, a, 0.0) for s, a in zip(speeds, angles_deg, strict=True)]
    v0 = np.array([x[0] for x in init])
    vt0 = np.array([x[1] for x in init])
    w0 = np.zeros(len(init))
    t_h = np.array([setup.hertz_time(v) for v in v0])
    dt = t_h / steps_per_contact
    max_steps = np.full(len(init), int(MAX_STEPS_FACTOR * steps_per_contact) + 10,
                        dtype=np.int64)
    out = np.zeros((len(init), O_SIZE))
    args = (v0, vt0, w0, *setup.kernel_args(), dt, *setup.flags(), max_steps, out)
    _impact_batch(*args)  # compiles (or loads) the kernel: never timed
    best = math.inf
    for _ in range(max(1, repeat)):
        t = time.process_time()
        _impact_batch(*args)
        best = min(best, time.process_time() - t)
    results = [_result(setup, v0[k], vt0[k], 0.0, out[k], dt[k], t_h[k])
               for k in range(len(init))]
    return results, best / len(init)


@functools.lru_cache(maxsize=64)
def dashpot_coefficient(restitution: float) -> float:
    """Dashpot coefficient that gives normal restitution ``restitution`` with the Hertz law.

    With the dashpot of :func:`hsgran.dem.law.dashpot_force` the restitution of a Hertz contact
    does not depend on the impact speed or the materials (the equation of motion scales out), so
    the coefficient is found once, by bisection on a frictionless head-on impact integrated at
    t_c/``CALIBRATION_STEPS``. The closed-form estimate of LIGGGHTS and LAMMPS,
    2 (5/6)^(1/2) |ln e|/(ln² e + π²)^(1/2), is 2 % below the calibrated value at e = 0.9 and
    16 % below at e = 0.5 (measured with this function): calibration is what a careful DEM
    user does.

    Args:
        restitution: e_n in (0, 1].

    Returns:
        The coefficient [-] (0 for e_n = 1).
    """
    e = float(restitution)
    if not 0.0 < e <= 1.0:
        raise InputError(f"must be in (0, 1] for a dashpot, got {restitution!r}", "restitution")
    if e == 1.0:
        return 0.0
    steel = Material("calibration", 7800.0, 200e9, 0.3)
    row = pair_row(steel, steel, Contact())
    radius, v0 = 1e-3, 1.0
    mass = solid_sphere_mass(steel.density, radius)
    t_h = float(hertz_contact_time(v0, mass, radius, row[P_E_STAR]))
    dt = t_h / CALIBRATION_STEPS
    out = np.zeros(O_SIZE)
    lo, hi = 0.0, CALIBRATION_MAX_COEF
    while hi - lo > CALIBRATION_TOL:
        mid = 0.5 * (lo + hi)
        _impact(v0, 0.0, 0.0, radius, mass, 0.4 * mass * radius**2, radius, row, 0.0, 1.0, mid,
                0.0, dt, False, False, False, False, TANGENTIAL_COULOMB,
                int(MAX_STEPS_FACTOR * CALIBRATION_STEPS), out)
        if out[O_VN] / v0 > e:
            lo = mid
        else:
            hi = mid
    return 0.5 * (lo + hi)
