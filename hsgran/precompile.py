"""Compile the event loop ahead of its first use (``hsgran compile``; layer 6).

The event loop is one large compiled function with four versions: with and without gravity
(straight or parabolic flights), each in the layout for ordinary and for large systems
(:data:`hsgran.engine.LARGE_FROM`). A cold compile of one version takes 3 min without gravity
and 14 min with it (2 cores, 2026-12-03); numba keeps the result on disk
(:mod:`hsgran._jit`), so it is paid once per installed version of hsgran, by the first run that
needs it. ``hsgran compile`` pays it up front instead, with the
versions compiled side by side in separate processes; ``tools/setup.sh`` runs it. Each version
is compiled by running a tiny scene for a few events: the same code path as a real run, so the
cache entries are the ones a real run looks up.
"""

from __future__ import annotations

import os
import time
from concurrent.futures import ProcessPoolExecutor, as_completed
from multiprocessing import get_context

#: Two spheres of the built-in steel bouncing on a steel floor, with every effect (the loop
#: with gravity).
_GRAVITY_SCENE = """
[scene]
name = "compile: loop with gravity"
duration = 0.01
gravity = [0.0, 0.0, -9.81]
effects = ["gravity", "rotation", "friction", "plasticity"]
[output]
frame_interval = 0.005
[[contacts]]
between = ["steel", "steel"]
sliding_friction = 0.3
[[walls]]
kind = "plane"
point = [0.0, 0.0, 0.0]
normal = [0.0, 0.0, 1.0]
material = "steel"
[[particles]]
material = "steel"
radius = 0.001
position = [0.0, 0.0, 0.0012]
velocity = [0.1, 0.0, -0.2]
[[particles]]
material = "steel"
radius = 0.001
position = [0.003, 0.0, 0.0012]
velocity = [-0.1, 0.0, -0.2]
"""

#: Two spheres of the built-in steel meeting in a periodic box, no effects (the loop without
#: gravity).
_FREE_SCENE = """
[scene]
name = "compile: loop without gravity"
duration = 0.01
effects = []
periodic = [true, true, true]
[output]
frame_interval = 0.005
[[walls]]
kind = "box"
lower = [0.0, 0.0, 0.0]
upper = [0.01, 0.01, 0.01]
[[particles]]
material = "steel"
radius = 0.001
position = [0.002, 0.005, 0.005]
velocity = [1.0, 0.0, 0.0]
[[particles]]
material = "steel"
radius = 0.001
position = [0.008, 0.005, 0.005]
velocity = [-1.0, 0.0, 0.0]
"""

#: The versions of the event loop, by name: (scene text, large-system layout). The ones that
#: take longest to compile come first, so that parallel jobs end at about the same time.
VERSIONS = {
    "gravity": (_GRAVITY_SCENE, False),
    "gravity-large": (_GRAVITY_SCENE, True),
    "free": (_FREE_SCENE, False),
    "free-large": (_FREE_SCENE, True),
}


def compile_version(name: str) -> float:
    """Compile one version of the event loop (see :data:`VERSIONS`) by running its scene for
    a few events; returns the wall time [s] (~0.5 s when the on-disk cache had it)."""
    from hsgran.engine import Simulation
    from hsgran.scene import parse_scene

    text, large = VERSIONS[name]
    t0 = time.perf_counter()
    sim = Simulation(parse_scene(text, source=f"<compile {name}>"), large=large)
    sim.run(until=0.01, max_collisions=10)
    return time.perf_counter() - t0


def compile_all(names=None, jobs: int = 1, report=print) -> dict[str, float]:
    """Compile the given versions of the event loop (default: all), ``jobs`` at a time, each
    in a process of its own; returns each one's wall time [s]. ``report(line)`` is called as
    each one ends."""
    names = list(VERSIONS) if names is None else list(names)
    done: dict[str, float] = {}
    if jobs <= 1:
        for name in names:
            done[name] = compile_version(name)
            report(f"{name}: {done[name]:.1f} s")
        return done
    # a fresh interpreter per job ("spawn"): nothing compiled before is shared by accident
    with ProcessPoolExecutor(max_workers=jobs, mp_context=get_context("spawn")) as pool:
        futures = {pool.submit(compile_version, name): name for name in names}
        for future in as_completed(futures):
            name = futures[future]
            done[name] = future.result()
            report(f"{name}: {done[name]:.1f} s")
    return done


def jit_disabled() -> bool:
    """Whether numba is switched off (``NUMBA_DISABLE_JIT=1``): nothing to compile then."""
    import numba

    return bool(numba.config.DISABLE_JIT)


def default_jobs() -> int:
    """Parallel compile jobs by default: one per core this process may use, at most one per
    version."""
    try:
        cores = len(os.sched_getaffinity(0))
    except AttributeError:  # not on Linux
        cores = os.cpu_count() or 1
    return max(1, min(cores, len(VERSIONS)))


def main_report(names, jobs: int) -> int:
    """Compile and print one line per version and a summary (the CLI's ``compile``)."""
    if jit_disabled():
        print("nothing to compile: NUMBA_DISABLE_JIT is set")
        return 0
    todo = list(VERSIONS) if names is None else list(names)
    print(f"compiling the event loop ({', '.join(todo)}) with {jobs} job(s): minutes per "
          f"version not yet in the cache (14 min with gravity on 2 cores), seconds for one "
          f"that is", flush=True)
    t0 = time.perf_counter()
    done = compile_all(todo, jobs, report=lambda line: print(line, flush=True))
    print(f"compiled {len(done)} version(s) of the event loop in "
          f"{time.perf_counter() - t0:.1f} s wall with {jobs} job(s)")
    return 0
