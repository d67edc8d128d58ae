"""Silo discharge against Beverloo's law (docs/open-systems.md, "Silo discharge").

Glass beads (diameter d = 2 mm, e = 0.5, μ = 0.3 with each other and the steel walls) fill a
flat-bottomed cylindrical silo of diameter 2D and drain through a circular orifice of diameter
D in its floor; each bead that leaves below comes back at the top (a recirculating inflow), so
the bed keeps its height and the flow becomes steady. For each D the tool counts the exits in
windows of the steady part of the run (from ``--warmup`` on), converts them to a mass rate
W = (exits per second) × m_bead, measures the bed's bulk density (the beads' volume over a
cylinder away from the wall, the floor and the bed's top, in the last frame, both while it
drains and, for Beverloo's ρ_b, poured into one silo, ``--poured``, with its orifice closed) and
fits

    W = C ρ_b √g (D − k d)^{5/2}

(Beverloo, Leniger & van de Velde 1961) by weighted least squares, printing C and k with their
standard errors (from the fit's covariance, scaled by the reduced χ²), the bulk density used
and each orifice's rate. The silo is narrow (D_silo/D = 2; Beverloo's law is usually checked
with D_silo > 2.5 D), so the walls are expected to lower C; the study is about the law's form.

The bed is at least ``--bed`` bead diameters high and at least ``--bed-per-orifice`` orifice
diameters (Beverloo's rate does not depend on the bed's height once the bed is higher than
about the orifice is wide, Nedderman 1992, ch. 10): 10 d for D ≤ 10 d, D from there on. Each
orifice up to ``--seeds-upto`` bead diameters runs with each of ``--seeds`` (the narrow ones,
where beads arch over the orifice, differ most between fills); its rate is the mean over the
seeds, and its error the larger of the seeds' spread (standard error of their mean) and the
windows' error combined over the seeds.

Usage:
    .venv/bin/python tools/beverloo.py [--diameters 5,6,8,10,12,15,20] [--seconds 0.5]
        [--warmup 0.2] [--windows 6] [--bed 10] [--bed-per-orifice 1] [--seeds 1,2,3]
        [--seeds-upto 6] [--poured 10] [--jobs 2]
"""

from __future__ import annotations

import argparse
import math
import time
from concurrent.futures import ProcessPoolExecutor, as_completed

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


