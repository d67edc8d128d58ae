"""Normal model: staged compression and elastic recovery (MODEL §3).

The deformation history is integrated in energy (quasi-static): the maximum compression δ_max
solves W(δ_max) = T0 = m* v0²/2 (§3.5), and the elastic energy returned in recovery follows from
the Hertz-type unloading of the flattened contact (§3.7). Stage codes are the ``STAGE_*``
constants. All functions are compiled, scalar in, scalars out.

Provenance: §3.1, §3.2, §3.6 [LIT]; §3.3 elastic–plastic log pressure law and §3.4 fully plastic
stage are **[OURS]** reconstructions (the paper's equations were not available; the literal
Stronge area law gives e_n > 1, see MODEL §3.10); §3.7 recovery [YT]/[LIT].
"""

from __future__ import annotations

import math

from hsgran._jit import njit
from hsgran.materials import (
    P_A,
    P_DY_R,
    P_E_STAR,
    P_FY_R2,
    P_P_P,
    P_RHO_P,
    P_WP_R3,
    P_WY_R3,
)

STAGE_FIXED = 0  #: prescribed restitution: the normal model was bypassed (§3.9)
STAGE_ELASTIC = 1  #: δ_max ≤ δ_y (§3.1), or the elastic Hertz law without plasticity
STAGE_ELASTIC_PLASTIC = 2  #: δ_y < δ_max ≤ δ_p (§3.3)
STAGE_FULLY_PLASTIC = 3  #: δ_max > δ_p (§3.4)
STAGE_NAMES = ("fixed", "elastic", "elastic-plastic", "fully-plastic")

#: Newton on w(u) stops once the relative step is below this: the iteration converges
#: quadratically, so the remaining error is then ~(1e-13)², far below double round-off.
NEWTON_RTOL = 1e-13
#: Newton iteration cap. From the start used below it needs 3–6 steps; 60 only guards
#: against an infinite loop on non-finite input.
NEWTON_MAX_ITER = 60
#: Hertz contact-duration constant C in t_c = C (m*²/(R* E*² v0))^(1/5) (MODEL §3.1 rounds it
#: to 2.868). Exactly, t_c = 2 (δ_max/v0) ∫₀¹ (1 − x^(5/2))^(−1/2) dx with the integral equal to
#: (2/5) B(2/5, 1/2), and δ_max = (15/16)^(2/5) (m*² v0⁴/(R* E*²))^(1/5), so C = 2.868266...
HERTZ_DURATION_COEF = (2.0 * 0.4 * math.gamma(0.4) * math.gamma(0.5) / math.gamma(0.9)
                       * (15.0 / 16.0) ** 0.4)


@njit
def hertz_max_compression(t0, e_star, r_eff):
    """Maximum compression of an elastic (Hertz) impact of kinetic energy ``t0``.

    Args:
        t0: Kinetic energy of the normal approach T0 = m* v0²/2 [J].
        e_star: Effective modulus E* [Pa].
        r_eff: Effective radius R* [m].

    Returns:
        (δ_max [m], F_max [N], a_max [m]).

    References:
        MODEL §3.1: W = (8/15) E* R*^(1/2) δ^(5/2), F = (4/3) E* R*^(1/2) δ^(3/2), a² = R* δ.
    """
    sr = math.sqrt(r_eff)
    d = (15.0 * t0 / (8.0 * e_star * sr)) ** 0.4
    f = (4.0 / 3.0) * e_star * sr * d * math.sqrt(d)
    return d, f, math.sqrt(r_eff * d)


@njit
def elastic_plastic_work(u, a_coef):
    """Scaled compression work w(u) = (W − W_y)/(F_y δ_y) of the elastic–plastic stage.

    Args:
        u: δ/δ_y ≥ 1 [-].
        a_coef: (λ − 1)/ln ρ_p [-].

    References:
        MODEL §3.3 [OURS]: w = (u² − 1)/2 + A [u² ln(u)/2 − u²/4 + 1/4]; dw/du = u (1 + A ln u).
    """
    uu = u * u
    return 0.5 * (uu - 1.0) + a_coef * (0.5 * uu * math.log(u) - 0.25 * uu + 0.25)


