"""Speed and memory of the event loop: elastic gas at several sizes, and a granular scene.

Usage:
    NUMBA_CACHE_DIR=... .venv/bin/python tools/bench_engine.py [--sizes 1e3,1e4,1e5,1e6]
        [--seconds 2] [--warmup 3] [--granular-count 2500] [--paired-rounds 9] [--quick]

Prints figures only (no pass/fail), with the targets next to them:

- **Elastic gas** (``effects = []``, no gravity, fully periodic cube, equal steel spheres of
  radius 10 mm at packing fraction 0.3): for each N, events/s (collisions + cell crossings;
  dropped stale entries are not counted) and collisions/s over a timed stretch of at least
  ``--seconds`` of wall time. The spheres start on a simple cubic lattice with random vacancies
  (the random [[fill]] cannot reach φ = 0.3 for large N) with Gaussian velocities (fixed seed,
  zero total momentum, rms speed 1 m/s), and run ``--warmup`` collisions per sphere untimed so
  the lattice melts before the timed stretch. Compile time is excluded: a small simulation of
  the same effect set is built first, and :class:`~hsgran.engine.Simulation` compiles (or loads
  the cache) at construction, which is never timed.
- **Scaling** (with 1e3 and 1e6 among the sizes): the two gases again, in ``--paired-rounds``
  rounds of equal chunks of collisions that alternate between the sizes in one process, so that
  both see the same state of the shared machine; the target's verdict is on the median of the
  per-round ratios (the separate runs are printed too).
- **Bytes per particle**: ``nbytes`` of the arrays the Simulation holds (views counted once, by
  their base buffer) divided by N, without and with the frame buffer (the buffer holds up to
  ``FRAME_BUFFER_BYTES`` = 32 MB of frames, so per particle it is large for small N), and the
  process peak-RSS increase per particle from building the Simulation to the end of its timed
  run (the Scene's own arrays are made before and not included). Peak RSS is VmHWM of
  /proc/self/status, reset before each size through /proc/self/clear_refs; where that is not
  possible, ``resource.getrusage`` ru_maxrss (a process-lifetime peak: only increases show).
  At small N the RSS figure is noise (the allocator reuses freed memory, pages are 4 kB, and
  untouched parts of the frame buffer are never resident); it is meaningful from N ~ 10⁵.
- **Granular scene**: steel spheres (radius 1–1.5 mm) falling in a closed glass box with
  gravity, rotation, friction and plasticity, like ``scenarios/falling_box.toml``, run only to
  0.11 s: the first spheres reach the floor at ≈ 0.1 s, so this is the cost of free fall with
  the first impacts (the pile that forms next is the following item). Independent fills
  (seeds 1, 2, ...) are run until the timed total reaches ``--seconds``.
- **Settling pile**: ``tools/scenes/pour.toml`` (2000 steel spheres poured into a glass box at
  e = 0.5, with the enduring-contact rules of docs/enduring-contact.md) run to ``--pile-until``
  (default 0.2 s, while the pile forms and events are densest; ``--pile-until 1`` runs it
  until every sphere is at rest, see that page): events per particle
  per simulated second (collisions, landings and motion-state changes) in the last 0.05 s and
  over the whole run, spheres at rest, wall time, engine bytes per particle and peak RSS.

The machine may be shared: figures are noisy; compare runs on an idle machine. Current
figures and their history: docs/performance.md.
"""

from __future__ import annotations

import argparse
import dataclasses
import gc
import math
import platform
import resource
import statistics
import time
from pathlib import Path

import numpy as np

from hsgran.engine import Simulation, SimulationError
from hsgran.events.kinds import EVENT_NAMES
from hsgran.onplane import MS_REST
from hsgran.scene import load_scene, parse_scene

#: Packing fraction of the elastic gas (the issue's benchmark density).
PACKING = 0.3
#: Sphere radius of the elastic gas [m] (only the ratio to the box matters).
RADIUS = 0.01
#: Root-mean-square speed of the elastic gas [m/s].
RMS_SPEED = 1.0
#: Seed of the lattice vacancies and velocities.
SEED = 1
#: Simulated-time limit of the elastic runs [s]: far beyond any collision budget used here, so
#: the runs stop on their collision counts (mean free time ≈ 10 ms at φ = 0.3).
GAS_DURATION = 1.0e6
#: Spheres in the warm-up simulation that loads the compiled loop before anything is measured.
COMPILE_SPHERES = 64
#: Fraction of the timed stretch run per call of Simulation.run (each call costs a few µs of
#: Python, negligible at this size).
CHUNK_FRACTION = 0.25
#: Smallest chunk of collisions per call [collisions].
MIN_CHUNK = 1000

