"""The figure of a sweep's results: each summary quantity against the first swept key.

``hsgran plot RESULTS/`` draws one panel per summary quantity (sharing the x axis, the first
[vary] key); the other swept keys make one line each (up to :data:`MAX_LINES`), seeds are drawn
as points with a line through their mean. Failed cases are left out and counted in the title.
A swept key whose values are not numbers (vectors, names) is drawn at positions 0, 1, ... with
its values as tick labels.
"""

from __future__ import annotations

import itertools
import json
import math
from collections import defaultdict

import numpy as np

from hsgran.sweep import store

#: Most lines (combinations of the other swept keys) in one panel before they become
#: indistinguishable; more are drawn as unlabelled points.
MAX_LINES = 8
#: Width and height of one panel [inch].
WIDTH, PANEL_HEIGHT = 8.0, 2.4
#: A positive x range wider than this ratio gets a logarithmic axis.
LOG_RATIO = 100.0


def _number(text: str) -> float | None:
    try:
        return float(text)
    except ValueError:
        return None


def _value(text: str) -> float:
    x = _number(text)
    return math.nan if x is None else x


def sweep_figure(results, Figure):
    """The matplotlib figure of a results folder.

    Args:
        results: Results folder of ``hsgran sweep``.
        Figure: ``matplotlib.figure.Figure`` (imported by the caller).

    Raises:
        InputError: not a results folder, or no finished case to draw.
    """
    from hsgran.errors import InputError

    man = store.read_manifest(results)
    rows = store.read_table(results)
    ok = [r for r in rows if r["status"] == "ok"]
    if not ok:
        raise InputError(f"{results}: no successful case to plot ({len(rows)} failed)")
    params, summaries, units = man["parameters"], man["summaries"], man.get("units", {})
    xkey, others = params[0], params[1:]
    xs = [_number(r[xkey]) for r in ok]
    categorical = any(x is None for x in xs)
    labels = list(dict.fromkeys(r[xkey] for r in ok))
    pos = ({t: float(k) for k, t in enumerate(labels)} if categorical
           else {r[xkey]: float(r[xkey]) for r in ok})
    groups = defaultdict(list)
    for r in ok:
        groups[tuple(r[k] for k in others)].append(r)
    fig = Figure(figsize=(WIDTH, PANEL_HEIGHT * len(summaries) + 0.8), layout="constrained")
    axes = fig.subplots(len(summaries), 1, sharex=True, squeeze=False)[:, 0]
    colours = itertools.cycle(f"C{k}" for k in range(10))
    for combo, members in sorted(groups.items()):
        colour = next(colours)
        label = ", ".join(f"{k} = {_short(v)}" for k, v in zip(others, combo, strict=True))
        labelled = len(groups) <= MAX_LINES and bool(others)
        by_x = defaultdict(list)
        for r in members:
            by_x[pos[r[xkey]]].append(r)
        x_sorted = sorted(by_x)
        for ax, name in zip(axes, summaries, strict=True):
            xp = [pos[r[xkey]] for r in members]
            yp = [_value(r[name]) for r in members]
            ax.plot(xp, yp, ls="none", marker="o", ms=3, color=colour, alpha=0.6)
            mean = [float(np.nanmean([_value(r[name]) for r in by_x[x]]))
                    if any(not math.isnan(_value(r[name])) for r in by_x[x]) else math.nan
                    for x in x_sorted]
            ax.plot(x_sorted, mean, color=colour, lw=1.2,
                    label=label if labelled and ax is axes[0] else None)
    for ax, name in zip(axes, summaries, strict=True):
        unit = units.get(name, "")
        ax.set_ylabel(f"{name} [{unit}]" if unit else name)
        ax.grid(True, alpha=0.3)
    values = sorted(set(pos.values()))
    if categorical:
        axes[-1].set_xticks(range(len(labels)), [_short(t) for t in labels], rotation=30)
    elif values[0] > 0 and values[-1] / values[0] > LOG_RATIO:
        axes[-1].set_xscale("log")
    axes[-1].set_xlabel(xkey)
    if len(groups) <= MAX_LINES and others:
        axes[0].legend(fontsize="small")
    failed = len(rows) - len(ok)
    seeds = " (points: seeds; line: their mean)" if man.get("seeds") else ""
    fig.suptitle(f"{man.get('name', 'sweep')}: {len(ok)} cases{seeds}"
                 + (f", {failed} failed cases not shown" if failed else ""))
    return fig


def _short(text: str, limit: int = 24) -> str:
    try:
        value = json.loads(text)
    except ValueError:
        value = text
    out = f"{value:.4g}" if isinstance(value, float) else str(value)
    return out if len(out) <= limit else out[:limit - 3] + "..."
