"""The oblique Hertz–Mindlin impact in dimensionless form: the table behind the
``tangential_compliance`` effect (layer 5; compiled kernels).

Maw, Barber & Fawcett (1976, 1981) showed that the tangential outcome of an oblique impact of
elastic spheres depends, besides μ, on two numbers only: a stiffness ratio of the contact and
the incidence Ψ1 = u0/(μ v0) (u0 the contact-point slip before, v0 the normal approach speed).
This module integrates the DEM form of that problem through the contact:

- normal: Hertz, F_n = (4/3) E* R*^(1/2) δ^(3/2), plus for e_n < 1 the restitution dashpot of
  :func:`hsgran.dem.law.dashpot_force` (Tsuji et al. 1992), with which e_n does not depend on
  the speed;
- tangential: Mindlin's no-slip spring k_t = 8 G* a, a = (R* δ)^(1/2), on the accumulated
  tangential displacement ξ, capped by Coulomb |F_t| ≤ μ F_n (the "no-slip" model of
  Di Renzo & Di Maio 2004; what :func:`hsgran.dem.law.mindlin_force` does per step). The spring
  is undamped: a tangential dashpot (Tsuji et al. 1992) with the dashpot's force at first
  contact makes the stick–slip problem ill-posed (the capped spring's displacement diverges
  as the overlap vanishes, and the outcome does not converge with the step).

With the units δ0 (the elastic Hertz maximum compression at v0), t0 = δ0/v0, F0 = m* v0²/δ0,
the equations are free of every dimension (docs/model.md §4.5 derives them):

    x'' = −(5/4) x^(3/2) − c (15/8)^(1/2) x^(1/4) x'          (x = δ/δ0)
    s'  = (m*/m_t) g,   z' = s,   g = −(15/2) κ x^(1/2) z,   |g| ≤ f_n

with s = u/(μ v0), z = ξ/(μ δ0), g = F_t/(μ F0), f_n = F_n/F0, κ = G*/E* and the dashpot
coefficient c (set by e_n). For solid spheres m*/m_t = 7/2 (sphere on a wall, or two spheres
of any sizes). The outcome is the tangential impulse as a fraction of its Coulomb bound,
φ = J_t/(μ J_n), a function of κ, e_n and q = m_t u0/(μ J_n) (the rigid rule of MODEL §4.2 is
φ = min(q, 1)). An elastic contact (no dashpot) with q ≥ 1 slides from first contact to the
end, φ = 1; a damped one sticks at first, so φ < 1 there too.

The integration is velocity Verlet with ``steps`` steps per unit of dimensionless time, as
:mod:`hsgran.dem.single` does it in physical units.
"""

from __future__ import annotations

import math

import numpy as np

from hsgran._jit import njit
from hsgran.dem.viscoelastic import damped_hertz_restitution

#: m*/m_t of solid spheres: m_t = 1/(1/m1 + 1/m2 + R1²/I1 + R2²/I2) = (2/7) m* (MODEL §4.1).
MASS_RATIO_SOLID = 3.5
#: Dimensionless time of an elastic Hertz contact: t_c = 2.9432 δ0/v0 (MODEL §3.1).
HERTZ_TIME = 2.9432
#: Steps per unit of dimensionless time of the table's integrations: the stick–slip switches
#: make Verlet first order in the step; 5000 steps per t0 put φ within 5e-5 of its value at
#: 80000 for e_n from 0.1 to 1 (measured at q = 0.25 to 2).
TABLE_STEPS = 5000.0
#: Longest integration, in units of t0 (a damped contact lasts longer than HERTZ_TIME, never
#: 20 times longer for e_n ≥ 0.05).
MAX_TIME = 60.0


@njit
def oblique(q, kappa, coef, mass_ratio, steps):
    """One dimensionless oblique impact (see the module).

    Args:
        q: Incidence m_t u0/(μ J_n) [-], with J_n = (1 + e_n) m* v0 of this integration's
            own e_n (found first: the normal motion does not depend on the tangential).
        kappa: G*/E* [-].
        coef: Dashpot coefficient c (0: elastic) [-].
        mass_ratio: m*/m_t [-].
        steps: Steps per unit of dimensionless time.

    Returns:
        (φ, e_n): J_t/(μ J_n) and the normal restitution of the integration.
    """
    # the normal motion does not depend on the tangential one: first e_n, then the slip
    e_n = damped_hertz_restitution(coef, 0.0, steps)
    s0 = q * mass_ratio * (1.0 + e_n)
    dt = 1.0 / steps
    h = 0.5 * dt
    damp = coef * math.sqrt(15.0 / 8.0)
    x = 0.0
    y = 1.0  # x' (approach rate)
    s = s0
    z = 0.0
    fn = 0.0
    g = 0.0
    jn = 0.0
    for _ in range(int(MAX_TIME * steps)):
        y -= fn * h
        s += mass_ratio * g * h
        jn += fn * h
        x += y * dt
        z += s * dt
        fn = 0.0
        g = 0.0
        if x > 0.0:
            fn = 1.25 * x * math.sqrt(x) + damp * math.sqrt(math.sqrt(x)) * y
            if fn < 0.0:
                fn = 0.0
            k = 7.5 * kappa * math.sqrt(x)
            g = -k * z
            if abs(g) > fn:
                g = fn if g > 0.0 else -fn
                z = -g / k
        else:
            z = 0.0
        y -= fn * h
        s += mass_ratio * g * h
        jn += fn * h
        if x <= 0.0 and y < 0.0:
            break
    if jn <= 0.0:
        return 0.0, e_n
    return (s0 - s) / (mass_ratio * jn), e_n


#: The q of the first table node, where χ = φ/q takes its limit for q → 0 (the sticking
#: response is linear in the slip while the Coulomb cap binds only in a vanishing end of the
#: contact) [-].
Q_LIMIT = 1e-4


@njit
def _grid(rs, kappas, coefs, mass_ratio, steps, chi):
    for a in range(kappas.shape[0]):
        for b in range(coefs.shape[0]):
            for c in range(rs.shape[0]):
                if rs[c] >= 1.0:
                    chi[a, b, c] = 1.0  # q = ∞: sliding throughout
                    continue
                q = max(rs[c] / (1.0 - rs[c]), Q_LIMIT)
                chi[a, b, c] = oblique(q, kappas[a], coefs[b], mass_ratio, steps)[0] / min(q, 1.0)


def table(rs, kappas, restitutions, steps: float = TABLE_STEPS,
          mass_ratio: float = MASS_RATIO_SOLID):
    """χ = φ/min(q, 1), the tangential impulse over the rigid rule's, over a grid of
    (κ, e_n, r = q/(1 + q)) (see the module): it stays finite as q → 0 (at q = 0 its limit,
    taken at Q_LIMIT), so that interpolating it keeps the relative accuracy of small
    impulses, and it tends to 1 as q → ∞ (set at r = 1).

    Args:
        rs, kappas, restitutions: Grid nodes (1-D); each e_n sets the dashpot coefficient of
            :func:`hsgran.dem.single.dashpot_coefficient`.
        steps: Steps per unit of dimensionless time.
        mass_ratio: m*/m_t.

    Returns:
        χ of shape (κ, e_n, r).
    """
    from hsgran.dem.single import dashpot_coefficient

    rs = np.asarray(rs, dtype=float)
    kappas = np.asarray(kappas, dtype=float)
    coefs = np.array([dashpot_coefficient(float(e)) for e in restitutions])
    chi = np.zeros((kappas.size, coefs.size, rs.size))
    _grid(rs, kappas, coefs, float(mass_ratio), float(steps), chi)
    return chi