#: Granular scene: end of the timed run [s]. The spheres start 58–100 mm up with small random
#: speeds and the first ones reach the floor at ≈ 0.1 s; a pile would form from ≈ 0.12 s.
GRANULAR_UNTIL = 0.11
#: Spheres in the granular scene of scenarios/falling_box.toml; the box cross-section is scaled
#: with the count so that the density of the falling cloud stays the same.
GRANULAR_COUNT = 2500
GRANULAR_BOX_SIDE = 0.05  #: [m] cross-section side of the box for GRANULAR_COUNT spheres

#: Targets (issue: the engine's performance goals).
TARGET_EVENTS_1E4 = 5.0e5  #: events/s at N = 10⁴
TARGET_SCALING = 0.5  #: events/s at N = 10⁶ relative to N = 10³
TARGET_BYTES = 1024  #: engine bytes per particle (frame buffer excluded)

#: Scaling target measured in pairs: rounds of equal chunks of collisions alternating between
#: N = 10³ and N = 10⁶ in one process, so that both sizes see the same state of the shared
#: machine (its speed drifts by tens of per cent within minutes; two separate runs a minute
#: apart compare the drift, not the sizes). The verdict is on the median of the paired ratios.
PAIRED_ROUNDS = 9
PAIRED_CHUNK = 200_000  #: collisions per chunk of the paired measurement

DEFAULT_SIZES = "1e3,1e4,1e5"
QUICK_SIZES = "1e3,1e4"
QUICK_SECONDS = 0.2
QUICK_WARMUP = 2.0
QUICK_GRANULAR_COUNT = 300
#: The settling pile and how far it is run [s]; --quick stops it while the spheres still fall.
PILE_SCENE = Path(__file__).resolve().parent / "scenes" / "pour.toml"
PILE_UNTIL = 0.2
QUICK_PILE_UNTIL = 0.05
#: The pile's rate is also given over this last stretch of the run [s].
PILE_LAST = 0.05
#: Events that change a sphere's motion (the rest are bookkeeping: cells, frames, stale).
MOTION_EVENTS = ("pair", "wall", "state", "land")

GAS_TEMPLATE = """
[scene]
name = "elastic gas on a lattice (benchmark)"
duration = {duration}
effects = []
seed = {seed}
periodic = [true, true, true]
[output]
frame_interval = {duration}
[[walls]]
kind = "box"
lower = [0.0, 0.0, 0.0]
upper = [{side!r}, {side!r}, {side!r}]
[[particles]]
material = "steel"
radius = {radius}
position = [{mid!r}, {mid!r}, {mid!r}]
"""

GRANULAR_TEMPLATE = """
[scene]
name = "steel balls falling into a glass box (benchmark)"
duration = 0.2
gravity = [0.0, 0.0, -9.81]
effects = ["gravity", "rotation", "friction", "plasticity"]
seed = {seed}
[output]
frame_interval = 0.002
[[contacts]]
between = ["steel", "steel"]
sliding_friction = 0.2
[[contacts]]
between = ["steel", "glass"]
sliding_friction = 0.3
[[walls]]
kind = "box"
lower = [0.0, 0.0, 0.0]
upper = [{side!r}, {side!r}, 0.10]
material = "glass"
[[fill]]
count = {count}
material = "steel"
radius = [0.0010, 0.0015]
region = {{ lower = [0.0, 0.0, 0.058], upper = [{side!r}, {side!r}, 0.10] }}
speed = 0.05
"""


# ---- scenes ------------------------------------------------------------------------------

