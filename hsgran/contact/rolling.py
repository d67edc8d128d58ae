"""Rolling resistance inside a collision (MODEL §5.2).

**[OURS]**, low confidence: an angular impulse H = min(μ_r R* J_n, H_cap) against the rolling
part of the relative spin, capped so that it can at most stop the relative rolling (our reading
of the paper's critical value C′). It is applied after the normal model and before the
tangential model, so a stick outcome still leaves zero slip.
"""

from __future__ import annotations

from hsgran._jit import njit


@njit
def rolling_couple(mu_r, r_eff, j_n, roll_speed, inv_i_sum):
    """Magnitude of the rolling-resistance angular impulse H [N m s].

    Args:
        mu_r: Dimensionless rolling friction μ_r [-].
        r_eff: Effective radius R* [m].
        j_n: Normal impulse J_n [N s].
        roll_speed: |Δω_r|, rolling part of the relative angular velocity [rad/s].
        inv_i_sum: 1/I1 + 1/I2 [1/(kg m²)] (a wall contributes 0).

    Returns:
        H = min(μ_r R* J_n, |Δω_r| / (1/I1 + 1/I2)).
    """
    return min(mu_r * r_eff * j_n, roll_speed / inv_i_sum)
