"""Run every case of a sweep on ``dask.distributed`` and gather the results.

A local cluster of worker *processes* (one single-threaded worker per core: the event loop is
serial and holds the GIL only briefly, but numba kernels and h5py do not share a process well
across threads) is started unless a scheduler address or a client is given. Each pending case
is one task (:func:`hsgran.sweep.case.execute_case`); the worker writes the case's row file
itself, so a finished case survives a crash of the client, and the client writes it too when
the worker could not (a worker on another machine without the shared folder, or a task that
Dask gave up on after its workers died). Results are taken as they complete, with a progress
bar over cases.

Dask retries a task whose worker died (up to its ``distributed.scheduler.allowed-failures``
setting, 3 by default) on another worker; a case that kills every worker it meets ends as a
``KilledWorker`` error row, like any other failing case.
"""

from __future__ import annotations

import os
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path

from hsgran import __version__
from hsgran.errors import MissingDependency
from hsgran.sweep import store
from hsgran.sweep.case import execute_case, one_line
from hsgran.sweep.spec import Case, SweepSpec
from hsgran.sweep.summaries import SUMMARIES

#: Prefix of the Dask task keys (the case id follows): shows in the dashboard.
TASK_PREFIX = "hsgran-case-"


@dataclass
class SweepReport:
    """What a call of :func:`run_sweep` did.

    Attributes:
        cases: Cases in the sweep.
        ran: Cases run now.
        skipped: Cases already done by an earlier run (rows found).
        failed: Cases run now that failed.
        failed_before: Skipped cases whose recorded row is a failure (rerun them with
            ``retry_failed``).
        wall_time: Wall time of the call [s], cluster start included.
        table: Path of results.csv.
        rows: The rows of every finished case of the sweep, by case index.
        errors: (index, one-line error) of every failed case of the sweep.
    """

    cases: int = 0
    ran: int = 0
    skipped: int = 0
    failed: int = 0
    failed_before: int = 0
    wall_time: float = 0.0
    table: Path | None = None
    rows: list[dict] = field(default_factory=list)
    errors: list[tuple[int, str]] = field(default_factory=list)

    @property
    def complete(self) -> bool:
        """Every case has a row."""
        return len(self.rows) == self.cases

    def lines(self) -> list[str]:
        """Human-readable summary."""
        rate = self.ran / self.wall_time if self.wall_time > 0 else 0.0
        out = [f"cases: {self.cases} in the sweep, {self.ran} run now ({self.failed} failed), "
               f"{self.skipped} already done"
               + (f" ({self.failed_before} of them failed: --retry-failed reruns them)"
                  if self.failed_before else ""),
               f"wall time {self.wall_time:.2f} s, {rate:.2f} cases/s"]
        if not self.complete:
            out.append(f"incomplete: {self.cases - len(self.rows)} cases have no result; "
                       "rerun the same command to finish")
        for index, error in self.errors[:5]:
            out.append(f"case {index} failed: {error}")
        if len(self.errors) > 5:
            out.append(f"... and {len(self.errors) - 5} more failed cases (see results.csv)")
        return out


def _import_dask():
    try:
        from dask.distributed import Client, LocalCluster, as_completed
    except ImportError:
        raise MissingDependency("sweeps need dask.distributed: pip install "
                                "'dask[distributed]'") from None
    return Client, LocalCluster, as_completed


def start_client(scheduler: str | None = None, workers: int | None = None):
    """A Dask client: to the scheduler at ``scheduler``, or to a new local cluster.

    Args:
        scheduler: Address such as ``tcp://host:8786``, or ``None`` for a local cluster.
        workers: Worker processes of the local cluster (default: one per core).

    Returns:
        ``(client, cluster)``; ``cluster`` is ``None`` for an existing scheduler. Close both.
    """
    Client, LocalCluster, _ = _import_dask()
    if scheduler is not None:
        return Client(scheduler), None
    cluster = LocalCluster(n_workers=workers or os.cpu_count() or 1, threads_per_worker=1,
                           processes=True, dashboard_address=":0")
    return Client(cluster), cluster


def manifest(spec: SweepSpec) -> dict:
    """The content of ``sweep.json`` for a sweep."""
    return {"name": spec.name, "sweep_file": spec.source, "scene": str(spec.scene_path),
            "parameters": spec.parameters, "seeds": spec.seeds is not None,
            "summaries": spec.summaries,
            "units": {n: SUMMARIES[n].unit for n in spec.summaries},
            "combine": spec.combine, "hsgran": __version__, "sweep_text": spec.text}


