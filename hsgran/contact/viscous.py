"""Viscoelastic damping: the restitution of viscoelastic spheres below the yield speed (layer 2;
the ``viscoelastic_damping`` effect, beyond the paper: docs/model.md §3.11).

In the paper's model (MODEL §3, §9) an impact below the yield speed is perfectly elastic. Real
spheres lose a few per cent of their normal speed there, through the viscosity of their bulk.
Brilliantov et al. (1996) derived the force of viscoelastic spheres (Hertz plus the dissipative
term of Kuwabara & Kono 1987) with one material constant, the dissipative constant A [s]
(``dissipative_constant`` of a material; a pair takes the compliance-weighted mean, [OURS]).
Its restitution depends on the impact speed v0 only through X = β v0^(1/5) (Ramírez et al.
1999; Schwager & Pöschel 2008):

    β = (3/2) A ρ^(2/5),   ρ = (4/3) E* R*^(1/2) / m*,
    e_visc = 1 − 1.15344 X + 0.79826 X² − … (the leading terms of their series).

The series converges slowly and not at all for X ≳ 0.5, so e_visc(X) is read from a table of
the integrated force law (``hsgran/data/derived_viscoelastic_restitution.csv``, made by
``tools/make_tables.py`` with :mod:`hsgran.dem.viscoelastic`), which agrees with the series'
first two terms (tests/dem/test_viscoelastic.py). Above X = 100 (e_visc < 6e-4) it is held at
the last value.

With the staged model, e_n = e_visc × e_staged [OURS]: the viscous loss takes the same fraction
of what the staged model returns, so e_n is continuous at the yield speed (e_staged = 1 there)
and stays the paper's above it but for that factor. A prescribed restitution bypasses both
(MODEL §3.9).
"""

from __future__ import annotations

import math

import numpy as np

from hsgran._jit import njit
from hsgran.errors import InputError
from hsgran.refdata import read_csv

#: The table's file in hsgran/data.
TABLE_FILE = "derived_viscoelastic_restitution.csv"
#: The table is uniform in √X from 0 to √X_MAX = 10 (X = 100) with this many nodes: linear
#: interpolation in √X is within 1e-5 of e (tests/contact/test_viscous.py).
SQRT_X_NODES = np.linspace(0.0, 10.0, 2001)


def _load():
    """e_visc at SQRT_X_NODES, or NaNs and why (a broken installation, or changed nodes)."""
    try:
        t = read_csv(TABLE_FILE)
        u = np.asarray(t["sqrt_X"], dtype=float)
        if u.shape != SQRT_X_NODES.shape or not np.allclose(u, SQRT_X_NODES, rtol=0, atol=1e-9):
            raise RuntimeError(f"{TABLE_FILE}: its nodes are not those of "
                               "hsgran.contact.viscous; run tools/make_tables.py")
        return np.ascontiguousarray(t["e_n"], dtype=float), ""
    except (OSError, RuntimeError, KeyError, InputError) as exc:
        return np.full(SQRT_X_NODES.size, np.nan), str(exc)


E_VISC, TABLE_ERROR = _load()
_DU = SQRT_X_NODES[1] - SQRT_X_NODES[0]


def check_table() -> None:
    """Raise if the table could not be loaded (called when a scene turns the effect on)."""
    if TABLE_ERROR:
        raise RuntimeError(f"viscoelastic_damping: {TABLE_ERROR}")


@njit
def damping_number(v0, m_eff, r_eff, e_star, a_diss):
    """X = β v0^(1/5) (see the module) [-] for impact speed v0 [m/s], m* [kg], R* [m], E* [Pa]
    and the dissipative constant A [s]."""
    rho = (4.0 / 3.0) * e_star * math.sqrt(r_eff) / m_eff
    return 1.5 * a_diss * rho ** 0.4 * v0 ** 0.2


@njit
def restitution_of(x_damp):
    """e_visc(X) from the table (linear in √X; held beyond its end) [-]."""
    u = math.sqrt(x_damp) / _DU
    n = E_VISC.shape[0]
    if u >= n - 1:
        return E_VISC[n - 1]
    i = int(u)
    w = u - i
    return (1.0 - w) * E_VISC[i] + w * E_VISC[i + 1]


def damping_number_for(e: float) -> float:
    """The damping number X at which e_visc(X) = e [-]: the inverse of :func:`restitution_of`,
    exact for its interpolation (e_visc falls monotonically along the table, and both are
    linear in √X between its nodes).

    Raises:
        RuntimeError: the table could not be loaded (:func:`check_table`).
        ValueError: ``e`` is not in [e_visc(X_MAX), 1] (X_MAX = 100, the table's end).
    """
    check_table()
    if not E_VISC[-1] <= e <= 1.0:  # (a NaN too)
        raise ValueError(f"restitution {e!r}: viscoelastic damping gives e in "
                         f"[{E_VISC[-1]:.3g}, 1]")
    if e == 1.0:
        return 0.0  # (exactly: interpolation from the node next to it leaves rounding)
    return float(np.interp(e, E_VISC[::-1], SQRT_X_NODES[::-1])) ** 2


def dissipative_constant_for(e: float, v0: float, m_eff: float, r_eff: float,
                             e_star: float) -> float:
    """The dissipative constant A [s] that gives a pair the viscous restitution ``e`` [-] at
    normal impact speed ``v0`` [m/s] (m* [kg], R* [m], E* [Pa] of the pair): X is linear in
    A (see the module), so A = X(e) / (X for A = 1 s). For choosing a material's
    ``dissipative_constant`` from a measured restitution (docs/model.md §3.11); 0 for e = 1.
    Raises as :func:`damping_number_for`."""
    return damping_number_for(e) / damping_number(v0, m_eff, r_eff, e_star, 1.0)


@njit
def viscoelastic_restitution(v0, m_eff, r_eff, e_star, a_diss):
    """Normal restitution of viscoelastic spheres at impact speed v0 (docs/model.md §3.11) [-].

    Args:
        v0: Normal impact speed [m/s].
        m_eff, r_eff, e_star: m* [kg], R* [m], E* [Pa].
        a_diss: Dissipative constant A of the pair [s].
    """
    return restitution_of(damping_number(v0, m_eff, r_eff, e_star, a_diss))