def lattice_gas(n: int, phi: float = PACKING, seed: int = SEED):
    """Elastic gas of ``n`` equal spheres on a simple cubic lattice with random vacancies.

    The box side L follows from φ exactly; the lattice has m = ⌈n^(1/3)⌉ sites per side, of which
    ``n`` random ones are occupied. The materials and checks come from parsing a one-sphere
    template scene; the sphere arrays are then replaced.

    Returns:
        A :class:`~hsgran.scene.Scene` (periodic, no walls, no gravity, no effects).

    Raises:
        ValueError: the lattice spacing is below one diameter (φ too high for this n).
    """
    side = (n * 4.0 / 3.0 * math.pi * RADIUS**3 / phi) ** (1.0 / 3.0)
    m = math.ceil(round(n ** (1.0 / 3.0), 9))
    while m**3 < n:  # guard against the rounding of the cube root
        m += 1
    spacing = side / m
    if spacing <= 2.0 * RADIUS:
        raise ValueError(f"lattice spacing {spacing:.4g} m is below the diameter at n = {n}")
    template = parse_scene(GAS_TEMPLATE.format(duration=GAS_DURATION, seed=seed, side=side,
                                               radius=RADIUS, mid=0.5 * side))
    rng = np.random.default_rng(seed)
    sites = np.sort(rng.choice(m**3, size=n, replace=False))
    ijk = np.stack(np.unravel_index(sites, (m, m, m)), axis=1)
    position = (ijk + 0.5) * spacing
    velocity = rng.standard_normal((n, 3))
    velocity -= velocity.mean(axis=0)
    velocity *= RMS_SPEED / math.sqrt(np.mean(np.sum(velocity**2, axis=1)))
    return dataclasses.replace(
        template, name=f"elastic gas, {n} spheres on a lattice",
        position=np.ascontiguousarray(position), velocity=velocity,
        angular_velocity=np.zeros((n, 3)), radius=np.full(n, RADIUS),
        material=np.zeros(n, dtype=np.int64))


def granular_scene(count: int, seed: int):
    """Falling-box scene with ``count`` spheres (cross-section scaled with the count)."""
    side = GRANULAR_BOX_SIDE * math.sqrt(count / GRANULAR_COUNT)
    return parse_scene(GRANULAR_TEMPLATE.format(seed=seed, side=side, count=count))


# ---- memory ------------------------------------------------------------------------------

class PeakRss:
    """Process peak resident set size [bytes], resettable where Linux allows it."""

    def __init__(self):
        self.resettable = self._reset()
        self.source = ("VmHWM of /proc/self/status (reset per size)" if self.resettable
                       else "getrusage ru_maxrss (lifetime peak)")

    @staticmethod
    def _reset() -> bool:
        try:
            with open("/proc/self/clear_refs", "w") as f:
                f.write("5")  # 5: reset the peak RSS to the current RSS (Linux ≥ 4.0)
            return True
        except OSError:
            return False

    @staticmethod
    def _status(field: str) -> int | None:
        try:
            with open("/proc/self/status") as f:
                for line in f:
                    if line.startswith(field + ":"):
                        return int(line.split()[1]) * 1024
        except OSError:
            pass
        return None

    def start(self) -> int:
        """Reset the peak (if possible) and return the baseline [bytes]."""
        if self.resettable:
            self._reset()
            return self._status("VmRSS")
        return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * 1024

    def peak(self) -> int:
        """Peak since :meth:`start` (or lifetime peak) [bytes]."""
        if self.resettable:
            return self._status("VmHWM")
        return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * 1024


def _root(a: np.ndarray) -> np.ndarray:
    while isinstance(a.base, np.ndarray):
        a = a.base
    return a


def state_bytes(sim) -> tuple[int, int]:
    """(bytes of the engine's arrays without the frame buffer, bytes of the frame buffer).

    Every numpy array the Simulation holds as an attribute (or inside a tuple attribute) is
    counted once, by its base buffer; attributes named ``fr_*`` are the frame buffer.
    """
    seen: dict[int, tuple[np.ndarray, bool]] = {}

    def visit(obj, frame):
        if isinstance(obj, np.ndarray):
            root = _root(obj)
            old = seen.get(id(root))
            seen[id(root)] = (root, frame or (old is not None and old[1]))
        elif isinstance(obj, tuple | list):
            for item in obj:
                visit(item, frame)

    for name, value in vars(sim).items():
        if name != "scene":
            visit(value, name.startswith("fr_"))
    state = sum(a.nbytes for a, frame in seen.values() if not frame)
    frames = sum(a.nbytes for a, frame in seen.values() if frame)
    return state, frames


