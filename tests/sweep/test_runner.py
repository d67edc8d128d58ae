"""Sweeps on a 2-worker local Dask cluster: the same results as the cases run one by one,
resumption after a killed worker or client without redoing finished cases, failing cases
recorded. Scenes are tiny (one sphere, 4 ms), so this also runs with NUMBA_DISABLE_JIT=1."""

from __future__ import annotations

import math
import os
import signal
import subprocess
import sys
import textwrap

import pytest

from hsgran.sweep import store
from hsgran.sweep.case import run_case
from hsgran.sweep.runner import TASK_PREFIX, run_sweep
from hsgran.sweep.spec import load_sweep
from tests.sweep.scenes import BALL, SUMMARIES, write

distributed = pytest.importorskip("dask.distributed")

#: Shape of the test cluster: two single-threaded worker processes (the machines have 2 cores).
N_WORKERS = 2


def new_cluster():
    cluster = distributed.LocalCluster(n_workers=N_WORKERS, threads_per_worker=1,
                                       processes=True, dashboard_address=":0")
    return distributed.Client(cluster), cluster


@pytest.fixture(scope="module")
def client():
    c, cluster = new_cluster()
    yield c
    c.close()
    cluster.close()


def same(a: float, b: float) -> bool:
    """Bit-for-bit equal, NaN equal to NaN."""
    return (math.isnan(a) and math.isnan(b)) or a == b


def row_times(results) -> dict:
    return {p.name: p.stat().st_mtime_ns for p in (results / store.ROWS).glob("*.json")}


def test_results_equal_the_cases_run_one_by_one(tmp_path, client):
    spec = load_sweep(write(tmp_path))
    out = tmp_path / "out"
    report = run_sweep(spec, out, client=client, progress=False)
    assert (report.cases, report.ran, report.skipped, report.errors) == (6, 6, 0, [])
    table = store.read_table(out)
    assert [int(r["index"]) for r in table] == list(range(6))
    for case, row, line in zip(spec.cases(), report.rows, table, strict=True):
        alone = run_case(BALL, case.overrides, SUMMARIES)
        assert row["status"] == "ok"
        assert row["params"] == case.params
        for name in SUMMARIES:
            assert same(row["summaries"][name], alone[name]), name
            assert same(float(line[name]), alone[name]), name   # the CSV reads back exactly
        assert alone["collisions"] >= 1.0
    # the swept values reached the scene: friction changes the spin after the impact
    spins = {(r["params"]["contacts[0].sliding_friction"], r["params"]["angle"]):
             r["summaries"]["spin_after"] for r in report.rows}
    assert spins[(0.1, 50.0)] < spins[(0.3, 50.0)]   # sliding, then rolling at 50 degrees

    before = row_times(out)
    again = run_sweep(spec, out, client=client, progress=False)
    assert (again.ran, again.skipped) == (0, 6)
    assert row_times(out) == before
    assert store.read_table(out) == table


def test_a_broken_case_is_recorded_and_the_rest_complete(tmp_path, client):
    sweep = write(tmp_path, sweep=textwrap.dedent("""\
        [sweep]
        scene = "ball.toml"
        summaries = ["e_n", "collisions"]
        [vary]
        "particles[0].radius" = [0.005, -1.0, 0.004]
        """))
    out = tmp_path / "out"
    report = run_sweep(load_sweep(sweep), out, client=client, progress=False)
    assert (report.ran, report.failed) == (3, 1)
    message = ("particles[0].radius: must be > 0 m, got -1.0 (value set by the override "
               "particles[0].radius)")
    assert report.errors == [(1, message)]
    table = store.read_table(out)
    assert [r["status"] for r in table] == ["ok", "error", "ok"]
    assert table[1]["error"] == message
    assert float(table[2]["collisions"]) >= 1.0
    assert any(line == f"case 1 failed: {message}" for line in report.lines())

    again = run_sweep(load_sweep(sweep), out, client=client, progress=False)
    assert (again.ran, again.skipped, again.failed_before) == (0, 3, 1)
    retried = run_sweep(load_sweep(sweep), out, client=client, progress=False,
                        retry_failed=True)
    assert (retried.ran, retried.failed, retried.skipped) == (1, 1, 2)


def test_a_killed_worker_loses_no_case_and_the_rerun_redoes_none(tmp_path):
    """A worker process dies while it runs case 3: Dask reruns that case on a worker that is
    alive, and a rerun runs nothing. Dask also starts again the finished cases whose results
    were held by the dead worker; those find their row file and are not simulated again."""
    spec = load_sweep(write(tmp_path))
    cases = spec.cases()
    victim = TASK_PREFIX + cases[3].case_id
    marker, log = tmp_path / "killed", tmp_path / "executions.log"

    class KillOnce(distributed.WorkerPlugin):
        """Exit the worker process the first time it starts the victim's task; log every
        task start."""

        def transition(self, key, start, finish, **kwargs):
            if finish != "executing":
                return
            with open(log, "a") as f:
                f.write(f"{key}\n")
            if key == victim and not marker.exists():
                marker.write_text("")
                os._exit(1)

    c, cluster = new_cluster()
    try:
        c.register_plugin(KillOnce(), name="kill-once")
        out = tmp_path / "out"
        reused = []
        report = run_sweep(spec, out, client=c, progress=False,
                           on_row=lambda row: reused.append(row.get("reused", False)))
        assert marker.exists()
        assert (report.ran, report.errors) == (6, [])
        assert all(r["status"] == "ok" for r in report.rows)
        started = log.read_text().split()
        assert started.count(victim) == 2
        assert sorted(set(started)) == sorted(TASK_PREFIX + k.case_id for k in cases)
        assert len(started) == len(cases) + 1 + sum(reused)
        before = row_times(out)
        again = run_sweep(spec, out, client=c, progress=False)
        assert (again.ran, again.skipped) == (0, 6)
        assert row_times(out) == before
    finally:
        c.close()
        cluster.close()


CLIENT_KILLED_AFTER = 2
CLIENT = f"""
import os, signal, sys
from hsgran.sweep import load_sweep, run_sweep

def on_row(row, seen=[]):
    seen.append(row)
    if len(seen) == {CLIENT_KILLED_AFTER}:
        os.kill(os.getpid(), signal.SIGKILL)

run_sweep(load_sweep(sys.argv[1]), sys.argv[2], workers={N_WORKERS}, progress=False,
          on_row=on_row)
"""


def test_a_killed_client_loses_no_finished_case(tmp_path):
    """The client is killed (SIGKILL) after two cases came back; the rerun keeps every row
    written before and runs only the rest."""
    sweep = write(tmp_path)
    out = tmp_path / "out"
    proc = subprocess.Popen([sys.executable, "-c", CLIENT, str(sweep), str(out)],
                            start_new_session=True, stderr=subprocess.DEVNULL)
    try:
        assert proc.wait(timeout=300) == -signal.SIGKILL
    finally:
        try:  # the cluster's processes were the client's children: end them too
            os.killpg(proc.pid, signal.SIGKILL)
        except ProcessLookupError:
            pass
    before = row_times(out)
    assert CLIENT_KILLED_AFTER <= len(before) <= 6
    assert not (out / store.TABLE).exists()
    c, cluster = new_cluster()
    try:
        report = run_sweep(load_sweep(sweep), out, client=c, progress=False)
    finally:
        c.close()
        cluster.close()
    assert (report.skipped, report.ran) == (len(before), 6 - len(before))
    assert report.complete
    assert not report.errors
    after = row_times(out)
    assert {k: after[k] for k in before} == before
    assert len(store.read_table(out)) == 6
