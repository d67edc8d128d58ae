"""``report.md`` of a validation run (layer 6).

Layout: the verdict, the summary table (one row per check: case, quantity, reference, hsgran,
deviation, tolerance, result; a check over a sweep shows its worst point), the known
disagreements with their sentence, the tolerance rules, then one section per case with its
figure, notes and every compared point.
"""

from __future__ import annotations

import math
import os
from pathlib import Path

from hsgran import __version__
from hsgran.validation.core import FAIL, INFO, KNOWN, PASS, TOLERANCE_RULES, Check

#: Result column text of each status.
STATUS_TEXT = {PASS: "pass", FAIL: "**FAIL**", KNOWN: "known", INFO: "info"}


def _num(x: float) -> str:
    if x is None or (isinstance(x, float) and math.isnan(x)):
        return "—"
    if x == 0.0:
        return "0"
    ax = abs(x)
    if 1e-3 <= ax < 1e5:
        return f"{x:.6g}"
    return f"{x:.4e}"


def _dev(x: float) -> str:
    if math.isnan(x):
        return "—"
    return "0" if x == 0.0 else f"{x:+.2e}"


def _cell(text: str) -> str:
    return text.replace("|", "\\|").replace("\n", " ")


def _tolerance(check: Check, tol: float) -> str:
    if check.kind != "assert":
        return "—"
    if tol == 0.0:
        return "0 (exact)"
    return f"±{tol:.2e} ({check.rule})"


def summary_rows(report) -> list[list[str]]:
    """The rows of the summary table (strings), in report order."""
    rows = []
    for case in report.cases:
        if case.error:
            rows.append([case.name, "(case did not run)", "—", "—", "—", "—",
                         STATUS_TEXT[FAIL]])
            continue
        for c in case.checks:
            w = c.worst
            n = len(c.points)
            where = "" if n == 0 else (f" ({n} points; worst at {w.at})" if n > 1
                                       else f" ({w.at})")
            unit = f" [{c.unit}]" if c.unit and "[" not in c.quantity else ""
            if w is None:
                rows.append([case.name, _cell(c.quantity + unit + " (no points)"),
                             _cell(c.reference), "—", "—", "—", STATUS_TEXT[c.status]])
                continue
            rows.append([case.name, _cell(c.quantity + unit + where),
                         _cell(f"{_num(w.reference)} ({c.reference})"), _num(w.value),
                         _dev(w.deviation), _tolerance(c, w.tolerance),
                         STATUS_TEXT[c.status]])
    return rows


