"""Where the compiled event loop spends its time: perf samples by compiled function.

Usage:
    .venv/bin/python tools/profile_loop.py [--size 1e4] [--collisions 2e6] [--cache DIR]
    .venv/bin/python tools/profile_loop.py --scene tools/scenes/pour.toml [--until 0.2]

Runs the elastic gas of tools/bench_engine.py (N spheres, warmed up, then ``--collisions``
collisions), or a scene file, under ``perf record`` (software clock, 4 kHz) and prints the
share of the samples in each compiled function of the loop. perf cannot name numba's JIT
code, so the child process writes where each function of the loop's compiled library was
loaded (the names come from the object code in numba's cache, the addresses from its JIT
engine) and the samples are assigned to those ranges here. Functions that numba inlines are
part of the loop (``_loop_of.<locals>.run_loop``). The debug build may keep a small function
out of line that the ordinary build inlines (motion.flight_position showed 6.6 % of the pour's
samples, and inlining it by hand changed nothing): check a lead with an A/B of the ordinary
build.

The loop is compiled with ``NUMBA_ENABLE_PROFILING=1`` (debug information) into its own cache
directory (under ``--cache``, default /tmp/hsgran-profile-cache; a cold compile takes a minute
or two the first time), so the ordinary cache is left alone. Like the ordinary cache
(hsgran._jit), it is named after a hash of the package's sources: numba keys a cached function
on its own file only, so after an edit of hsgran/motion.py the loop of hsgran/_loop.py, which
inlines it, would load stale, with the old functions' names (a profile of 2026-11-28 showed
functions that no longer existed). Needs ``perf`` (Debian package
linux-perf) and permission to sample user code (perf_event_paranoid ≤ 2).

What it has found is recorded in docs/performance.md (numba's reference counting, see
hsgran._jit.njit).
"""

from __future__ import annotations

import argparse
import bisect
import collections
import json
import os
import pickle
import re
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
DEFAULT_CACHE = Path(tempfile.gettempdir()) / "hsgran-profile-cache"
#: Sampling frequency of perf's software clock [Hz].
SAMPLE_HZ = 4000
#: Functions listed (the rest are summed under "other").
TOP = 14

CHILD = r"""
import json, sys
sys.path.insert(0, {tools!r})
from bench_engine import lattice_gas
from hsgran import _loop
from hsgran.engine import Simulation
from hsgran.scene import load_scene
n, amount, out, scene = int(sys.argv[1]), float(sys.argv[2]), sys.argv[3], sys.argv[4]
if scene:
    sim = Simulation(load_scene(scene))
    loop = _loop.run_loop_gravity if sim.scene.effects.gravity else _loop.run_loop_free
else:
    sim = Simulation(lattice_gas(n))
    sim.run(until=1e6, max_collisions=3 * n // 2)
    loop = _loop.run_loop_free
engine = next(iter(loop.overloads.values())).library._codegen._engine._ee
names = json.load(open(out))["names"]
json.dump({{"addresses": {{nm: engine.get_function_address(nm) for nm in names}}}}, open(out, "w"))
if scene:
    sim.run(until=amount)
else:
    sim.run(until=1e6, max_collisions=int(amount))
"""


def _library_symbols(cache: Path, loop: str) -> dict[str, int]:
    """{symbol: size [bytes]} of the functions in the cached object code of ``loop``
    (``run_loop_free`` or ``run_loop_gravity``), merged over its cached versions (layouts);
    the child reports where the version it loaded put them."""
    # both loops are closures of hsgran._loop._loop_of, cached under its name (every version of
    # either is merged: a symbol the loaded version lacks is never sampled)
    entries = sorted(cache.glob("hsgran_*/_loop._loop_of.locals.run_loop-*.nbc"))
    if not entries:
        raise SystemExit(f"no compiled {loop} in {cache}")
    import numba  # noqa: F401  (the cache entries unpickle into numba objects)

    def elf(obj):
        if isinstance(obj, bytes) and obj[:4] == b"\x7fELF":
            return obj
        if isinstance(obj, tuple | list):
            for item in obj:
                found = elf(item)
                if found is not None:
                    return found
        return None

    symbols = {}
    for entry in entries:
        with tempfile.NamedTemporaryFile(suffix=".o") as f:
            f.write(elf(pickle.loads(entry.read_bytes())))
            f.flush()
            nm = subprocess.run(["nm", "-S", f.name], capture_output=True, text=True,
                                check=True)
        for line in nm.stdout.splitlines():
            parts = line.split()
            if len(parts) == 4 and parts[2] in "tTwW":
                symbols[parts[3]] = int(parts[1], 16)
    return symbols