def bed_height(dd: float, bed: float, per_orifice: float) -> float:
    """The bed's height [bead diameters] for an orifice of ``dd`` bead diameters: ``bed`` or
    ``per_orifice`` × ``dd``, the higher."""
    return max(bed, per_orifice * dd)


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
    return {"dd": dd, "seed": seed, "shut": shut, "geo": geo,
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
    return inside.sum() * V_BEAD / volume


def seed_rate(r: dict, edges, m_bead: float) -> tuple[float, float, float]:
    """One run's mass rate [kg/s]: the mean over the windows ``edges``, its standard error,
    and the drift (the later half of the windows' rate over the earlier half's, − 1) [-]."""
    counts, _ = np.histogram(r["exits"], edges)
    rates = counts / np.diff(edges) * m_bead
    half = len(rates) // 2
    drift = rates[half:].mean() / max(rates[:half].mean(), 1e-300) - 1.0
    return rates.mean(), rates.std(ddof=1) / math.sqrt(len(rates)), drift


def combine(rates: list[float], errors: list[float]) -> tuple[float, float]:
    """The mean of one orifice's per-seed rates and its error: the larger of the seeds'
    standard error of the mean and the windows' errors combined (√Σσ²/n)."""
    n = len(rates)
    mean = float(np.mean(rates))
    windows = math.sqrt(sum(e * e for e in errors)) / n
    spread = float(np.std(rates, ddof=1)) / math.sqrt(n) if n > 1 else 0.0
    return mean, max(windows, spread)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--diameters", default="5,6,8,10,12,15,20",
                    help="orifice diameters in bead diameters, comma-separated")
    ap.add_argument("--seconds", type=float, default=0.5, help="simulated time per run [s]")
    ap.add_argument("--warmup", type=float, default=0.2,
                    help="exits before this time [s] are not counted (the bed forms)")
    ap.add_argument("--windows", type=int, default=6, help="windows of the steady part")
    ap.add_argument("--bed", type=float, default=10.0,
                    help="least bed height [bead diameters]")
    ap.add_argument("--bed-per-orifice", type=float, default=1.0,
                    help="least bed height [orifice diameters]")
    ap.add_argument("--seeds", default="1,2,3",
                    help="fill seeds, comma-separated, for the orifices up to --seeds-upto")
    ap.add_argument("--seeds-upto", type=float, default=6.0,
                    help="orifices wider than this [bead diameters] run the first seed only")
    ap.add_argument("--poured", type=float, default=10.0,
                    help="orifice [bead diameters] of the silo poured closed for rho_b")
    ap.add_argument("--jobs", type=int, default=2)
    a = ap.parse_args()
    dds = [float(s) for s in a.diameters.split(",")]
    seeds = [int(s) for s in a.seeds.split(",")]

    def bed(dd):
        return bed_height(dd, a.bed, a.bed_per_orifice)

    # the poured bed's bulk density: a silo (--poured), closed, from the same fill; the
    # largest runs first, so that the last to finish are short
    jobs = [(dd, bed(dd), a.seconds, seed, False) for dd in sorted(dds, reverse=True)
            for seed in (seeds if dd <= a.seeds_upto else seeds[:1])]
    jobs.insert(1, (a.poured, bed(a.poured), a.seconds, seeds[0], True))
    d = 2.0 * RADIUS
    m_bead = RHO_GLASS * V_BEAD
    edges = np.linspace(a.warmup, a.seconds, a.windows + 1)
    header = (f"{'D/d':>5} {'seed':>4} {'bed/d':>5} {'beads':>6} {'exits':>6} {'W [g/s]':>9} "
              f"{'±':>7} {'drift':>6} {'phi_b':>6} {'absent':>6} {'wall [s]':>9}  guard")

    def measure(r) -> dict:
        """The run ``r`` with its rate, error and drift (seed_rate) and bulk fraction."""
        r["w"], r["dw"], r["drift"] = seed_rate(r, edges, m_bead)
        r["phi"] = bulk_fraction(r["position"], r["present"], r["geo"]["silo"], r["geo"]["bed"])
        return r

    def row(r) -> str:
        return (f"{r['dd']:5.1f} {r['seed']:4d} {r['geo']['bed'] / d:5.1f} "
                f"{r['geo']['count']:6d} {r['exits'].size:6d} {1e3 * r['w']:9.3f} "
                f"{1e3 * r['dw']:7.3f} {100 * r['drift']:+5.1f}% {r['phi']:6.3f} "
                f"{int((~r['present']).sum()):6d} "
                f"{r['wall']:9.1f}  "
                + (f"at {r['guard'][0]:.4f} s: {r['guard'][1]}" if r["guard"] else
                   f"none (ran to {a.seconds} s)")
                + ("  (closed: rho_b)" if r["shut"] else ""))

    results, poured = [], None
    print("as each run ends:\n" + header, flush=True)
    with ProcessPoolExecutor(max_workers=a.jobs) as pool:
        for future in as_completed([pool.submit(run_one, job) for job in jobs]):
            r = measure(future.result())
            print(row(r), flush=True)
            if r["shut"]:
                poured = r
            else:
                results.append(r)
    results.sort(key=lambda r: (r["dd"], r["seed"]))
    print("\n" + header)
    per_orifice: dict[float, list] = {}
    for r in results:
        print(row(r))
        # a run the collapse guard stopped is reported above and left out of the fit
        if not r["guard"]:
            per_orifice.setdefault(r["dd"], []).append((r["w"], r["dw"], r["phi"]))
    rows = []
    for dd_, runs in sorted(per_orifice.items()):
        w, dw = combine([x[0] for x in runs], [x[1] for x in runs])
        rows.append((dd_, w, dw, float(np.mean([x[2] for x in runs])), len(runs)))
    dd, w, dw, phi, n_seeds = (np.array(c) for c in zip(*rows, strict=True))
    if n_seeds.max() > 1:
        print("over the seeds: " + ", ".join(
            f"{di:g} d: {1e3 * wi:.3f} ± {1e3 * ei:.3f} g/s ({ni} seeds)"
            for di, wi, ei, ni in zip(dd, w, dw, n_seeds, strict=True) if ni > 1))
    phi_b = poured["phi"]
    if poured["guard"]:
        print(f"the closed pour stopped at the collapse guard at {poured['guard'][0]:.4f} s; "
              "its bed is measured there")
    rho_b = RHO_GLASS * phi_b
    print(f"bulk density rho_b = {rho_b:.0f} kg/m^3: phi = {phi_b:.3f} of glass "
          f"({RHO_GLASS:.0f}) in the poured bed of the D = {poured['dd']:g} d silo, closed, at "
          f"{a.seconds} s ({poured['wall']:.0f} s of wall time); while draining, phi_b above "
          f"is {phi.min():.3f}-{phi.max():.3f}")
    if len(dd) < 3:
        print(f"no fit: {len(dd)} orifice(s) ran to the end, the law's two parameters need 3")
        return
    from scipy.optimize import curve_fit

    def law(dd_, c, k):
        return c * rho_b * math.sqrt(G) * np.clip(dd_ * d - k * d, 0.0, None) ** 2.5

    (c, k), cov = curve_fit(law, dd, w, p0=(0.58, 1.5), sigma=np.maximum(dw, 1e-12 * w.max()),
                            absolute_sigma=False)
    ec, ek = np.sqrt(np.diag(cov))
    print(f"Beverloo fit: C = {c:.3f} ± {ec:.3f}, k = {k:.2f} ± {ek:.2f} "
          f"({len(dd)} orifices, D = {dd.min():g}-{dd.max():g} d)")
    print("residuals [%]: " + ", ".join(f"{100 * (wi / law(di, c, k) - 1):+.1f}"
                                       for di, wi in zip(dd, w, strict=True)))


if __name__ == "__main__":
    main()
