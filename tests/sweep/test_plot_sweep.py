"""``hsgran plot RESULTS/``: each summary quantity against the swept keys."""

from __future__ import annotations

import math

import pytest

from hsgran.cli import main
from hsgran.sweep import store
from hsgran.sweep.figure import sweep_figure
from tests.cli_errors import run_error

pytest.importorskip("matplotlib")


def results(tmp_path, failed=1):
    """A results folder: e_n(v) for two frictions and two seeds, one failed case."""
    root = store.prepare(tmp_path / "res")
    store.write_manifest(root, {"name": "test sweep", "parameters": ["v", "mu"],
                                "seeds": True, "summaries": ["e_n", "collisions"],
                                "units": {"e_n": "-", "collisions": "-"}})
    rows, k = [], 0
    for v in (0.1, 1.0, 10.0, 100.0):
        for mu in (0.1, 0.3):
            for seed in (0, 1):
                ok = k >= failed
                rows.append({"index": k, "case": f"c{k}", "status": "ok" if ok else "error",
                             "params": {"v": v, "mu": mu}, "seed": seed,
                             "summaries": {"e_n": 1.0 / (1.0 + v * mu) + 0.01 * seed,
                                           "collisions": 1.0} if ok else {},
                             "wall_time": 0.01, "error": "" if ok else "boom"})
                k += 1
    store.write_table(root, rows, ["v", "mu"], ["e_n", "collisions"], True)
    return root


def test_panels_lines_and_mean_over_seeds(tmp_path):
    from matplotlib.figure import Figure

    fig = sweep_figure(results(tmp_path), Figure)
    axes = fig.axes
    assert [ax.get_ylabel() for ax in axes] == ["e_n [-]", "collisions [-]"]
    assert axes[-1].get_xlabel() == "v"
    assert axes[-1].get_xscale() == "log"          # 0.1 .. 100: four decades
    lines = [ln for ln in axes[0].get_lines() if ln.get_linestyle() != "None"]
    assert [ln.get_label() for ln in lines] == ["mu = 0.1", "mu = 0.3"]
    x, y = lines[1].get_data()                      # mu = 0.3: mean over the two seeds
    assert list(x) == [0.1, 1.0, 10.0, 100.0]
    assert y[0] == pytest.approx(1.0 / 1.03 + 0.005)
    assert "1 failed cases not shown" in fig._suptitle.get_text()
    assert not math.isnan(y[-1])


def test_cli_plot_of_a_results_folder(tmp_path, capsys):
    root = results(tmp_path)
    assert main(["plot", str(root)]) == 0
    assert (root / "summary.png").stat().st_size > 0
    assert "summary.png" in capsys.readouterr().out
    err = run_error(capsys, ["plot", str(root), "--particles", "0"])
    assert "--particles: applies to a trajectory" in err
    empty = store.prepare(tmp_path / "empty")
    assert "not a results folder" in run_error(capsys, ["plot", str(empty), "-o",
                                                         str(tmp_path / "x.png")])
