"""Bit-identity of final states: does a change to the engine leave every trajectory as it was?

Runs a fixed set of scenes to fixed end times and prints, for each, the SHA-1 of the final
positions, velocities (and spins) and the event counts. A refactoring of the engine that keeps
the physics must print the same lines before and after.

Usage:
    .venv/bin/python tools/identity.py [--scenes pour,box,plate,gas] [--out FILE]
    .venv/bin/python tools/identity.py --compare BEFORE.json AFTER.json
    .venv/bin/python tools/identity.py --rev REV      # the same scenes at a git revision too

``--rev REV`` checks out REV into a temporary git worktree, runs this script's scenes there in a
separate process (with the same virtual environment, the worktree first on ``sys.path``; its
loop compiles cold, a few minutes) and compares with the working tree. Exit code 1 if any scene
differs, 2 on bad arguments.

Scenes (end times chosen so that each run takes seconds to a minute):
    pour   tools/scenes/pour.toml, 2000 spheres poured at e = 0.5, to 1 s
    box    scenarios/falling_box.toml, 2500 spheres into a box, to 0.15 s
    plate  scenarios/sphere_on_plate.toml, the paper's sphere on a plate, to 12 s
    gas    an elastic gas of 1000 spheres at packing fraction 0.3 (tools/bench_engine.py's
           lattice gas), 300,000 collisions
"""

from __future__ import annotations

import argparse
import hashlib
import json
import os
import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent

#: scene name -> (file relative to the repository, or None for the lattice gas; end time [s] or
#: None; collision budget or None)
SCENES = {
    "pour": ("tools/scenes/pour.toml", 1.0, None),
    "box": ("scenarios/falling_box.toml", 0.15, None),
    "plate": ("scenarios/sphere_on_plate.toml", 12.0, None),
    "gas": (None, None, 300_000),
}
GAS_SPHERES = 1000


def _digest(*arrays) -> str:
    h = hashlib.sha1()
    for a in arrays:
        h.update(memoryview(a.copy()).cast("B"))
    return h.hexdigest()


def run_scene(name: str) -> dict:
    """Final-state fingerprint of one scene: hashes of positions, velocities, spins, counts."""
    if str(ROOT / "tools") not in sys.path:  # bench_engine's lattice gas
        sys.path.insert(0, str(ROOT / "tools"))
    from hsgran.engine import Simulation
    from hsgran.scene import load_scene

    path, until, budget = SCENES[name]
    if path is None:
        import bench_engine

        scene = bench_engine.lattice_gas(GAS_SPHERES)
    else:
        scene = load_scene(ROOT / path)
    sim = Simulation(scene)
    summary = sim.run(until=until, max_collisions=budget)
    out = {"pos": _digest(sim.pos), "vel": _digest(sim.vel),
           "events": {k: v for k, v in summary.events.items() if v},
           "time": repr(sim.time)}
    if sim.rotation:
        out["omg"] = _digest(sim.omg)
    return out


def run_all(names) -> dict:
    return {name: run_scene(name) for name in names}


def compare(before: dict, after: dict) -> bool:
    """Print one line per scene; True when all are identical."""
    same = True
    for name in sorted(set(before) | set(after)):
        a, b = before.get(name), after.get(name)
        ok = a == b
        same &= ok
        print(f"{name:6s} {'identical' if ok else 'DIFFERENT'}")
        if not ok:
            print(f"    before: {json.dumps(a, sort_keys=True)}")
            print(f"    after:  {json.dumps(b, sort_keys=True)}")
    return same


def at_revision(rev: str, names) -> dict:
    """Run the scenes with the package of git revision ``rev`` (a temporary worktree)."""
    with tempfile.TemporaryDirectory() as tmp:
        wt = Path(tmp) / "wt"
        subprocess.run(["git", "-C", str(ROOT), "worktree", "add", "--detach", "-q", str(wt),
                        rev], check=True)
        try:
            env = dict(os.environ, PYTHONPATH=str(wt))
            res = subprocess.run([sys.executable, str(ROOT / "tools" / "identity.py"),
                                  "--scenes", ",".join(names), "--root", str(wt)],
                                 env=env, check=True, capture_output=True, text=True)
            return json.loads(res.stdout.strip().splitlines()[-1])
        finally:
            subprocess.run(["git", "-C", str(ROOT), "worktree", "remove", "--force", str(wt)],
                           check=False)


def main(argv=None) -> int:
    global ROOT
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--scenes", default=",".join(SCENES))
    p.add_argument("--out", help="write the fingerprints to this JSON file")
    p.add_argument("--compare", nargs=2, metavar=("BEFORE", "AFTER"))
    p.add_argument("--rev", help="compare with this git revision")
    p.add_argument("--root", help=argparse.SUPPRESS)  # the worktree a --rev child runs in
    args = p.parse_args(argv)
    if args.compare:
        before, after = (json.loads(Path(f).read_text()) for f in args.compare)
        return 0 if compare(before, after) else 1
    names = [s for s in args.scenes.split(",") if s]
    unknown = [s for s in names if s not in SCENES]
    if unknown:
        print(f"identity: unknown scene {unknown[0]!r}; known: {', '.join(SCENES)}",
              file=sys.stderr)
        return 2
    if args.root:
        ROOT = Path(args.root)
        sys.path.insert(0, str(ROOT))
        print(json.dumps(run_all(names)))
        return 0
    now = run_all(names)
    if args.out:
        Path(args.out).write_text(json.dumps(now, indent=1, sort_keys=True))
    if args.rev:
        return 0 if compare(at_revision(args.rev, names), now) else 1
    print(json.dumps(now, indent=1, sort_keys=True))
    return 0


if __name__ == "__main__":
    sys.exit(main())