# ---- runs --------------------------------------------------------------------------------

def _executed(events: dict) -> int:
    return events.get("pair", 0) + events.get("wall", 0) + events.get("cell", 0)


def timed_collisions(sim, seconds: float, rate: float, until: float):
    """Run chunks of collisions until ``seconds`` of run time have passed.

    Returns:
        (wall time [s], counts by event kind) summed over the chunks.
    """
    chunk = max(MIN_CHUNK, int(rate * seconds * CHUNK_FRACTION))
    wall = 0.0
    total: dict[str, int] = {}
    while wall < seconds:
        s = sim.run(until=until, max_collisions=chunk)
        wall += s.wall_time
        for k, v in s.events.items():
            total[k] = total.get(k, 0) + v
    return wall, total


def bench_gas(n: int, seconds: float, warmup: float, rss: PeakRss) -> dict:
    """Figures of the elastic gas with ``n`` spheres."""
    scene = lattice_gas(n)
    gc.collect()
    base = rss.start()
    t0 = time.perf_counter()
    sim = Simulation(scene)
    setup = time.perf_counter() - t0
    warm = sim.run(until=GAS_DURATION, max_collisions=max(1, int(warmup * n / 2)))
    rate = warm.collisions / warm.wall_time if warm.wall_time > 0 else 1e6
    wall, events = timed_collisions(sim, seconds, rate, GAS_DURATION)
    peak = rss.peak() - base
    state, frames = state_bytes(sim)
    collisions = events.get("pair", 0) + events.get("wall", 0)
    out = dict(n=n, setup=setup, warm_collisions=warm.collisions, collisions=collisions,
               cells=events.get("cell", 0), stale=events.get("stale", 0), wall=wall,
               events_per_s=_executed(events) / wall, collisions_per_s=collisions / wall,
               state=state / n, with_frames=(state + frames) / n, peak_rss=peak / n)
    del sim
    gc.collect()
    return out


def bench_paired(small: int, large: int, rounds: int, warmup: float) -> dict:
    """Events/s of the elastic gas at two sizes, measured in alternating chunks (PAIRED_*).

    Returns:
        Median events/s of each size, the median of the per-round ratios large/small, and the
        ratio of the best chunks.
    """
    sims = {}
    for n in (small, large):
        sims[n] = Simulation(lattice_gas(n))
        sims[n].run(until=GAS_DURATION, max_collisions=max(1, int(warmup * n / 2)))
    rates: dict[int, list[float]] = {small: [], large: []}
    for _ in range(rounds):
        for n in (small, large):
            s = sims[n].run(until=GAS_DURATION, max_collisions=PAIRED_CHUNK)
            rates[n].append(_executed(s.events) / s.wall_time)
    del sims
    gc.collect()
    ratios = [b / a for a, b in zip(rates[small], rates[large], strict=True)]
    return dict(small=statistics.median(rates[small]), large=statistics.median(rates[large]),
                ratio=statistics.median(ratios), best=max(rates[large]) / max(rates[small]))


def bench_granular(count: int, seconds: float) -> dict:
    """Events/s of the falling-box scene (runs fills of seed 1, 2, ... until ``seconds``)."""
    wall = 0.0
    events: dict[str, int] = {}
    runs = 0
    simulated = 0.0
    while wall < seconds or runs == 0:
        sim = Simulation(granular_scene(count, seed=runs + 1))
        s = sim.run(until=GRANULAR_UNTIL)
        runs += 1
        wall += s.wall_time
        simulated += s.simulated_time
        for k, v in s.events.items():
            events[k] = events.get(k, 0) + v
    collisions = events.get("pair", 0) + events.get("wall", 0)
    return dict(count=count, runs=runs, wall=wall, simulated=simulated, events=events,
                events_per_s=_executed(events) / wall, collisions_per_s=collisions / wall)


