"""Tangential model: sliding or rolling decided from the normal impulse (MODEL §4).

Rigid-body tangential model [P]: the slip keeps its direction during the impact and only
shrinks; Coulomb friction bounds the tangential impulse. Formulas [LIT] (Walton's model with
zero tangential restitution, MODEL §4.4).
"""

from __future__ import annotations

from hsgran._jit import njit

REGIME_NONE = 0  #: no tangential impulse (no slip, or no friction)
REGIME_ROLLING = 1  #: slip brought to zero: the bodies leave rolling (stick)
REGIME_SLIDING = 2  #: Coulomb limit reached: the bodies leave sliding
REGIME_NAMES = ("none", "rolling", "sliding")


@njit
def tangential_impulse(slip, m_t, mu_s, j_n):
    """Magnitude of the friction impulse and the regime.

    Args:
        slip: |ΔV_t|, the contact-point slip speed before the impulse [m/s].
        m_t: Tangential effective mass m_t* [kg] (2/7 m* for solid spheres).
        mu_s: Sliding friction coefficient [-].
        j_n: Normal impulse J_n [N s].

    Returns:
        (J_t [N s], regime): J_stick = m_t* |ΔV_t| if it is within the Coulomb limit μ_s J_n
        (rolling), else μ_s J_n (sliding).

    References:
        MODEL §4.2.
    """
    j_stick = m_t * slip
    j_lim = mu_s * j_n
    if j_stick <= j_lim:
        return j_stick, REGIME_ROLLING
    return j_lim, REGIME_SLIDING