def summary_table(report) -> str:
    """The summary table as markdown."""
    head = ["case", "quantity", "reference", "hsgran", "deviation", "tolerance", "result"]
    lines = ["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
    lines += ["| " + " | ".join(r) + " |" for r in summary_rows(report)]
    return "\n".join(lines)


def case_table(report) -> str:
    """One row per case: its checks by result, the worst asserted deviation/tolerance, result."""
    head = ["case", "what", "checks", "pass", "fail", "known", "info",
            "worst deviation/tolerance", "result"]
    lines = ["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
    for case in report.cases:
        counts = {s: sum(c.status == s for c in case.checks) for s in (PASS, FAIL, KNOWN, INFO)}
        ratios = [p.ratio for c in case.checks if c.kind == "assert" for p in c.points]
        worst = "—" if not ratios else f"{max(ratios):.2g}"
        result = "pass" if case.passed else ("**FAIL** (error)" if case.error else "**FAIL**")
        lines.append(f"| {case.name} | {_cell(case.title)} | {len(case.checks)} | "
                     f"{counts[PASS]} | {counts[FAIL]} | {counts[KNOWN]} | {counts[INFO]} | "
                     f"{worst} | {result} |")
    return "\n".join(lines)


def _known(report) -> list[str]:
    """One bullet per distinct sentence of a known disagreement or qualitative comparison."""
    by_note: dict[str, list[str]] = {}
    for case in report.cases:
        for c in case.checks:
            if c.kind in ("known", "info") and c.note:
                worst = c.worst
                dev = "" if worst is None or math.isnan(worst.deviation) else (
                    f", largest |deviation| {abs(worst.deviation):.3g}")
                by_note.setdefault(c.note, []).append(f"{case.name}: {c.quantity}{dev}")
    out = []
    for note, where in by_note.items():
        listing = "; ".join(where[:6]) + (f"; and {len(where) - 6} more" if len(where) > 6
                                          else "")
        out.append(f"- {note} *({listing})*")
    return out


def _points_table(check: Check) -> str:
    lines = ["| at | reference | hsgran | deviation | tolerance | ok |",
             "|---|---|---|---|---|---|"]
    for p in check.points:
        ok = "—" if check.kind != "assert" else ("yes" if p.ok else "**no**")
        tol = "—" if check.kind != "assert" else ("0" if p.tolerance == 0.0
                                                  else f"{p.tolerance:.2e}")
        lines.append(f"| {_cell(p.at)} | {_num(p.reference)} | {_num(p.value)} | "
                     f"{_dev(p.deviation)} | {tol} | {ok} |")
    return "\n".join(lines)


def _relative(path: Path, start: Path) -> str:
    try:
        return Path(os.path.relpath(path, start)).as_posix()
    except ValueError:
        return str(path)


def render_report(report) -> str:
    """report.md as text."""
    from hsgran.validation import CASES

    what = {c.name: c.what for c in CASES}
    n_pass = sum(c.passed for c in report.cases)
    checks = [c for case in report.cases for c in case.checks]
    counts = {s: sum(c.status == s for c in checks) for s in (PASS, FAIL, KNOWN, INFO)}
    verdict = ("**PASS** — every case reproduces its reference within tolerance"
               if report.passed else
               f"**FAIL** — failing case(s): {', '.join(report.failed)}")
    scenes = ("the scene texts built into hsgran" if report.scenes_dir is None
              else f"`{_relative(report.scenes_dir, Path.cwd())}`")
    lines = [
        "# hsgran validation report", "",
        f"hsgran {__version__} · {len(report.cases)} cases ({n_pass} passed) · "
        f"{len(checks)} checks: {counts[PASS]} pass, {counts[FAIL]} fail, "
        f"{counts[KNOWN]} known disagreements, {counts[INFO]} qualitative · "
        f"wall time {report.wall_time:.1f} s · scenes from {scenes}", "",
        f"Result: {verdict}.", "",
        "Each case runs its scene files through the event-driven engine "
        "(`hsgran.engine.Simulation`) and compares the outcome with its reference. A row "
        "covering a sweep shows its worst point (largest deviation/tolerance); every point is "
        "listed in the case's section. *known* rows are documented disagreements of the model "
        "with the reference, reported and never counted as passes; *info* rows are qualitative "
        "comparisons whose source gives no number to hold a tolerance to. Deviation = hsgran − "
        "reference.", "",
        "## Cases at a glance", "", case_table(report), "",
        "## Summary", "", summary_table(report), "",
        "## Known disagreements and qualitative comparisons", "",
        *(_known(report) or ["None."]), "",
        "## Tolerances", "",
        "Every tolerance comes from the reference's own uncertainty or from round-off; none is "
        "tuned to make a case pass.", "",
        *[f"- **{name}**: {text}." for name, text in TOLERANCE_RULES.items()], "",
        "## Case details", "",
    ]
    for case in report.cases:
        lines += [f"### {case.name} — {case.title}", "",
                  f"{what.get(case.name, '')} Result: "
                  f"{'pass' if case.passed else '**FAIL**'} ({case.wall_time:.1f} s).", ""]
        if case.scenes:
            lines += ["Scene files: " + ", ".join(f"`{Path(s).name}`" for s in case.scenes), ""]
        if case.error:
            lines += ["The case stopped with an error:", "", "```", case.error.strip(), "```", ""]
        if case.figure is not None and case.figure.exists():
            lines += [f"![{case.name}]({_relative(case.figure, report.out_dir)})", ""]
        lines += [f"- {note}" for note in case.notes]
        if case.notes:
            lines.append("")
        for c in case.checks:
            lines += [f"<details><summary>{STATUS_TEXT[c.status]}: {_cell(c.quantity)} — "
                      f"{_cell(c.reference)} ({len(c.points)} points)</summary>", ""]
            if c.note:
                lines += [c.note, ""]
            lines += [_points_table(c), "", "</details>", ""]
    return "\n".join(lines)


def write_report(report) -> Path:
    """Write report.md into the report's directory; returns its path."""
    path = report.report_path
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(render_report(report), encoding="utf-8")
    return path
