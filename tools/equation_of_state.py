"""The equation of state and the collision frequency of an elastic hard-sphere gas, measured
from the events, against Carnahan–Starling and Enskog (issue 29; docs/observables.md).

For each packing fraction φ: N equal glass spheres (radius 1 mm) start on an FCC lattice in a
fully periodic cube with Gaussian velocities of zero total momentum; no effects, so every
collision is elastic (e_n = 1). After ``--equilibrate`` collisions per sphere, the run sums the
impulse moment over frame intervals (``[output] observables``) and prints

- Z = P V / (N k T) = 1 + tr Σ r_ij ⊗ J_ij / (3 τ N k T), N k T = (2/3) E_kin (the kinetic
  energy is exactly conserved), against Z_CS = (1 + φ + φ² − φ³) / (1 − φ)³;
- the collision frequency per sphere, 2 N_coll / (N τ), against Enskog's
  ω_E = 4 n σ² g(σ) √(π k T / m) with the Carnahan–Starling contact value
  g(σ) = (1 − φ/2) / (1 − φ)³,

each with its standard error from block averages. Usage::

    .venv/bin/python tools/equation_of_state.py            # φ = 0.1 0.2 0.3 0.4, N = 2048
    .venv/bin/python tools/equation_of_state.py --phi 0.3 --cells 4 --collisions 2000
"""

from __future__ import annotations

import argparse
import math
import time

import numpy as np

from hsgran.engine import Simulation
from hsgran.observables import mean_and_error
from hsgran.scene import parse_scene

RADIUS = 1e-3  #: [m]
FCC = np.array([[0, 0, 0], [0.5, 0.5, 0], [0.5, 0, 0.5], [0, 0.5, 0.5]])
FRAMES = 200  #: intervals of the measurement (20 blocks of 10)


def carnahan_starling(phi: float) -> float:
    """Compressibility factor Z of hard spheres (Carnahan & Starling, J. Chem. Phys. 51, 635
    (1969))."""
    return (1 + phi + phi**2 - phi**3) / (1 - phi) ** 3


def enskog_frequency(phi: float, kt: float, mass: float, sigma: float) -> float:
    """Collisions per sphere per second of a hard-sphere gas in Enskog's theory with the
    Carnahan–Starling contact value (Chapman & Cowling, ch. 16) [1/s]."""
    g = (1 - phi / 2) / (1 - phi) ** 3
    n = 6 * phi / (math.pi * sigma**3)
    return 4 * n * sigma**2 * g * math.sqrt(math.pi * kt / mass)


def gas_scene(phi: float, cells: int, duration: float, frame: float, seed: int) -> str:
    """Scene text: 4 cells³ spheres on an FCC lattice at packing fraction ``phi``."""
    n = 4 * cells**3
    box = (n * 4 / 3 * math.pi * RADIUS**3 / phi) ** (1 / 3)
    a = box / cells
    grid = np.array([(i, j, k) for i in range(cells) for j in range(cells)
                     for k in range(cells)], dtype=float)
    pos = ((grid[:, None, :] + FCC[None]) * a).reshape(-1, 3) + 0.25 * a
    rng = np.random.default_rng(seed)
    vel = rng.normal(size=(n, 3))
    vel -= vel.mean(axis=0)
    spheres = "\n".join(
        f"[[particles]]\nmaterial = \"glass\"\nradius = {RADIUS}\n"
        f"position = [{p[0]:.17g}, {p[1]:.17g}, {p[2]:.17g}]\n"
        f"velocity = [{v[0]:.17g}, {v[1]:.17g}, {v[2]:.17g}]"
        for p, v in zip(pos, vel, strict=True))
    return (f"[scene]\nname = \"elastic gas at phi = {phi}\"\nduration = {duration!r}\n"
            f"effects = []\nperiodic = [true, true, true]\nseed = {seed}\n"
            f"[output]\nframe_interval = {frame!r}\nobservables = true\n"
            f"[[walls]]\nkind = \"box\"\nlower = [0, 0, 0]\nupper = [{box!r}, {box!r}, {box!r}]\n"
            + spheres + "\n")


