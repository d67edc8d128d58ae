"""Silo discharge against Beverloo's law (docs/open-systems.md, "Silo discharge").

Glass beads (diameter d = 2 mm, e = 0.5, μ = 0.3 with each other and the steel walls) fill a
flat-bottomed cylindrical silo of diameter 2D and drain through a circular orifice of diameter
D in its floor; each bead that leaves below comes back at the top (a recirculating inflow), so
the bed keeps its height and the flow becomes steady. For each D the tool counts the exits in
windows of the steady part of the run (from ``--warmup`` on), converts them to a mass rate
W = (exits per second) × m_bead, measures the bed's bulk density (the beads' volume over a
cylinder away from the wall, the floor and the bed's top, in the last frame, both while it
drains and, for Beverloo's ρ_b, poured into the widest silo with its orifice closed) and fits

    W = C ρ_b √g (D − k d)^{5/2}

(Beverloo, Leniger & van de Velde 1961) by weighted least squares, printing C and k with their
standard errors (from the fit's covariance, scaled by the reduced χ²), the bulk density used
and each orifice's rate. The silo is narrow (D_silo/D = 2; Beverloo's law is usually checked
with D_silo > 2.5 D), so the walls are expected to lower C; the study is about the law's form.

Usage:
    .venv/bin/python tools/beverloo.py [--diameters 5,6,8,10,12,15,20] [--seconds 0.5]
        [--warmup 0.2] [--windows 6] [--bed 10] [--jobs 2]
"""

from __future__ import annotations

import argparse
import math
import time
from concurrent.futures import ProcessPoolExecutor

import numpy as np

#: Bead radius [m], and the densities the scene's materials have [kg/m³].
RADIUS = 0.001
RHO_GLASS = 2500.0
V_BEAD = 4.0 / 3.0 * math.pi * RADIUS ** 3  #: a bead's volume [m³]
G = 9.81  #: [m/s²]
#: Random loose fill before the beads fall: the fill's volume fraction (placement is random and
#: non-overlapping, hsgran.placement; far below its jamming limit, so it places at once).
FILL_FRACTION = 0.25
#: Packing fraction of the settled bed used to size it (the measured one is reported) [-].
BED_FRACTION = 0.6
#: Bulk density region: this many bead diameters clear of the wall, the floor and the bed's top.
CLEAR = 2.0
#: The recirculating inflow's rate is this many times the most the orifice can pass: a bed of
#: packing BED_FRACTION crossing its whole area at the free-fall speed √(g D) of an arch of
#: its span (Beverloo's rate is about 0.6 of that) [-]. The inflow must never hold the
#: discharge back: with one rate of 40,000 beads/s for every orifice, the D = 20 d silo
#: (~50,000/s) drained, and its rate fell until the run's end.
INFLOW_MARGIN = 2.0

SCENE = """
[scene]
name = "silo D = {dd} d"
duration = {seconds}
gravity = [0.0, 0.0, -9.81]
effects = ["gravity", "rotation", "friction"]
seed = {seed}
[output]
frame_interval = 0.01
[[contacts]]
between = ["glass", "glass"]
restitution = 0.5
sliding_friction = 0.3
[[contacts]]
between = ["glass", "steel"]
restitution = 0.5
sliding_friction = 0.3
[[walls]]
kind = "cylinder"
center = [0.0, 0.0, {half_height}]
axis = [0.0, 0.0, 1.0]
radius = {silo}
length = {height}
caps = false
material = "steel"
[[walls]]
kind = "plane"
point = [0.0, 0.0, 0.0]
normal = [0.0, 0.0, 1.0]
material = "steel"
hole = {{ shape = "circle", center = [0.0, 0.0, 0.0], radius = {orifice} }}
[[fill]]
count = {count}
material = "glass"
radius = {radius}
region = {{ lower = [{lo}, {lo}, {z0}], upper = [{hi}, {hi}, {z1}] }}
[[outlets]]
kind = "below"
point = [0.0, 0.0, {below}]
normal = [0.0, 0.0, 1.0]
[[inflow]]
recirculate = true
region = {{ lower = [{lo}, {lo}, {in0}], upper = [{hi}, {hi}, {in1}] }}
rate = {rate}
interval = 0.005
"""


