"""One collision from Python: a sphere on a wall, or two spheres (layer 4).

This is the validated public face of the compiled kernel :func:`hsgran.contact.model.resolve`:
it checks inputs, builds masses, inertias and the pair row, runs one collision with diagnostics
and returns an :class:`ImpactResult`.

Frame used by :func:`oblique_velocity` (and ``hsgran impact``): the wall normal is +z, the sphere
moves towards +x before impact, the impact angle θ is measured from the normal, and a spin ω
about +y = n × t̂ is positive in the forward-rolling sense (topspin).
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass

import numpy as np

from hsgran.contact import model
from hsgran.contact.normal import STAGE_NAMES
from hsgran.contact.tangential import REGIME_NAMES
from hsgran.effects import Effects
from hsgran.errors import InputError, check_positive
from hsgran.materials import (
    SOLID_SPHERE_INERTIA,
    Contact,
    CriticalValues,
    Material,
    critical_values,
    pair_row,
    solid_sphere_mass,
)


@dataclass(frozen=True)
class ImpactResult:
    """Outcome of one collision (SI units; vectors as 3-element lists in :meth:`to_dict`).

    Deformation fields are NaN where the model does not define them (e.g. a prescribed
    restitution bypasses the deformation model; the Hertz contact time exists only in the
    elastic stage).
    """

    velocity_after: np.ndarray  #: sphere 1 centre velocity after [m/s]
    angular_velocity_after: np.ndarray  #: sphere 1 spin after [rad/s]
    other_velocity_after: np.ndarray  #: sphere 2 (or wall) velocity after [m/s]
    other_angular_velocity_after: np.ndarray  #: sphere 2 spin after [rad/s] (0 for a wall)
    collided: bool  #: False if the bodies were not approaching (nothing applied)
    e_n: float  #: normal restitution [-]
    stage: str  #: deepest compression stage reached (or "fixed")
    regime: str  #: "sliding", "rolling" or "none"
    captured: bool  #: adhesion captured the sphere (e_n = 0)
    impact_speed: float  #: normal approach speed v0 [m/s]
    normal_impulse: float  #: J_n [N s]
    stage_impulses: tuple  #: (elastic, elastic–plastic, fully plastic) compression impulses [N s]
    tangential_impulse: float  #: J_t [N s]
    rolling_impulse: float  #: rolling-couple angular impulse H [N m s]
    delta_max: float  #: maximum compression [m]
    residual_deformation: float  #: plastic deformation left after recovery [m]
    contact_radius_max: float  #: contact radius at maximum compression [m]
    force_max: float  #: maximum normal force [N]
    recovery_radius: float  #: R′ of the unloading stage [m]
    work_recovered: float  #: elastic energy returned W_r [J]
    work_adhesion: float  #: adhesion work in recovery W_A [J]
    energy_lost: float  #: kinetic energy dissipated [J]
    contact_time: float  #: Hertz contact duration (elastic stage only) [s]
    critical: CriticalValues  #: the pair's critical values for these sizes

    def to_dict(self) -> dict:
        """Plain JSON-ready dict (arrays as lists, NaN as None)."""
        out = {}
        for k, v in asdict(self).items():
            if isinstance(v, np.ndarray):
                v = [float(x) for x in v]
            elif isinstance(v, tuple):
                v = [_json_float(float(x)) for x in v]
            elif isinstance(v, dict):
                v = {kk: _json_float(vv) for kk, vv in v.items()}
            elif isinstance(v, float):
                v = _json_float(v)
            out[k] = v
        return out


def _json_float(x: float):
    return None if isinstance(x, float) and not math.isfinite(x) else float(x)


def _vector(value, key: str) -> np.ndarray:
    try:
        arr = np.asarray(value, dtype=np.float64)
    except (TypeError, ValueError):
        raise InputError(f"must be 3 numbers, got {value!r}", key) from None
    if arr.shape != (3,):
        raise InputError(f"must be 3 numbers, got {value!r}", key)
    if not np.all(np.isfinite(arr)):
        raise InputError(f"must be finite, got {value!r}", key)
    return arr.copy()


def sphere_mass(material: Material, radius: float) -> float:
    """Mass of a solid sphere [kg] from density [kg/m³] and radius [m]."""
    return solid_sphere_mass(material.density, radius)


def oblique_velocity(speed: float, angle_deg: float) -> np.ndarray:
    """Velocity [m/s] of a sphere hitting a wall with normal +z at ``angle_deg`` from the normal,
    moving towards +x: (V sin θ, 0, −V cos θ).

    Raises:
        InputError: speed ≤ 0 or angle outside [0, 90).
    """
    speed = check_positive(speed, "speed")
    if (isinstance(angle_deg, bool) or not isinstance(angle_deg, (int, float))
            or not 0.0 <= angle_deg < 90.0):
        raise InputError(f"must be in [0, 90) degrees from the wall normal, got {angle_deg!r}",
                         "angle")
    th = math.radians(angle_deg)
    return np.array([speed * math.sin(th), 0.0, -speed * math.cos(th)])


def _check_contact_for(effects: Effects, contact: Contact) -> None:
    if effects.friction and contact.sliding_friction is None:
        raise InputError("a value is required by the 'friction' effect: pass "
                         "Contact(sliding_friction=...), or switch the effect off",
                         "sliding_friction")


def _check_sphere(material: Material, key: str) -> None:
    if material.rigid or not math.isfinite(material.density):
        raise InputError(f"material '{material.name}' is rigid: it can be a wall, not a sphere",
                         key)


def _run(v1, w1, v2, w2, normal, inv_m1, inv_m2, inv_i1, inv_i2, r1, r2, curv, row, effects,
         r_eff, m_eff) -> ImpactResult:
    rec = model.new_record()
    hit = model.make_resolver(effects, diagnostics=True)(
        v1, w1, v2, w2, normal[0], normal[1], normal[2], inv_m1, inv_m2, inv_i1, inv_i2, r1, r2,
        curv, row, rec)
    crit = critical_values(row, r_eff, m_eff)
    if not hit:
        nan = math.nan
        return ImpactResult(v1, w1, v2, w2, False, nan, "none", "none", False, 0.0, 0.0,
                            (0.0, 0.0, 0.0), 0.0, 0.0, nan, nan, nan, nan, nan, nan, nan, 0.0,
                            nan, crit)
    return ImpactResult(
        velocity_after=v1, angular_velocity_after=w1,
        other_velocity_after=v2, other_angular_velocity_after=w2, collided=True,
        e_n=float(rec[model.REC_E_N]), stage=STAGE_NAMES[int(rec[model.REC_STAGE])],
        regime=REGIME_NAMES[int(rec[model.REC_REGIME])],
        captured=bool(rec[model.REC_CAPTURED]), impact_speed=float(rec[model.REC_V0]),
        normal_impulse=float(rec[model.REC_J_N]),
        stage_impulses=(float(rec[model.REC_P_E]), float(rec[model.REC_P_EP]),
                        float(rec[model.REC_P_PL])),
        tangential_impulse=float(rec[model.REC_J_T]),
        rolling_impulse=float(rec[model.REC_H_ROLL]),
        delta_max=float(rec[model.REC_DELTA_MAX]),
        residual_deformation=float(rec[model.REC_DELTA_RES]),
        contact_radius_max=float(rec[model.REC_A_MAX]), force_max=float(rec[model.REC_F_MAX]),
        recovery_radius=float(rec[model.REC_R_PRIME]), work_recovered=float(rec[model.REC_W_R]),
        work_adhesion=float(rec[model.REC_W_A]), energy_lost=float(rec[model.REC_ENERGY_LOST]),
        contact_time=float(rec[model.REC_T_CONTACT]), critical=crit)


def sphere_wall_impact(sphere: Material, wall: Material, radius: float, velocity,
                       angular_velocity=(0.0, 0.0, 0.0), *, normal=(0.0, 0.0, 1.0),
                       wall_velocity=(0.0, 0.0, 0.0), contact: Contact | None = None,
                       effects: Effects | None = None) -> ImpactResult:
    """One sphere–wall collision.

    Args:
        sphere: Sphere material.
        wall: Wall material (``rigid`` drops out of E*).
        radius: Sphere radius [m].
        velocity: Sphere velocity before impact [m/s], (3,).
        angular_velocity: Sphere spin before impact [rad/s], (3,).
        normal: Wall normal pointing towards the sphere [-], (3,); normalised here.
        wall_velocity: Velocity of a moving wall [m/s], (3,).
        contact: Pair properties (default: none declared, i.e. frictionless and no rolling
            resistance unless the effects need them).
        effects: Enabled effects (default: all).

    Returns:
        :class:`ImpactResult`; ``other_*`` hold the (unchanged) wall velocity and zero spin.

    Raises:
        InputError: non-physical or missing input.

    References:
        MODEL §2 (wall as body 2 with infinite mass), §6.
    """
    effects = Effects.all() if effects is None else effects
    contact = Contact() if contact is None else contact
    _check_contact_for(effects, contact)
    _check_sphere(sphere, "sphere")
    radius = check_positive(radius, "radius")
    n = _vector(normal, "normal")
    norm = float(np.linalg.norm(n))
    if norm == 0.0:
        raise InputError("must not be the zero vector", "normal")
    n /= norm
    m = sphere_mass(sphere, radius)
    inertia = SOLID_SPHERE_INERTIA * m * radius**2
    row = pair_row(sphere, wall, contact)
    return _run(_vector(velocity, "velocity"), _vector(angular_velocity, "angular_velocity"),
                _vector(wall_velocity, "wall_velocity"), np.zeros(3), n, 1.0 / m, 0.0,
                1.0 / inertia, 0.0, radius, 0.0, 1.0 / radius, row, effects, radius, m)


def sphere_sphere_impact(material1: Material, material2: Material, radius1: float,
                         radius2: float, velocity1, velocity2, angular_velocity1=(0.0, 0.0, 0.0),
                         angular_velocity2=(0.0, 0.0, 0.0), *, normal=(0.0, 0.0, 1.0),
                         contact: Contact | None = None,
                         effects: Effects | None = None) -> ImpactResult:
    """One sphere–sphere collision.

    Args:
        material1, material2: Materials of spheres 1 and 2.
        radius1, radius2: Radii [m].
        velocity1, velocity2: Centre velocities before impact [m/s], (3,).
        angular_velocity1, angular_velocity2: Spins before impact [rad/s], (3,).
        normal: Unit vector from the centre of sphere 2 to that of sphere 1 [-], (3,).
        contact: Pair properties.
        effects: Enabled effects (default: all).

    Returns:
        :class:`ImpactResult` with both spheres' velocities and spins after.

    Raises:
        InputError: non-physical or missing input.
    """
    effects = Effects.all() if effects is None else effects
    contact = Contact() if contact is None else contact
    _check_contact_for(effects, contact)
    _check_sphere(material1, "material1")
    _check_sphere(material2, "material2")
    r1 = check_positive(radius1, "radius1")
    r2 = check_positive(radius2, "radius2")
    n = _vector(normal, "normal")
    norm = float(np.linalg.norm(n))
    if norm == 0.0:
        raise InputError("must not be the zero vector", "normal")
    n /= norm
    m1 = sphere_mass(material1, r1)
    m2 = sphere_mass(material2, r2)
    row = pair_row(material1, material2, contact)
    r_eff = 1.0 / (1.0 / r1 + 1.0 / r2)
    m_eff = 1.0 / (1.0 / m1 + 1.0 / m2)
    return _run(_vector(velocity1, "velocity1"), _vector(angular_velocity1, "angular_velocity1"),
                _vector(velocity2, "velocity2"), _vector(angular_velocity2, "angular_velocity2"),
                n, 1.0 / m1, 1.0 / m2, 1.0 / (SOLID_SPHERE_INERTIA * m1 * r1**2),
                1.0 / (SOLID_SPHERE_INERTIA * m2 * r2**2), r1, r2, 1.0 / r_eff, row, effects,
                r_eff, m_eff)