class _Keep:
    def __init__(self):
        self.blocks = []

    def on_frames(self, block):
        self.blocks.append(block)


def measure(phi: float, cells: int, collisions: float, equilibrate: float, seed: int) -> dict:
    """Run one gas and return Z and ω with their errors and the theory's values."""
    sigma = 2 * RADIUS
    mass_guess = 2500.0 * 4 / 3 * math.pi * RADIUS**3  # only to size the run
    omega_guess = enskog_frequency(phi, mass_guess / 3, mass_guess, sigma)  # ⟨v²⟩ = 3 kT/m = 3
    t_eq = equilibrate / omega_guess
    t_run = collisions / omega_guess
    frame = t_run / FRAMES
    duration = t_eq + t_run
    scene = parse_scene(gas_scene(phi, cells, duration, frame, seed))
    sim = Simulation(scene)
    keep = _Keep()
    wall = time.perf_counter()
    sim.run(duration, observers=[keep])
    wall = time.perf_counter() - wall
    t = np.concatenate([b.time for b in keep.blocks])
    moment = np.concatenate([b.impulse_moment for b in keep.blocks])
    counts = np.concatenate([b.collisions for b in keep.blocks])
    vel = np.concatenate([b.velocity for b in keep.blocks])
    mass = float(scene.mass()[0])
    n = scene.n
    kinetic = 0.5 * mass * np.einsum("fnk,fnk->f", vel, vel)
    first = int(np.searchsorted(t, t_eq - 0.5 * frame)) + 1  # intervals after equilibration
    tau = np.diff(t)[first - 1:]
    nkt = 2.0 / 3.0 * kinetic[first:]
    z = 1.0 + np.trace(moment[first:], axis1=1, axis2=2) / (3.0 * tau * nkt)
    omega = 2.0 * counts[first:, 0] / (n * tau)
    kt = float(nkt.mean()) / n
    z_mean, z_err = mean_and_error(z, 20)
    w_mean, w_err = mean_and_error(omega, 20)
    return dict(phi=phi, n=n, z=z_mean, z_err=z_err, z_cs=carnahan_starling(phi),
                omega=w_mean, omega_err=w_err, omega_e=enskog_frequency(phi, kt, mass, sigma),
                collisions=int(counts[first:, 0].sum()), wall=wall,
                drift=float(abs(kinetic[-1] / kinetic[0] - 1)))


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--phi", type=float, nargs="+", default=[0.1, 0.2, 0.3, 0.4])
    ap.add_argument("--cells", type=int, default=8, help="FCC cells per edge (N = 4 cells³)")
    ap.add_argument("--collisions", type=float, default=4000.0,
                    help="collisions per sphere measured")
    ap.add_argument("--equilibrate", type=float, default=50.0,
                    help="collisions per sphere before measuring")
    ap.add_argument("--seed", type=int, default=1)
    args = ap.parse_args()
    print(f"{'phi':>5} {'N':>6} {'Z':>9} {'±':>7} {'Z_CS':>8} {'dev %':>7} "
          f"{'omega 1/s':>10} {'±':>6} {'Enskog':>9} {'dev %':>7} {'collisions':>11} "
          f"{'wall s':>7} {'|dE/E|':>8}")
    for phi in args.phi:
        r = measure(phi, args.cells, args.collisions, args.equilibrate, args.seed)
        print(f"{phi:5.2f} {r['n']:6d} {r['z']:9.5f} {r['z_err']:7.5f} {r['z_cs']:8.5f} "
              f"{100 * (r['z'] / r['z_cs'] - 1):+7.3f} {r['omega']:10.2f} {r['omega_err']:6.2f} "
              f"{r['omega_e']:9.2f} {100 * (r['omega'] / r['omega_e'] - 1):+7.3f} "
              f"{r['collisions']:11.4g} {r['wall']:7.1f} {r['drift']:8.1e}", flush=True)


if __name__ == "__main__":
    main()
