"""``hsgran sweep``: the command-line parser and handler (registered by :mod:`hsgran.cli`).

Only argparse and the light modules are imported here; Dask, numba and h5py load when the
command runs, so ``hsgran --help`` stays fast.
"""

from __future__ import annotations

import argparse
import sys

from hsgran.errors import EXIT_BAD_INPUT, InputError, MissingDependency

#: Exit code when the sweep ran but some case failed (bad input is 2).
EXIT_CASES_FAILED = 1

_DESCRIPTION = """\
Run one base scene over a grid of parameters and seeds on dask.distributed (a
local cluster with one worker per core, or --scheduler tcp://HOST:PORT), and
gather a summary row per case into RESULTS/results.csv. Each finished case is
kept in RESULTS/rows/, so rerunning the same command skips the cases already
done (after a crash of a worker or of this client, or to extend a sweep). A
failing case is recorded with its error and does not stop the sweep.
"""

_EPILOG = """\
sweep file (TOML; full description: docs/sweeps.md):
  [sweep]
  scene = "base.toml"              # relative to the sweep file
  combine = "grid"                 # or "zip"
  seeds = [0, 1, 2]                # optional; or { start = 0, count = 10 }
  summaries = ["e_n", "rebound_angle", "spin_after"]
  trajectories = false             # RESULTS/trajectories/<case>.h5
  [vary]                           # a scene key path, or a parameter name
  "contacts[0].sliding_friction" = [0.1, 0.2, 0.3]
  angle = { start = 1, stop = 89, num = 45 }   # or step = ..., log = true
  [set]                            # scene values computed from parameters
  "particles[0].velocity" = ["3.9*sin(radians(angle))", 0, "-3.9*cos(radians(angle))"]

summaries: {summaries}

examples:
  hsgran sweep scenarios/sweeps/kharaz_angle.toml -o kharaz/
  hsgran sweep sweep.toml -o out/ --scheduler tcp://10.0.0.5:8786
  hsgran plot kharaz/

exit codes: 0 every case succeeded, 1 some case failed (see results.csv), 2 bad input.
"""


def add_sweep_parser(sub) -> None:
    """Add the ``sweep`` subcommand to an argparse subparsers object."""
    from hsgran.sweep.summaries import SUMMARIES

    p = sub.add_parser(
        "sweep", help="run a scene over parameters and seeds on Dask, gather a results table",
        description=_DESCRIPTION, epilog=_EPILOG.replace("{summaries}", ", ".join(SUMMARIES)),
        formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("sweep", metavar="SWEEP.toml", help="sweep file")
    p.add_argument("-o", "--output", metavar="RESULTS", required=True,
                   help="results folder (created; reused to resume)")
    p.add_argument("--scheduler", metavar="ADDRESS",
                   help="use the Dask scheduler at ADDRESS (tcp://HOST:PORT) instead of a "
                        "local cluster; RESULTS should then be on a folder the workers share")
    p.add_argument("--workers", metavar="N",
                   help="worker processes of the local cluster (default: one per core)")
    p.add_argument("--retry-failed", action="store_true",
                   help="rerun the cases recorded as failed (by default they are skipped)")
    p.add_argument("--trajectories", action="store_true",
                   help="write every case's trajectory (as trajectories = true)")
    p.add_argument("--no-progress", action="store_true", help="no progress bar")


def _workers(text: str | None) -> int | None:
    if text is None:
        return None
    try:
        n = int(text)
    except ValueError:
        n = 0
    if n < 1:
        raise InputError(f"must be a whole number >= 1, got {text!r}", "--workers")
    return n


def cmd_sweep(args: argparse.Namespace) -> int:
    """``hsgran sweep``: run a sweep, print its summary."""
    from hsgran.sweep.runner import run_sweep
    from hsgran.sweep.spec import load_sweep
    from hsgran.sweep.store import prepare

    workers = _workers(args.workers)
    if args.scheduler is not None and workers is not None:
        raise InputError("--workers sizes the local cluster; it cannot be used with "
                         "--scheduler", "--workers")
    spec = load_sweep(args.sweep)
    prepare(args.output)
    try:
        report = run_sweep(spec, args.output, scheduler=args.scheduler, workers=workers,
                           retry_failed=args.retry_failed,
                           trajectories=True if args.trajectories else None,
                           progress=not args.no_progress)
    except MissingDependency as exc:
        print(f"hsgran: error: {' '.join(str(exc).split())}", file=sys.stderr)
        return EXIT_BAD_INPUT
    except OSError as exc:  # e.g. the scheduler address cannot be reached
        raise InputError(f"cannot reach the Dask scheduler: {' '.join(str(exc).split())}",
                         "--scheduler") from None
    for line in report.lines():
        print(line)
    print(f"results: {report.table}")
    return EXIT_CASES_FAILED if report.errors else 0
