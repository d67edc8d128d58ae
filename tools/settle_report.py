"""How far a settling scene gets: events per particle and second, spheres at rest, and where the
collapse guard stops it (docs/enduring-contact.md, "Settling scenes: where it stands").

Usage:
    NUMBA_CACHE_DIR=... .venv/bin/python tools/settle_report.py [SCENE ...]
        [--duration 1.0] [--interval 0.01] [--set KEY=TOML_VALUE ...]

Default scenes: ``scenarios/falling_box.toml`` (its duration raised to ``--duration``) and
``tools/scenes/pour.toml`` (2000 spheres poured at e = 0.5). For each interval of simulated time
it prints the collisions, landings and motion-state events per particle and simulated second,
the spheres at rest, and the wall time; the last line says where the run ended: at the end, or
at the collapse guard with the sphere and instant it names. Figures only, no pass/fail.
"""

from __future__ import annotations

import argparse
import dataclasses
import sys
import time
import tomllib
from pathlib import Path

import numpy as np

from hsgran.engine import Simulation, SimulationError
from hsgran.events.kinds import EVENT_NAMES
from hsgran.onplane import MS_REST
from hsgran.scene import load_scene

ROOT = Path(__file__).resolve().parent.parent
DEFAULT_SCENES = (ROOT / "scenarios" / "falling_box.toml", ROOT / "tools" / "scenes" / "pour.toml")
#: Events that change a sphere's motion (the rest are bookkeeping: cells, frames, stale).
MOTION_EVENTS = ("pair", "wall", "state", "land")


def report(path: Path, duration: float, interval: float, overrides=None) -> None:
    scene = dataclasses.replace(load_scene(path, overrides=overrides), duration=duration)
    sim = Simulation(scene)
    idx = [EVENT_NAMES.index(k) for k in MOTION_EVENTS]
    print(f"# {path.name}: {scene.n} spheres to t = {duration} s")
    print(f"{'t [s]':>8} {'events/particle/s':>18} {'at rest':>8} {'wall [s]':>9}")
    prev = sim.counts.copy()
    t0 = time.perf_counter()
    steps = round(duration / interval)
    for k in range(1, steps + 1):
        t = k * interval
        try:
            sim.run(until=t)
        except SimulationError as ex:
            print(f"stopped: {ex}")
            return
        d = sim.counts - prev
        prev = sim.counts.copy()
        rate = d[idx].sum() / scene.n / interval
        rest = int(np.sum(sim.mstate == MS_REST)) if scene.effects.gravity else 0
        print(f"{t:8.3f} {rate:18.1f} {rest:8d} {time.perf_counter() - t0:9.1f}", flush=True)
    print("events by kind: "
          + ", ".join(f"{k} {c}" for k, c in zip(EVENT_NAMES, sim.counts, strict=True) if c))
    print(f"finished at t = {duration} s")


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("scenes", nargs="*", type=Path, default=list(DEFAULT_SCENES))
    ap.add_argument("--duration", type=float, default=1.0, help="simulated time [s]")
    ap.add_argument("--interval", type=float, default=0.01, help="report interval [s]")
    ap.add_argument("--set", action="append", default=[], metavar="KEY=VALUE",
                    help="override a scene key; VALUE in TOML (e.g. "
                         "'scene.effects=[\"gravity\"]'); repeatable")
    args = ap.parse_args(argv)
    overrides = {}
    for item in args.set:
        key, sep, value = item.partition("=")
        if not sep:
            ap.error(f"--set {item!r}: expected KEY=VALUE")
        try:
            overrides[key.strip()] = tomllib.loads(f"v = {value}")["v"]
        except tomllib.TOMLDecodeError as ex:
            ap.error(f"--set {item!r}: the value is not TOML ({ex})")
    for path in args.scenes:
        report(path, args.duration, args.interval, overrides or None)
    return 0


if __name__ == "__main__":
    sys.exit(main())