@njit
def solve_elastic_plastic(target, a_coef, rho_p):
    """Solve w(u) = ``target`` for u in [1, ρ_p] (MODEL §3.5, middle case).

    w is increasing and convex on u ≥ 1 (w'' = 1 + A + A ln u > 0), so Newton converges from
    any start in [1, ρ_p]; after the first step it approaches the root monotonically from above.

    Args:
        target: (T0 − W_y)/(F_y δ_y) ≥ 0 [-].
        a_coef: (λ − 1)/ln ρ_p [-].
        rho_p: δ_p/δ_y [-].

    Returns:
        u = δ_max/δ_y [-].
    """
    # Start: the A = 0 root, corrected once for the log term (close for all targets).
    u = math.sqrt(2.0 * target + 1.0)
    u = math.sqrt((2.0 * target + 1.0 - 0.5 * a_coef) / (1.0 + a_coef * (math.log(u) - 0.5)))
    u = min(max(u, 1.0), rho_p)
    for _ in range(NEWTON_MAX_ITER):
        lu = math.log(u)
        step = (elastic_plastic_work(u, a_coef) - target) / (u * (1.0 + a_coef * lu))
        u -= step
        if u < 1.0:
            u = 1.0
        if abs(step) <= NEWTON_RTOL * u:
            break
    return u


@njit
def staged_max_compression(t0, r_eff, row):
    """Stage and maximum compression of the staged normal model.

    Args:
        t0: Kinetic energy of the normal approach T0 [J].
        r_eff: Effective radius R* [m].
        row: Pair row (``hsgran.materials.pair_row``).

    Returns:
        (stage, δ_max [m], F_max [N], a_max [m]).

    References:
        MODEL §3.5 (energy balance W(δ_max) = T0); laws of §3.1, §3.3, §3.4; a² = R* δ in all
        stages ([OURS], Thornton–Ning convention).
    """
    r3 = r_eff * r_eff * r_eff
    wy = row[P_WY_R3] * r3
    if t0 <= wy:
        d, f, a = hertz_max_compression(t0, row[P_E_STAR], r_eff)
        return STAGE_ELASTIC, d, f, a
    dy = row[P_DY_R] * r_eff
    fy = row[P_FY_R2] * r_eff * r_eff
    wp = row[P_WP_R3] * r3
    if t0 < wp:
        a_coef = row[P_A]
        u = solve_elastic_plastic((t0 - wy) / (fy * dy), a_coef, row[P_RHO_P])
        d = u * dy
        f = fy * u * (1.0 + a_coef * math.log(u))  # §3.3 F = F_y u [1 + (λ−1) ln(u)/L]
        return STAGE_ELASTIC_PLASTIC, d, f, math.sqrt(r_eff * d)
    dp = row[P_RHO_P] * dy
    pp = row[P_P_P]
    d = math.sqrt(dp * dp + 2.0 * (t0 - wp) / (math.pi * r_eff * pp))  # §3.5, T0 ≥ W_p
    return STAGE_FULLY_PLASTIC, d, math.pi * r_eff * d * pp, math.sqrt(r_eff * d)


@njit
def elastic_recovery(f_max, a_max, e_star):
    """Elastic unloading of a flattened contact (MODEL §3.7).

    Args:
        f_max: Force at maximum compression [N].
        a_max: Contact radius at maximum compression [m].
        e_star: Effective modulus E* [Pa].

    Returns:
        (R′ [m], δ_r [m], W_r [J]): unloading radius 4E* a³/(3F), recovered deformation
        3F/(4E* a), and returned elastic energy (2/5) F δ_r.
    """
    r_prime = 4.0 * e_star * a_max**3 / (3.0 * f_max)
    d_r = 3.0 * f_max / (4.0 * e_star * a_max)
    return r_prime, d_r, 0.4 * f_max * d_r


@njit
def stage_impulses(v0, m_eff, wy, wp):
    """Normal impulse accumulated in each compression stage (MODEL §3.6).

    Args:
        v0: Normal impact speed [m/s].
        m_eff: Effective mass m* [kg].
        wy: Work at first yield W_y [J] (``inf`` if the pair never yields).
        wp: Work at full plasticity W_p [J].

    Returns:
        (P_e, P_ep, P_pl) [N s]; they add up to the compression impulse m* v0.
    """
    vy2 = 2.0 * wy / m_eff
    vp2 = 2.0 * wp / m_eff
    v02 = v0 * v0
    if v02 <= vy2:
        return m_eff * v0, 0.0, 0.0
    s_y = math.sqrt(v02 - vy2)
    if v02 <= vp2:
        return m_eff * (v0 - s_y), m_eff * s_y, 0.0
    s_p = math.sqrt(v02 - vp2)
    return m_eff * (v0 - s_y), m_eff * (s_y - s_p), m_eff * s_p


@njit
def hertz_contact_time(v0, m_eff, r_eff, e_star):
    """Duration of an elastic Hertz impact [s] (MODEL §3.1)."""
    return HERTZ_DURATION_COEF * (m_eff * m_eff / (r_eff * e_star * e_star * v0)) ** 0.2
