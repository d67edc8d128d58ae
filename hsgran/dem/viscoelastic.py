"""The restitution of viscoelastic spheres, integrated in dimensionless form: the table behind
the ``viscoelastic_damping`` effect (layer 5; compiled kernels).

Brilliantov, Spahn, Hertzsch & Pöschel (1996) derived the normal force of viscoelastic spheres,

    F_n = (4/3) E* R*^(1/2) (δ^(3/2) + (3/2) A δ^(1/2) dδ/dt),

the Hertz force with the dissipative term of Kuwabara & Kono (1987); A [s] is a material
constant (docs/model.md §3.11). Scaled as in :mod:`hsgran.dem.mindlin` (δ0, t0 = δ0/v0) it is

    x'' = −(5/4) (x^(3/2) + (3/2) γ x^(1/2) x'),   γ = (2/3) (4/5)^(2/5) X,

with X = β v0^(1/5), β = (3/2) A ρ^(2/5), ρ = (4/3) E* R*^(1/2)/m* (Ramírez et al. 1999): the
restitution depends on A, the materials and v0 only through X. The force is cut at zero (a
viscoelastic contact cannot pull; its surfaces part after the force has vanished, the "delayed
recovery" of Schwager & Pöschel 2008), and e_n is the speed when it vanishes. Schwager & Pöschel
expand e_n(X) in a series whose leading terms are 1 − C1 X + C2 X² (C1 = 1.15344,
C2 = 0.79826, Ramírez et al. 1999); tests/dem/test_viscoelastic.py checks the integration
against them.
"""

from __future__ import annotations

import math

import numpy as np

from hsgran._jit import njit

#: Steps per unit of dimensionless time: e_n to ~1e-9 (second order; the force's cut at zero
#: is met at a step's end, an error of order dt² in speed as the force vanishes linearly).
STEPS = 20000.0
#: Longest integration, in units of t0.
MAX_TIME = 200.0
#: X of γ: γ = GAMMA_PER_X · X.
GAMMA_PER_X = (2.0 / 3.0) * 0.8 ** 0.4


@njit
def damped_hertz_restitution(coef, gamma, steps):
    """e_n of the dimensionless damped Hertz contact, x'' = −f_n with
    f_n = (5/4) x^(3/2) + c (15/8)^(1/2) x^(1/4) x' + (15/8) γ x^(1/2) x' cut at zero: the
    restitution dashpot of :func:`hsgran.dem.law.dashpot_force` (coefficient c) and the
    viscoelastic force (γ, see the module), in the units of :mod:`hsgran.dem.mindlin`. Once the
    force has vanished while the surfaces part it stays zero (both damping terms fall off
    more slowly than the elastic one), so that speed is e_n."""
    tsuji = coef * math.sqrt(15.0 / 8.0)
    kk = 1.875 * gamma
    dt = 1.0 / steps
    h = 0.5 * dt
    x = 0.0
    y = 1.0  # x', the approach rate
    fn = 0.0
    for _ in range(int(MAX_TIME * steps)):
        y -= fn * h
        x += y * dt
        fn = 0.0
        if x > 0.0:
            rx = math.sqrt(x)
            fn = 1.25 * x * rx + (tsuji * math.sqrt(rx) + kk * rx) * y
            if fn < 0.0:
                fn = 0.0
        y -= fn * h
        if y < 0.0 and fn == 0.0:
            break
    return max(-y, 0.0)


@njit
def restitution(x_damp, steps):
    """e_n of the dimensionless viscoelastic Hertz contact with damping X = β v0^(1/5)."""
    return damped_hertz_restitution(0.0, GAMMA_PER_X * x_damp, steps)


@njit
def _grid(xs, steps, out):
    for k in range(xs.shape[0]):
        out[k] = restitution(xs[k], steps)


def table(xs, steps: float = STEPS) -> np.ndarray:
    """e_n at each X of ``xs``."""
    xs = np.asarray(xs, dtype=float)
    out = np.zeros(xs.size)
    _grid(xs, float(steps), out)
    return out
