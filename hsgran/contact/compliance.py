"""Tangential compliance: the friction impulse of an elastic oblique impact (layer 2; the
``tangential_compliance`` effect, beyond the paper: docs/model.md §4.5).

The paper's tangential model (MODEL §4) is rigid: the slip stops (rolling) or the Coulomb bound
is reached (sliding). Real contacts are tangentially elastic: below the critical angle the
contact stores tangential strain and gives it back, so the slip can reverse (tangential recoil,
e_t above 5/7 near normal incidence) or not quite stop (e_t below 5/7 near the critical angle).
Maw, Barber & Fawcett (1976, 1981) showed that for elastic spheres the outcome depends only on
a stiffness ratio and the incidence; here it is the no-slip Mindlin spring with a Coulomb cap
that DEM codes integrate (Di Renzo & Di Maio 2004), solved once in dimensionless form by
:mod:`hsgran.dem.mindlin` and tabulated (``hsgran/data/tangential_compliance.npz``, made by
``tools/make_tables.py``). Per collision the effect costs one table look-up:

    J_t = χ(κ, e_n, q) min(q, 1) μ J_n,   q = m_t |u0| / (μ J_n),

with κ = G*/E* of the pair (P_G_RATIO), e_n the collision's normal restitution, u0 the slip
before, m_t = (2/7) m* (MODEL §4.1). The rigid rule of MODEL §4.2 is χ = 1. χ is the ratio of
the elastic contact's impulse to the rigid one: above 1 where the slip reverses (recoil), below
where it does not stop; negative for the recoil at near-normal incidence. For e_n < 1 the
table's normal force is Hertz with a restitution dashpot of the same e_n (Tsuji et al. 1992),
the spring undamped, also where the staged model gave that e_n: the shape of the normal force
history of a plastic impact is not the dashpot's, an approximation of ours [OURS]. The
dashpot's force at first contact makes the contact stick at first even at grazing incidence, so
for e_n < 1, χ approaches 1 only as q → ∞ (at e_n = 0.5,
1 − χ is 0.016 at q = 1 and 0.003 at q = 5); for e_n = 1 it is 1 for q ≥ 1 (gross sliding
from first contact to the end).

Accuracy of the interpolation (tests/contact/test_compliance.py, against direct integration at
500 random κ, e_n, q off the nodes): χ within 0.0165, so e_t of a wall impact within
(2/7) × 0.0165 = 0.005 (φ has kinks where the number of stick–slip switches changes, which
fall between nodes). κ and e_n outside the table are clamped to its range (κ of real solids,
ν in [−1, 0.5), is inside it; e_n below 0.02 takes the value at 0.02).
"""

from __future__ import annotations

import numpy as np

from hsgran._jit import njit
from hsgran.errors import InputError
from hsgran.refdata import data_path

#: Table nodes of r = q/(1 + q) in [0, 1] (q from 0 to ∞; r = 1/2 at the rigid rule's kink
#: q = 1; χ = 1 at r = 1).
R_NODES = np.linspace(0.0, 1.0, 101)
#: Table nodes of κ = G*/E*: 1/6 (ν = 0.5) to 1/3 (ν = −1); κ of a pair is a weighted mean of
#: its materials' (1 − ν)/(2(2 − ν)), so every pair of real solids is inside.
KAPPA_NODES = np.linspace(1.0 / 6.0, 1.0 / 3.0, 11)
#: Table nodes of e_n: dense below 0.2, where a strong dashpot makes ψ change fast.
E_NODES = np.concatenate([np.linspace(0.02, 0.2, 37), np.linspace(0.22, 1.0, 40)])
#: The table's file in hsgran/data.
TABLE_FILE = "tangential_compliance.npz"


def load_table() -> np.ndarray:
    """χ of shape (κ, e_n, r) from the shipped file, checked against the nodes above."""
    with np.load(data_path(TABLE_FILE)) as f:
        for name, nodes in (("r", R_NODES), ("kappa", KAPPA_NODES), ("e_n", E_NODES)):
            if f[name].shape != nodes.shape or not np.allclose(f[name], nodes, rtol=0,
                                                               atol=1e-12):
                raise RuntimeError(f"{TABLE_FILE}: its {name} nodes are not those of "
                                   "hsgran.contact.compliance; run tools/make_compliance_table.py")
        return np.ascontiguousarray(f["chi"], dtype=np.float64)


def _load_or_nan():
    """The table, or NaN of its shape and why (a broken installation, or the nodes changed and
    tools/make_compliance_table.py has not been run: it imports this module)."""
    try:
        return load_table(), ""
    except (OSError, RuntimeError, KeyError, InputError) as exc:
        return np.full((KAPPA_NODES.size, E_NODES.size, R_NODES.size), np.nan), str(exc)


CHI, TABLE_ERROR = _load_or_nan()


def check_table() -> None:
    """Raise if the table could not be loaded (called when a scene turns the effect on)."""
    if TABLE_ERROR:
        raise RuntimeError(f"tangential_compliance: {TABLE_ERROR}")
_R_STEP = R_NODES[1] - R_NODES[0]
_K0 = KAPPA_NODES[0]
_K_STEP = KAPPA_NODES[1] - KAPPA_NODES[0]


@njit(inline="always")
def _cell(x, x0, step, n):
    """Index i of the cell [x_i, x_i+1] of a uniform grid holding x (clamped), and the weight
    of x_i+1."""
    u = (x - x0) / step
    if u <= 0.0:
        return 0, 0.0
    if u >= n - 1:
        return n - 2, 1.0
    i = int(u)
    return i, u - i


@njit
def chi(kappa, e_n, q):
    """χ(κ, e_n, q) by trilinear interpolation of the table in (κ, e_n, q/(1 + q)), clamped
    to its range [-]."""
    nk, ne, nq = CHI.shape
    ik, wk = _cell(kappa, _K0, _K_STEP, nk)
    iq, wq = _cell(q / (1.0 + q), 0.0, _R_STEP, nq)
    if e_n <= E_NODES[0]:
        ie, we = 0, 0.0
    elif e_n >= E_NODES[ne - 1]:
        ie, we = ne - 2, 1.0
    else:
        ie = np.searchsorted(E_NODES, e_n) - 1
        we = (e_n - E_NODES[ie]) / (E_NODES[ie + 1] - E_NODES[ie])
    out = 0.0
    for a in range(2):
        fa = wk if a else 1.0 - wk
        for b in range(2):
            fb = we if b else 1.0 - we
            for c in range(2):
                fc = wq if c else 1.0 - wq
                out += fa * fb * fc * CHI[ik + a, ie + b, iq + c]
    return out


@njit
def compliant_impulse(slip, m_t, mu_s, j_n, kappa, e_n):
    """Friction impulse of an elastic contact (see the module).

    Args:
        slip: |ΔV_t|, the slip speed before [m/s].
        m_t: Tangential effective mass m_t* [kg].
        mu_s: Sliding friction μ_s [-].
        j_n: Normal impulse J_n [N s].
        kappa: G*/E* of the pair [-].
        e_n: Normal restitution of the collision [-].

    Returns:
        (J_t [N s] along −(slip direction), sliding): ``sliding`` where the rigid rule would
        slide (q ≥ 1, MODEL §4.2).
    """
    j_lim = mu_s * j_n
    j_stick = m_t * slip
    if j_lim <= 0.0:
        return 0.0, True
    if j_stick >= j_lim:
        return chi(kappa, e_n, j_stick / j_lim) * j_lim, True
    return chi(kappa, e_n, j_stick / j_lim) * j_stick, False