def silo_scene(dd: float, bed: float, seconds: float, seed: int) -> tuple[str, dict]:
    """The scene text for an orifice of ``dd`` bead diameters and a bed ``bed`` diameters
    high, and its geometry (silo radius, bed height [m], bead count)."""
    d = 2.0 * RADIUS
    orifice = 0.5 * dd * d
    silo = dd * d  # the silo's radius: its diameter is 2D
    count = round(BED_FRACTION * math.pi * silo ** 2 * bed * d
                  / V_BEAD)
    half = silo / math.sqrt(2.0) - 1.05 * RADIUS  # a square inside the silo
    area = (2.0 * half) ** 2
    z0 = 2.0 * RADIUS
    z1 = z0 + count * 4.0 / 3.0 * math.pi * RADIUS ** 3 / (FILL_FRACTION * area)
    height = z1 + 20.0 * d
    rate = (INFLOW_MARGIN * BED_FRACTION / V_BEAD * math.pi / 4.0 * (2.0 * orifice) ** 2
            * math.sqrt(G * 2.0 * orifice))
    text = SCENE.format(dd=dd, seconds=seconds, seed=seed, half_height=0.5 * height,
                        rate=f"{rate:.1f}",
                        silo=silo, height=height, orifice=orifice, count=count, radius=RADIUS,
                        lo=-half, hi=half, z0=z0, z1=z1, below=-4.0 * d,
                        in0=bed * d + 4.0 * d, in1=bed * d + 8.0 * d)
    return text, {"silo": silo, "bed": bed * d, "count": count}


def closed(text: str) -> str:
    """The scene with its orifice closed, and neither outlet nor inflow: a poured bed."""
    text = text.split("[[outlets]]")[0]
    return "\n".join(line for line in text.splitlines() if not line.startswith("hole ="))


def run_one(args) -> dict:
    """Run one orifice (or, ``shut``, the same silo closed); return its exit times, the last
    frame's positions and the run's figures."""
    from hsgran.engine import Simulation, SimulationError
    from hsgran.events.kinds import EV_EXIT
    from hsgran.scene import parse_scene

    dd, bed, seconds, seed, shut = args
    text, geo = silo_scene(dd, bed, seconds, seed)
    if shut:
        text = closed(text)
    scene = parse_scene(text)
    sim = Simulation(scene, log_events=True)
    exits = []
    last = {}

    class Keep:
        def on_events(self, b):
            exits.append(b.time[b.kind == EV_EXIT])

        def on_frames(self, b):
            last["position"] = b.position[-1]
            last["present"] = b.motion_state[-1] >= 0

    wall = time.perf_counter()
    guard = None
    try:
        events = sim.run(observers=[Keep()]).events
    except SimulationError as err:  # the collapse guard: reported, not hidden
        guard, events = (sim.time, str(err)), {}
    return {"dd": dd, "shut": shut, "geo": geo,
            "exits": np.concatenate(exits) if exits else np.zeros(0),
            "position": last["position"], "present": last["present"],
            "wall": time.perf_counter() - wall, "events": events, "guard": guard,
            "dissipated": sim.dissipated_energy()}


