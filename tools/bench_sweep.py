"""Benchmark of ``hsgran sweep``: is a sweep worth distributing with Dask?

For two workloads — the Kharaz oblique-impact sweep (45 cases of about a millisecond: the
scheduler's cost dominates) and an ensemble of granular gases over seeds (cases of about half a
second: the simulation dominates) — it measures:

* the wall time of one case run serially in this process (after a warm-up case);
* the sweep's wall time on a local Dask cluster of 1 and of 2 worker processes (workers
  started and warmed up beforehand: cluster start is reported separately);
* the speed-up from 1 to 2 workers;
* the scheduler's overhead per case: (1-worker sweep time − serial time) / cases.

Usage: ``.venv/bin/python tools/bench_sweep.py [--seeds 8] [--gas-duration 0.05]``.
"""

from __future__ import annotations

import argparse
import os
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from hsgran.sweep.case import execute_case  # noqa: E402
from hsgran.sweep.runner import run_sweep, task_of  # noqa: E402
from hsgran.sweep.spec import load_sweep  # noqa: E402

GAS_SWEEP = """\
[sweep]
name = "granular gas ensemble"
scene = "{scene}"
seeds = {{ start = 0, count = {seeds} }}
summaries = ["collisions", "kinetic_energy"]
[vary]
"scene.duration" = [{duration}]
"""


def serial_per_case(spec, folder: Path) -> float:
    """Mean wall time [s] of one case run in this process (after one warm-up case)."""
    cases = spec.cases()
    execute_case({**task_of(spec, cases[0], folder, False), "row": None})
    t0 = time.perf_counter()
    for case in cases:
        row = execute_case({**task_of(spec, case, folder, False), "row": None})
        assert row["status"] == "ok", row["error"]
    return (time.perf_counter() - t0) / len(cases)


def distributed_time(spec, workers: int, folder: Path) -> tuple[float, float]:
    """(cluster start [s], sweep wall time [s]) on a local cluster of ``workers`` processes."""
    from dask.distributed import Client, LocalCluster

    t0 = time.perf_counter()
    cluster = LocalCluster(n_workers=workers, threads_per_worker=1, processes=True,
                           dashboard_address=":0")
    client = Client(cluster)
    start = time.perf_counter() - t0
    try:
        warm = task_of(spec, spec.cases()[0], folder, False)
        warm["row"] = None
        addresses = list(client.scheduler_info()["workers"])
        client.gather([client.submit(execute_case, warm, workers=[a], pure=False)
                       for a in addresses])      # numba's cache loaded in every worker
        t0 = time.perf_counter()
        report = run_sweep(spec, folder / f"w{workers}", client=client, progress=False)
        wall = time.perf_counter() - t0
        if report.ran != len(spec.cases()) or report.errors:
            raise RuntimeError(f"the benchmark sweep did not run cleanly: {report.errors}")
    finally:
        client.close()
        cluster.close()
    return start, wall


def bench(name: str, spec, folder: Path) -> None:
    n = len(spec.cases())
    t_case = serial_per_case(spec, folder)
    start1, t1 = distributed_time(spec, 1, folder)
    start2, t2 = distributed_time(spec, 2, folder)
    overhead = (t1 - n * t_case) / n
    print(f"\n{name}: {n} cases")
    print(f"  one case, serial in-process      {1e3 * t_case:9.2f} ms")
    print(f"  serial total (cases x case)      {n * t_case:9.3f} s")
    print(f"  sweep, 1 worker                  {t1:9.3f} s  (cluster start {start1:.2f} s)")
    print(f"  sweep, 2 workers                 {t2:9.3f} s  (cluster start {start2:.2f} s)")
    print(f"  speed-up 1 -> 2 workers          {t1 / t2:9.2f} x")
    print(f"  scheduler overhead per case      {1e3 * overhead:9.2f} ms")


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--seeds", type=int, default=8, help="cases of the gas ensemble")
    p.add_argument("--gas-duration", type=float, default=0.05,
                   help="simulated time of one gas case [s]")
    args = p.parse_args(argv)
    print(f"machine: {os.cpu_count()} cores; NUMBA_DISABLE_JIT="
          f"{os.environ.get('NUMBA_DISABLE_JIT', '0')}")
    with tempfile.TemporaryDirectory(prefix="bench_sweep_") as tmp:
        folder = Path(tmp)
        bench("Kharaz oblique impacts (scenarios/sweeps/kharaz_angle.toml)",
              load_sweep(ROOT / "scenarios/sweeps/kharaz_angle.toml"), folder)
        gas = folder / "gas.toml"
        gas.write_text(GAS_SWEEP.format(scene=ROOT / "scenarios/granular_gas.toml",
                                        seeds=args.seeds, duration=args.gas_duration))
        bench(f"granular gas, 3000 spheres, {args.gas_duration:g} s, over seeds",
              load_sweep(gas), folder)
    return 0


if __name__ == "__main__":
    sys.exit(main())
