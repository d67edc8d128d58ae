"""The force of one contact at one instant: hsgran's staged law written as F(δ) (MODEL §3–§5).

The impulse model (:mod:`hsgran.contact`) integrates this law in energy and never needs the
force at a given instant. A time-stepping integrator does, so the same laws are written here as
functions of the current overlap, using the pair row of :func:`hsgran.materials.pair_row` (so
the constants δ_y, F_y, λ, ρ_p, p_p, E*, f0 are exactly the impulse model's) and the recovery
formulas of :func:`hsgran.contact.normal.elastic_recovery`:

* loading (compression) — §3.1 Hertz, §3.3 elastic–plastic log-pressure law **[OURS]**, §3.4
  fully plastic stage **[OURS]**; a² = R* δ in all stages (Thornton–Ning convention, [OURS]);
* unloading — §3.7: Hertz with the flattened radius R′ from (δ_max, F_max, a_max), shifted by
  the residual deformation δ_res; reloading below δ_max follows the same elastic curve;
* adhesion — §3.8: Dunn's line force 2π a f0 on the contact perimeter, recovery only
  ([P]/[YT]; f0 estimate [OURS]);
* a restitution dashpot (not part of docs/model.md): how DEM codes prescribe e_n; used only when a
  pair gives a fixed restitution, which in the impulse model bypasses §3.1–3.8 (§3.9);
* tangential — Coulomb friction with rigid sticking (the impulse model's assumption, §4: no
  tangential compliance), or a Mindlin no-slip spring k_t = 8 G* a capped by Coulomb (what DEM
  codes use; not part of docs/model.md, which has no tangential compliance, §4.4);
* rolling resistance — torque μ_r R* F_n against the rolling spin (§5.1, [OURS]).

All functions are compiled scalar kernels (SI units throughout).
"""

from __future__ import annotations

import math

from hsgran._jit import njit
from hsgran.contact.normal import elastic_recovery
from hsgran.materials import P_A, P_DY_R, P_E_STAR, P_FY_R2, P_P_P, P_RHO_P


@njit
def loading_force(d, r_eff, row, plasticity):
    """Normal force on the compression (loading) curve.

    Args:
        d: Overlap δ ≥ 0 [m].
        r_eff: Effective radius R* [m].
        row: Pair row (``hsgran.materials.pair_row``).
        plasticity: Staged law (True) or elastic Hertz at all depths (False).

    Returns:
        F [N].

    References:
        MODEL §3.1 F = (4/3) E* R*^(1/2) δ^(3/2); §3.3 F = F_y u [1 + (λ − 1) ln(u)/L] with
        u = δ/δ_y ([OURS]); §3.4 F = π R* δ p_p ([OURS]).
    """
    if d <= 0.0:
        return 0.0
    if plasticity:
        dy = row[P_DY_R] * r_eff
        if d > dy:  # a pair that never yields stores δ_y = ∞
            if d <= row[P_RHO_P] * dy:
                u = d / dy
                return row[P_FY_R2] * r_eff * r_eff * u * (1.0 + row[P_A] * math.log(u))
            return math.pi * r_eff * d * row[P_P_P]
    return (4.0 / 3.0) * row[P_E_STAR] * math.sqrt(r_eff) * d * math.sqrt(d)


@njit
def unloading_curve(d_max, r_eff, row, plasticity):
    """Parameters of the elastic unloading curve that starts at maximum compression.

    Args:
        d_max: Deepest overlap reached so far δ_max [m].
        r_eff: Effective radius R* [m].
        row: Pair row.
        plasticity: Staged law (True) or elastic Hertz (False).

    Returns:
        (R′ [m], δ_res [m]): the flattened radius and the residual plastic deformation.
        An elastic contact unloads along its loading curve: (R*, 0).

    References:
        MODEL §3.7: R′ = 4E* a_max³/(3F_max), δ_r = 3F_max/(4E* a_max), δ_res = δ_max − δ_r.
    """
    if not plasticity or d_max <= row[P_DY_R] * r_eff:
        return r_eff, 0.0
    f_max = loading_force(d_max, r_eff, row, plasticity)
    r_prime, d_r, _ = elastic_recovery(f_max, math.sqrt(r_eff * d_max), row[P_E_STAR])
    return r_prime, d_max - d_r


@njit
def unloading_force(d, r_prime, d_res, e_star):
    """Force and contact radius on the unloading curve (MODEL §3.7).

    Args:
        d: Overlap δ [m].
        r_prime: Unloading radius R′ [m].
        d_res: Residual deformation δ_res [m].
        e_star: Effective modulus E* [Pa].

    Returns:
        (F [N], a [m]): F = (4/3) E* R′^(1/2) (δ − δ_res)^(3/2), a² = R′ (δ − δ_res); zero once
        δ ≤ δ_res (the surfaces have separated from the flattened profile).
    """
    x = d - d_res
    if x <= 0.0:
        return 0.0, 0.0
    return (4.0 / 3.0) * e_star * math.sqrt(r_prime) * x * math.sqrt(x), math.sqrt(r_prime * x)