def bulk_fraction(position, present, silo, bed) -> float:
    """Volume fraction of beads whose centres lie in a cylinder CLEAR diameters clear of the
    wall, the floor and the bed's top (its 95th height percentile) [-]."""
    d = 2.0 * RADIUS
    x = position[present]
    top = np.percentile(x[:, 2], 95.0)
    r_in = silo - CLEAR * d
    z_lo, z_hi = CLEAR * d, top - CLEAR * d
    inside = (np.hypot(x[:, 0], x[:, 1]) < r_in) & (x[:, 2] > z_lo) & (x[:, 2] < z_hi)
    volume = math.pi * r_in ** 2 * max(z_hi - z_lo, 1e-12)
    return inside.sum() * 4.0 / 3.0 * math.pi * RADIUS ** 3 / volume


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--diameters", default="5,6,8,10,12,15,20",
                    help="orifice diameters in bead diameters, comma-separated")
    ap.add_argument("--seconds", type=float, default=0.5, help="simulated time per run [s]")
    ap.add_argument("--warmup", type=float, default=0.2,
                    help="exits before this time [s] are not counted (the bed forms)")
    ap.add_argument("--windows", type=int, default=6, help="windows of the steady part")
    ap.add_argument("--bed", type=float, default=10.0, help="bed height [bead diameters]")
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--jobs", type=int, default=2)
    a = ap.parse_args()
    dds = [float(s) for s in a.diameters.split(",")]
    # the poured bed's bulk density: the widest silo, closed, from the same fill
    jobs = [(max(dds), a.bed, a.seconds, a.seed, True)]
    jobs += [(dd, a.bed, a.seconds, a.seed, False) for dd in sorted(dds, reverse=True)]
    with ProcessPoolExecutor(max_workers=a.jobs) as pool:
        results = list(pool.map(run_one, jobs))
    poured = results.pop(0)
    results.sort(key=lambda r: r["dd"])
    d = 2.0 * RADIUS
    m_bead = RHO_GLASS * 4.0 / 3.0 * math.pi * RADIUS ** 3
    edges = np.linspace(a.warmup, a.seconds, a.windows + 1)
    rows = []
    print(f"{'D/d':>5} {'beads':>6} {'exits':>6} {'W [g/s]':>9} {'±':>7} {'phi_b':>6} "
          f"{'absent':>6} {'wall [s]':>9}  guard")
    for r in results:
        counts, _ = np.histogram(r["exits"], edges)
        rates = counts / np.diff(edges) * m_bead
        w, dw = rates.mean(), rates.std(ddof=1) / math.sqrt(len(rates))
        phi = bulk_fraction(r["position"], r["present"], r["geo"]["silo"], r["geo"]["bed"])
        rows.append((r["dd"], w, dw, phi))
        print(f"{r['dd']:5.1f} {r['geo']['count']:6d} {r['exits'].size:6d} {1e3 * w:9.3f} "
              f"{1e3 * dw:7.3f} {phi:6.3f} {int((~r['present']).sum()):6d} {r['wall']:9.1f}  "
              + (f"at {r['guard'][0]:.4f} s: {r['guard'][1]}" if r["guard"] else
                 f"none (ran to {a.seconds} s)"))
    # a run the collapse guard stopped is reported above and left out of the fit
    rows = [row for row, r in zip(rows, results, strict=True) if not r["guard"]]
    dd, w, dw, phi = (np.array(c) for c in zip(*rows, strict=True))
    phi_b = bulk_fraction(poured["position"], poured["present"], poured["geo"]["silo"],
                          poured["geo"]["bed"])
    if poured["guard"]:
        print(f"the closed pour stopped at the collapse guard at {poured['guard'][0]:.4f} s; "
              "its bed is measured there")
    rho_b = RHO_GLASS * phi_b
    from scipy.optimize import curve_fit

    def law(dd_, c, k):
        return c * rho_b * math.sqrt(G) * np.clip(dd_ * d - k * d, 0.0, None) ** 2.5

    (c, k), cov = curve_fit(law, dd, w, p0=(0.58, 1.5), sigma=np.maximum(dw, 1e-12 * w.max()),
                            absolute_sigma=False)
    ec, ek = np.sqrt(np.diag(cov))
    print(f"bulk density rho_b = {rho_b:.0f} kg/m^3: phi = {phi_b:.3f} of glass "
          f"({RHO_GLASS:.0f}) in the poured bed of the D = {poured['dd']:g} d silo, closed, at "
          f"{a.seconds} s ({poured['wall']:.0f} s of wall time); while draining, phi_b above "
          f"is {phi.min():.3f}-{phi.max():.3f}")
    print(f"Beverloo fit: C = {c:.3f} ± {ec:.3f}, k = {k:.2f} ± {ek:.2f} "
          f"({len(dd)} orifices, D = {dd.min():g}-{dd.max():g} d)")
    print("residuals [%]: " + ", ".join(f"{100 * (wi / law(di, c, k) - 1):+.1f}"
                                       for di, wi in zip(dd, w, strict=True)))


if __name__ == "__main__":
    main()
