"""Cost of one collision per effect set: compiled, batched over many random events.

Usage:
    .venv/bin/python tools/bench_contact.py [--events 1000000] [--repeat 5]

Prints ns/event for each effect set (compile time excluded). The events are processed in
cache-resident chunks of ``--chunk`` events, each timed on a fresh copy of its inputs, so the
figure is the arithmetic of the model and not the memory bandwidth of streaming 10⁶ events;
each chunk's time is the best of ``--repeat`` runs. The events are sphere–sphere collisions
of steel spheres (radii 1–10 mm, approach speeds log-uniform in 0.01–10 m/s, so all three
compression stages occur, random oblique directions and spins).
Every effect set runs the same events, so differences are the price of the effects.
Two columns: the kernel specialised to the effect set (flags compiled in), and the kernel with
the flags as run-time switches, which is how the event loop calls it.
"""

from __future__ import annotations

import argparse
import dataclasses
import platform
import time

import numpy as np

from hsgran.contact.model import REC_SIZE, make_batch_resolver
from hsgran.effects import Effects
from hsgran.materials import BUILTIN_MATERIALS, Contact, pair_row

EFFECT_SETS = (
    ("elastic Hertz (no effects)", ()),
    ("fixed restitution", ("fixed",)),
    ("plasticity", ("plasticity",)),
    ("plasticity+adhesion", ("plasticity", "adhesion")),
    ("rotation+friction", ("rotation", "friction")),
    ("plasticity+rotation+friction", ("plasticity", "rotation", "friction")),
    ("rotation+friction+tangential_compliance", ("rotation", "friction", "tangential_compliance")),
    ("plasticity+viscoelastic_damping", ("plasticity", "viscoelastic_damping")),
    (
        "full model (all effects)",
        ("plasticity", "adhesion", "rotation", "friction", "rolling_resistance"),
    ),
)


def make_events(k: int, seed: int = 1):
    """Random approaching sphere pairs (arrays for ``make_batch_resolver``)."""
    rng = np.random.default_rng(seed)
    steel = BUILTIN_MATERIALS["steel"]
    r1 = rng.uniform(1e-3, 1e-2, k)
    r2 = rng.uniform(1e-3, 1e-2, k)
    m1 = steel.density * 4 / 3 * np.pi * r1**3
    m2 = steel.density * 4 / 3 * np.pi * r2**3
    n = rng.normal(size=(k, 3))
    n /= np.linalg.norm(n, axis=1)[:, None]
    speed = 10 ** rng.uniform(-2, 1, k)
    tang = rng.normal(size=(k, 3))
    tang -= np.sum(tang * n, axis=1)[:, None] * n
    vel1 = -speed[:, None] * n + 0.5 * speed[:, None] * tang
    vel2 = np.zeros((k, 3))
    omg1 = rng.normal(scale=50.0, size=(k, 3))
    omg2 = rng.normal(scale=50.0, size=(k, 3))
    return dict(
        vel1=vel1,
        omg1=omg1,
        vel2=vel2,
        omg2=omg2,
        normal=n,
        inv_m1=1 / m1,
        inv_m2=1 / m2,
        inv_i1=1 / (0.4 * m1 * r1**2),
        inv_i2=1 / (0.4 * m2 * r2**2),
        r1=r1,
        r2=r2,
        curv=1 / r1 + 1 / r2,
    )


def rows_for(fixed: bool) -> np.ndarray:
    """One pair row: steel on steel with friction, rolling friction, adhesion and a
    dissipative constant (read only by the ``viscoelastic_damping`` sets)."""
    steel = dataclasses.replace(BUILTIN_MATERIALS["steel"], dissipative_constant=2e-8)
    contact = Contact(
        sliding_friction=0.3,
        rolling_friction=0.01,
        work_of_adhesion=0.05,
        restitution=0.8 if fixed else None,
    )
    return pair_row(steel, steel, contact)[None, :]


def time_set(names, events, chunk: int, repeat: int, switched: bool) -> float:
    """ns/event for one effect set: sum over chunks of the best of ``repeat`` timings."""
    fixed = "fixed" in names
    effects = Effects(**{n: True for n in names if n != "fixed"})
    batch = make_batch_resolver(effects, switched=switched)
    rows = rows_for(fixed)
    k = events["vel1"].shape[0]
    keys = (
        "vel1",
        "omg1",
        "vel2",
        "omg2",
        "normal",
        "inv_m1",
        "inv_m2",
        "inv_i1",
        "inv_i2",
        "r1",
        "r2",
        "curv",
    )
    idx = np.zeros(chunk, dtype=np.int64)
    recs = np.empty((chunk, REC_SIZE))
    small = {key: v[:chunk].copy() for key, v in events.items()}
    batch(*[small[key] for key in keys], rows, idx, recs)  # compile or load from cache
    total = 0.0
    for start in range(0, k, chunk):
        best = np.inf
        for _ in range(repeat):
            args = [events[key][start : start + chunk].copy() for key in keys]
            t = time.perf_counter()
            hit = batch(*args, rows, idx, recs)
            best = min(best, time.perf_counter() - t)
            if not hit.all():
                raise RuntimeError("an event did not collide: the generator is wrong")
        total += best
    return total / k * 1e9


def main(argv=None) -> int:
    """Print the benchmark table."""
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--events", type=int, default=1_000_000)
    ap.add_argument("--chunk", type=int, default=10_000)
    ap.add_argument("--repeat", type=int, default=3)
    args = ap.parse_args(argv)
    events = make_events(args.events)
    print(
        f"# hsgran collision kernel, {args.events:,} random sphere–sphere events, "
        f"chunks of {args.chunk:,} (best of {args.repeat}); "
        f"{platform.processor() or platform.machine()}, "
        f"Python {platform.python_version()}"
    )
    print(f"{'effect set':<40} {'ns/event specialised':>21} {'ns/event switched':>18}")
    for label, names in EFFECT_SETS:
        spec = time_set(names, events, args.chunk, args.repeat, False)
        swit = time_set(names, events, args.chunk, args.repeat, True)
        print(f"{label:<40} {spec:21.1f} {swit:18.1f}", flush=True)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
