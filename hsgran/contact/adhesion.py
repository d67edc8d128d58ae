"""Adhesion during recovery: Dunn's line force on the contact perimeter (MODEL §3.8).

Provenance: line force acting only in recovery, capture when it wins [P]/[YT]; the work integral
is **[OURS]** (medium confidence); the estimate of f0 from a work of adhesion is **[OURS]** (low
confidence) and is swappable: give ``adhesion_line_force`` directly to bypass it.
"""

from __future__ import annotations

import math

from hsgran._jit import njit
from hsgran.materials import P_F0, P_F0_COEF


@njit
def line_force(row, r_eff):
    """Adhesion line force f0 [N/m] of a pair for effective radius ``r_eff`` [m].

    Either the pair's direct value, or the JKR-matched estimate 0.4924 (E* R* Δγ²)^(1/3)
    (MODEL §3.8, [OURS]) whose R*-independent part the pair row stores.
    """
    return row[P_F0] + row[P_F0_COEF] * r_eff ** (1.0 / 3.0)


@njit
def adhesion_work(f0, a_max, d_r):
    """Work of the adhesion line force over the recovery stroke [J].

    Args:
        f0: Line force [N/m].
        a_max: Contact radius at maximum compression [m].
        d_r: Recovered (elastic) deformation δ_r [m].

    References:
        MODEL §3.8: W_A = ∫ 2π a f0 dx with a² = R′ x, = (4π/3) f0 a_max δ_r.
    """
    return (4.0 * math.pi / 3.0) * f0 * a_max * d_r