def task_of(spec: SweepSpec, case: Case, results: Path, trajectories: bool,
            retry: bool = False) -> dict:
    """The payload of one case for :func:`~hsgran.sweep.case.execute_case`."""
    traj = store.trajectory_path(results, case.case_id) if trajectories else None
    return {"scene_text": spec.scene_text, "source": str(spec.scene_path),
            "overrides": case.overrides, "summaries": spec.summaries,
            "row": str(store.row_path(results, case.case_id)), "retry": retry,
            "trajectory": None if traj is None else str(traj),
            "row_base": {"case": case.case_id, "index": case.index, "params": case.params,
                         "seed": case.seed}}


def run_sweep(spec: SweepSpec, results, *, client=None, scheduler: str | None = None,
              workers: int | None = None, retry_failed: bool = False,
              trajectories: bool | None = None, progress: bool = True,
              on_row: Callable[[dict], None] | None = None) -> SweepReport:
    """Run the cases of a sweep that have no row yet, and rebuild results.csv.

    Args:
        spec: The sweep (:func:`hsgran.sweep.spec.load_sweep`).
        results: Results folder (created if needed).
        client: A ``dask.distributed.Client`` to use (left open), or ``None``.
        scheduler: Scheduler address to connect to when no client is given; ``None``
            starts a local cluster.
        workers: Worker processes of the local cluster (default: one per core).
        retry_failed: Rerun the cases whose recorded row is a failure.
        trajectories: Write each case's trajectory (default: the sweep file's choice).
        progress: Show a progress bar over cases.
        on_row: Called with each new row as it arrives (in the client).

    Returns:
        The :class:`SweepReport`.

    Raises:
        InputError: bad results folder or a [set] expression that fails for some case.
        MissingDependency: dask.distributed is not installed.
    """
    t0 = time.perf_counter()
    root = store.prepare(results)
    cases = spec.cases()
    store.write_manifest(root, manifest(spec))
    want_traj = spec.trajectories if trajectories is None else trajectories
    if want_traj:
        (root / store.TRAJECTORIES).mkdir(exist_ok=True)
    rows: dict[int, dict] = {}
    pending: list[Case] = []
    report = SweepReport(cases=len(cases))
    for case in cases:
        row = store.read_row(store.row_path(root, case.case_id))
        if store.is_done(row, spec.summaries, retry_failed):
            rows[case.index] = {**row, "index": case.index, "params": case.params}
            report.skipped += 1
            report.failed_before += row["status"] != "ok"
        else:
            pending.append(case)
    bar = None
    own = None
    try:
        if pending:
            if progress:
                from tqdm import tqdm

                bar = tqdm(total=len(cases), initial=report.skipped, unit="case",
                           desc="sweep", smoothing=0.1)
            if client is None:
                client, cluster = start_client(scheduler, workers)
                own = (client, cluster)
            for row in _run(client, spec, pending, root, want_traj, retry_failed):
                rows[row["index"]] = row
                report.ran += 1
                report.failed += row["status"] != "ok"
                if bar is not None:
                    bar.update(1)
                    bar.set_postfix_str(f"{report.failed} failed", refresh=False)
                if on_row is not None:
                    on_row(row)
    finally:
        if bar is not None:
            bar.close()
        if own is not None:
            own[0].close()
            if own[1] is not None:
                own[1].close()
        report.rows = [rows[k] for k in sorted(rows)]
        report.errors = [(r["index"], r.get("error", "")) for r in report.rows
                         if r["status"] != "ok"]
        report.table = store.write_table(root, report.rows, spec.parameters, spec.summaries,
                                         spec.seeds is not None)
        report.wall_time = time.perf_counter() - t0
    return report


def _run(client, spec: SweepSpec, pending: list[Case], root: Path, trajectories: bool,
         retry: bool):
    """Submit the pending cases and yield their rows as they complete."""
    _, _, as_completed = _import_dask()
    by_key = {}
    futures = []
    for case in pending:
        task = task_of(spec, case, root, trajectories, retry)
        future = client.submit(execute_case, task, key=TASK_PREFIX + case.case_id, pure=False)
        by_key[future.key] = (case, task)
        futures.append(future)
    for future in as_completed(futures):
        case, task = by_key.pop(future.key)
        try:
            row = future.result()
        except Exception as exc:  # the task itself failed in Dask (e.g. KilledWorker)
            row = {**task["row_base"], "status": "error",
                   "error": f"dask: {one_line(exc)}", "summaries": {}, "wall_time": None}
        finally:
            future.release()
        path = store.row_path(root, case.case_id)
        if not path.exists():
            store.write_row(path, row)
        yield row