def _short(symbol: str) -> str:
    """Readable name of a numba-mangled symbol: its length-prefixed parts after ``_ZN`` (module
    path and function), up to the ABI tags."""
    if not symbol.startswith("_ZN"):
        return symbol
    rest, words = symbol[3:], []
    while rest[:1].isdigit():
        k = re.match(r"\d+", rest).group()
        words.append(rest[len(k):len(k) + int(k)])
        rest = rest[len(k) + int(k):]
    return ".".join(words) or symbol[:40]


def _run_child(n: int, amount: float, scene: str, cache: Path, out: Path,
               perf_data: Path | None):
    env = {**os.environ, "NUMBA_CACHE_DIR": str(cache), "NUMBA_ENABLE_PROFILING": "1"}
    code = CHILD.format(tools=str(ROOT / "tools"))
    cmd = [sys.executable, "-c", code, str(n), repr(amount), str(out), scene]
    if perf_data is not None:
        cmd = ["perf", "record", "-q", "-k", "1", "-e", "cpu-clock", "-F", str(SAMPLE_HZ),
               "-o", str(perf_data), *cmd]
    subprocess.run(cmd, check=True, env=env, cwd=ROOT, stdout=subprocess.DEVNULL)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--size", type=float, default=1e4, help="spheres of the gas (default 1e4)")
    ap.add_argument("--collisions", type=float, default=2e6,
                    help="collisions of the gas sampled after its warm-up (default 2e6)")
    ap.add_argument("--scene", default="",
                    help="profile this scene file instead of the gas (e.g. tools/scenes/pour.toml)")
    ap.add_argument("--until", type=float, default=None,
                    help="with --scene: simulated time to run to [s] (default: its duration)")
    ap.add_argument("--cache", type=Path, default=DEFAULT_CACHE,
                    help=f"numba cache of the profiled build (default {DEFAULT_CACHE})")
    args = ap.parse_args(argv)
    if shutil.which("perf") is None:
        print("perf not found: apt-get install linux-perf", file=sys.stderr)
        return 2
    n = round(args.size)
    scene = str(Path(args.scene).resolve()) if args.scene else ""
    if scene:
        from hsgran.errors import HsgranError
        from hsgran.scene import load_scene

        try:
            sc = load_scene(scene)
        except HsgranError as ex:
            print(f"profile_loop: {ex}", file=sys.stderr)
            return 2
        loop = "run_loop_gravity" if sc.effects.gravity else "run_loop_free"
        amount, first = (args.until or sc.duration), 1e-9
        what = f"{args.scene} to t = {amount:g} s"
    else:
        loop, amount, first = "run_loop_free", float(round(args.collisions)), 1.0
        what = f"elastic gas, N = {n:,}, warm-up and {round(args.collisions):,} collisions"
    from hsgran._jit import _source_digest

    cache = args.cache / _source_digest()
    with tempfile.TemporaryDirectory() as tmp:
        out = Path(tmp) / "addresses.json"
        perf_data = Path(tmp) / "perf.data"
        print(f"# compiling (or loading) the loop with debug information in {cache}",
              flush=True)
        out.write_text(json.dumps({"names": []}))
        _run_child(n, first, scene, cache, out, None)
        symbols = _library_symbols(cache, loop)
        out.write_text(json.dumps({"names": sorted(symbols)}))
        _run_child(n, amount, scene, cache, out, perf_data)
        addresses = json.loads(out.read_text())["addresses"]
        script = subprocess.run(["perf", "script", "-i", str(perf_data), "-F", "ip"],
                                capture_output=True, text=True, check=True).stdout
    ranges = sorted((a, a + symbols[nm], nm) for nm, a in addresses.items() if a)
    starts = [r[0] for r in ranges]
    counts: collections.Counter = collections.Counter()
    outside = 0
    for line in script.splitlines():
        parts = line.split()
        if not parts:
            continue
        ip = int(parts[0], 16)
        k = bisect.bisect_right(starts, ip) - 1
        if k >= 0 and ip < ranges[k][1]:
            counts[_short(ranges[k][2])] += 1
        else:
            outside += 1  # start-up, scene building, Python, numpy, the kernel
    inside = sum(counts.values())
    print(f"# {what}; {inside:,} samples in the loop's compiled code at {SAMPLE_HZ} Hz "
          f"({outside:,} elsewhere: start-up, Python)")
    print(f"{'share':>7}  function (share of the loop's samples)")
    listed = counts.most_common(TOP)
    for name, c in listed:
        print(f"{100 * c / inside:6.2f}%  {name}")
    other = inside - sum(c for _, c in listed)
    if other:
        print(f"{100 * other / inside:6.2f}%  other")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