@njit
def adhesion_force(a, f0):
    """Dunn's adhesion force 2π a f0 [N] of a line force ``f0`` [N/m] on a perimeter of radius
    ``a`` [m] (MODEL §3.8); it acts against separation during recovery only."""
    return 2.0 * math.pi * a * f0


@njit
def dashpot_force(approach_rate, d, r_eff, m_eff, e_star, coef):
    """Normal viscous force of a restitution dashpot (DEM practice, not docs/model.md).

    Args:
        approach_rate: dδ/dt [m/s], positive while compressing.
        d: Overlap δ [m].
        r_eff, m_eff, e_star: R* [m], m* [kg], E* [Pa].
        coef: Dimensionless damping coefficient (see ``single.dashpot_coefficient``).

    Returns:
        coef (m* S_n)^(1/2) dδ/dt [N], with the Hertz normal stiffness S_n = 2 E* (R* δ)^(1/2).
        With this form (Tsuji et al. 1992, as in LIGGGHTS and LAMMPS' coeff_restitution
        damping) e_n does not depend on the impact speed, so one coefficient gives one e_n.
    """
    if d <= 0.0:
        return 0.0
    s_n = 2.0 * e_star * math.sqrt(r_eff * d)
    return coef * math.sqrt(m_eff * s_n) * approach_rate


@njit
def kuwabara_kono_force(approach_rate, d, r_eff, e_star, a_diss):
    """Viscous normal force of viscoelastic spheres (Kuwabara & Kono 1987; Brilliantov et al.
    1996; docs/model.md §3.11): (4/3) E* R*^(1/2) (3/2) A δ^(1/2) dδ/dt = A S_n dδ/dt [N],
    with the Hertz normal stiffness S_n = 2 E* (R* δ)^(1/2) and the pair's dissipative
    constant A [s]; dδ/dt [m/s] positive while compressing, δ [m]."""
    if d <= 0.0:
        return 0.0
    return a_diss * 2.0 * e_star * math.sqrt(r_eff * d) * approach_rate


@njit
def coulomb_force(slip, m_t, mu, f_n, dt):
    """Tangential force of Coulomb friction with rigid sticking, for one time step.

    The force that would stop the slip within the step, m_t* u/dt, is applied if it is within
    the Coulomb limit μ F_n; otherwise the force is μ F_n against the slip. As dt → 0 this is
    the impulse model's rigid-body rule J_t = min(m_t* |u0|, μ J_n) (MODEL §4.2).

    Args:
        slip: Contact-point slip velocity u along the tangent [m/s].
        m_t: Tangential effective mass m_t* [kg].
        mu: Sliding friction μ_s [-].
        f_n: Normal force (compressive part, ≥ 0) [N].
        dt: Time step [s].

    Returns:
        F_t [N] along the tangent (opposite in sign to ``slip``).
    """
    need = m_t * slip / dt
    lim = mu * f_n
    if abs(need) <= lim:
        return -need
    return -lim if slip > 0.0 else lim


@njit
def mindlin_force(xi, k_t, mu, f_n):
    """Tangential spring with a Coulomb cap (Mindlin no-slip stiffness, DEM practice).

    Args:
        xi: Accumulated tangential displacement ξ [m].
        k_t: Tangential stiffness 8 G* a [N/m].
        mu: Sliding friction μ_s [-].
        f_n: Normal force (compressive part, ≥ 0) [N].

    Returns:
        (F_t [N], ξ [m]): −k_t ξ, or ∓μ F_n with ξ shortened to the sliding limit.
    """
    f = -k_t * xi
    lim = mu * f_n
    if abs(f) <= lim:
        return f, xi
    if k_t <= 0.0:
        return 0.0, 0.0
    s = 1.0 if xi > 0.0 else -1.0
    return -s * lim, s * lim / k_t


@njit
def rolling_torque(spin, inertia, mu_r, r_eff, f_n, dt):
    """Rolling-resistance torque about the rolling axis, for one time step.

    Args:
        spin: Rolling part of the relative angular velocity [rad/s].
        inertia: Moment of inertia of the spinning body [kg m²].
        mu_r: Rolling friction μ_r [-].
        r_eff: R* [m].
        f_n: Normal force (compressive part) [N].
        dt: Time step [s].

    Returns:
        Torque [N m] against ``spin``: μ_r R* F_n (MODEL §5.1, [OURS]), capped at the value
        that stops the rolling within the step (the time-resolved form of the §5.2 cap).
    """
    need = inertia * spin / dt
    lim = mu_r * r_eff * f_n
    if abs(need) <= lim:
        return -need
    return -lim if spin > 0.0 else lim