def bench_pile(until: float, rss: PeakRss) -> dict:
    """Figures of the settling pile run to ``until`` [s] (or to where the collapse guard
    stops it)."""
    scene = dataclasses.replace(load_scene(PILE_SCENE), duration=until)
    gc.collect()
    base = rss.start()
    sim = Simulation(scene)
    idx = [EVENT_NAMES.index(k) for k in MOTION_EVENTS]
    t_last = max(0.0, until - PILE_LAST)
    stopped = ""
    wall = 0.0
    mid = None
    for t in (t_last, until):
        try:
            wall += sim.run(until=t).wall_time
        except SimulationError as ex:
            stopped = str(ex)
            break
        if mid is None:
            mid = (sim.counts[idx].sum(), sim.time)
    total = int(sim.counts[idx].sum())
    t_end = sim.time
    n = scene.n
    last_rate = ((total - mid[0]) / n / (t_end - mid[1])
                 if mid is not None and t_end > mid[1] else math.nan)
    state, _ = state_bytes(sim)
    return dict(n=n, t_end=t_end, wall=wall, per_particle_s=total / n / max(t_end, 1e-300),
                last_rate=last_rate, at_rest=int((sim.mstate == MS_REST).sum()),
                state=state / n, peak_rss=(rss.peak() - base) / n, stopped=stopped)


# ---- report ------------------------------------------------------------------------------

def _sizes(text: str) -> list[int]:
    sizes = [round(float(s)) for s in text.split(",") if s.strip()]
    if not sizes or min(sizes) < COMPILE_SPHERES:
        raise SystemExit(f"--sizes: give sizes ≥ {COMPILE_SPHERES}, e.g. 1e3,1e4,1e5")
    return sorted(sizes)


def _verdict(ok: bool) -> str:
    return "met" if ok else "NOT met"


