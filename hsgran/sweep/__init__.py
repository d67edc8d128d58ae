"""Sweeps and ensembles: one base scene over parameters and seeds, on dask.distributed.

Modules, one job each:

* :mod:`.spec` — the sweep file (TOML) and its expansion into :class:`~.spec.Case` objects;
* :mod:`.expr` — the arithmetic of ``[set]`` expressions (no ``eval``);
* :mod:`.summaries` — the named summary quantities of one run;
* :mod:`.case` — one case: scene + overrides → run → summaries (what a Dask task runs);
* :mod:`.store` — the results folder: row files written atomically, results.csv;
* :mod:`.runner` — submission to Dask, progress, resumption;
* :mod:`.cli` — ``hsgran sweep``.

The Python API (the heavy parts are imported on first use)::

    from hsgran.sweep import load_sweep, run_sweep, run_case
    report = run_sweep(load_sweep("scenarios/sweeps/kharaz_angle.toml"), "kharaz/")
    row = run_case("scene.toml", {"contacts[0].sliding_friction": 0.2}, ["e_n"])

Layer 6 (uses the engine, the writer and the public API).
"""

from __future__ import annotations

from hsgran.sweep.cli import add_sweep_parser, cmd_sweep

__all__ = ["SUMMARIES", "add_sweep_parser", "cmd_sweep", "load_sweep", "parse_sweep",
           "run_case", "run_sweep", "start_client"]

_LAZY = {"load_sweep": "spec", "parse_sweep": "spec", "SUMMARIES": "summaries",
         "run_case": "case", "run_sweep": "runner", "start_client": "runner"}


def __getattr__(name):
    if name in _LAZY:
        import importlib

        return getattr(importlib.import_module(f"hsgran.sweep.{_LAZY[name]}"), name)
    raise AttributeError(f"module 'hsgran.sweep' has no attribute {name!r}")