def main(argv=None) -> int:
    """Run the benchmark and print the figures."""
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--sizes", default=None,
                    help=f"comma-separated N (default {DEFAULT_SIZES}; {QUICK_SIZES} with "
                         "--quick); add 1e6 for the scaling target")
    ap.add_argument("--seconds", type=float, default=None,
                    help="least wall time of each timed stretch [s] (default 2, quick 0.2)")
    ap.add_argument("--warmup", type=float, default=None,
                    help="untimed collisions per sphere before timing (default 3, quick 2)")
    ap.add_argument("--granular-count", type=int, default=None,
                    help=f"spheres of the granular scene (default {GRANULAR_COUNT}, quick "
                         f"{QUICK_GRANULAR_COUNT})")
    ap.add_argument("--pile-until", type=float, default=None,
                    help=f"simulated time of the settling pile [s] (default {PILE_UNTIL}, quick "
                         f"{QUICK_PILE_UNTIL})")
    ap.add_argument("--paired-rounds", type=int, default=PAIRED_ROUNDS,
                    help="rounds of the paired N = 1e3 / 1e6 measurement of the scaling target "
                         f"when --sizes has both (default {PAIRED_ROUNDS}; 0: none)")
    ap.add_argument("--quick", action="store_true", help="a fast smoke run with small settings")
    args = ap.parse_args(argv)
    quick = args.quick
    sizes = _sizes(args.sizes or (QUICK_SIZES if quick else DEFAULT_SIZES))
    seconds = args.seconds if args.seconds is not None else (QUICK_SECONDS if quick else 2.0)
    warmup = args.warmup if args.warmup is not None else (QUICK_WARMUP if quick else 3.0)
    g_count = args.granular_count or (QUICK_GRANULAR_COUNT if quick else GRANULAR_COUNT)
    pile_until = args.pile_until or (QUICK_PILE_UNTIL if quick else PILE_UNTIL)

    rss = PeakRss()
    print(f"# hsgran event-loop benchmark; {platform.processor() or platform.machine()}, "
          f"Python {platform.python_version()}{' (--quick)' if quick else ''}")
    print(f"# elastic gas: phi = {PACKING}, periodic cube, equal spheres, rms speed "
          f"{RMS_SPEED} m/s, simple cubic lattice start; warm-up {warmup:g} collisions per "
          f"sphere untimed, then >= {seconds:g} s timed; compile time excluded")
    t0 = time.perf_counter()
    Simulation(lattice_gas(COMPILE_SPHERES))  # compile or load the elastic loop
    print(f"# compile/load of the elastic loop: {time.perf_counter() - t0:.1f} s", flush=True)

    print(f"{'N':>9} {'setup s':>8} {'warm-up coll':>13} {'timed coll':>11} {'wall s':>7} "
          f"{'events/s':>10} {'collisions/s':>13}")
    results = []
    for n in sizes:
        r = bench_gas(n, seconds, warmup, rss)
        results.append(r)
        print(f"{n:>9,} {r['setup']:8.2f} {r['warm_collisions']:>13,} {r['collisions']:>11,} "
              f"{r['wall']:7.2f} {r['events_per_s']:10.3g} {r['collisions_per_s']:13.3g}",
              flush=True)
    print()
    print(f"# bytes per particle: engine arrays' nbytes / N without and with the frame buffer; "
          f"peak RSS increase / N from {rss.source}")
    print(f"{'N':>9} {'state B':>9} {'+frames B':>10} {'peak RSS B':>11}")
    for r in results:
        print(f"{r['n']:>9,} {r['state']:9.0f} {r['with_frames']:10.0f} {r['peak_rss']:11.0f}")
    print()

    g = bench_granular(g_count, seconds)
    ev = ", ".join(f"{k} {v:,}" for k, v in g["events"].items() if v)
    print(f"# granular: {g_count} steel spheres falling in a glass box (gravity, rotation, "
          f"friction, plasticity) to t = {GRANULAR_UNTIL} s, {g['runs']} fill(s)")
    print(f"granular: {g['events_per_s']:.3g} events/s, {g['collisions_per_s']:.3g} "
          f"collisions/s ({ev}; {g['wall']:.2f} s wall)")
    print()

    p = bench_pile(pile_until, rss)
    print(f"# settling pile: {PILE_SCENE.name}, {p['n']} spheres poured at e = 0.5, run to "
          f"t = {pile_until:g} s")
    print(f"pile: {p['per_particle_s']:.3g} events/particle/s over the run, "
          f"{p['last_rate']:.3g} in the last {PILE_LAST:g} s; {p['at_rest']} at rest at "
          f"t = {p['t_end']:.4g} s; {p['wall']:.2f} s wall; {p['state']:.0f} B/particle state, "
          f"{p['peak_rss']:.0f} B/particle peak RSS")
    if p["stopped"]:
        print(f"pile stopped: {p['stopped']}")
    print()

    by_n = {r["n"]: r for r in results}
    print("targets:")
    if 10_000 in by_n:
        e4 = by_n[10_000]["events_per_s"]
        print(f"  events/s at N = 1e4 >= {TARGET_EVENTS_1E4:.1e}: {e4:.3g}  "
              f"[{_verdict(e4 >= TARGET_EVENTS_1E4)}]")
    else:
        print(f"  events/s at N = 1e4 >= {TARGET_EVENTS_1E4:.1e}: not measured (add 1e4)")
    if 1_000 in by_n and 1_000_000 in by_n:
        ratio = by_n[1_000_000]["events_per_s"] / by_n[1_000]["events_per_s"]
        if args.paired_rounds > 0:
            pr = bench_paired(1_000, 1_000_000, args.paired_rounds, warmup)
            print(f"  events/s at N = 1e6 >= {TARGET_SCALING} x N = 1e3: paired ratio "
                  f"{pr['ratio']:.2f} (median of {args.paired_rounds} rounds of "
                  f"{PAIRED_CHUNK:,} collisions each; medians {pr['small']:.3g} and "
                  f"{pr['large']:.3g} events/s; best chunks {pr['best']:.2f}; the separate "
                  f"runs above {ratio:.2f})  [{_verdict(pr['ratio'] >= TARGET_SCALING)}]")
        else:
            print(f"  events/s at N = 1e6 >= {TARGET_SCALING} x N = 1e3: ratio {ratio:.2f} "
                  f"(separate runs)  [{_verdict(ratio >= TARGET_SCALING)}]")
    else:
        print(f"  events/s at N = 1e6 >= {TARGET_SCALING} x N = 1e3: not measured "
              "(--sizes with 1e3 and 1e6)")
        if 1_000 in by_n and len(results) > 1:
            big = results[-1]
            ratio = big["events_per_s"] / by_n[1_000]["events_per_s"]
            print(f"    (largest measured, N = {big['n']:,}: ratio {ratio:.2f})")
    worst = max(r["state"] for r in results)
    print(f"  engine state <= {TARGET_BYTES} B/particle (frame buffer excluded): largest "
          f"{worst:.0f} B  [{_verdict(worst <= TARGET_BYTES)}]")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
