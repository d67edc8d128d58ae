"""The results folder of a sweep: one row file per finished case, a table rebuilt from them.

Layout of ``RESULTS/``::

    sweep.json            what was swept: parameters, summaries and units, the sweep file
    rows/<case id>.json   one finished case (written atomically: temporary file, then rename)
    trajectories/<id>.h5  each case's trajectory, when the sweep asks for them
    results.csv           every finished case of the current sweep, one line each, in order

A row file exists only once its case has finished (successfully or not), and a rename is
atomic on POSIX file systems, so a crash of a worker or of the client at any moment leaves
either a complete row or none: rerunning the sweep skips exactly the cases whose row exists.
``results.csv`` is derived data, rebuilt from the rows at the end of every run (also an
interrupted one).
"""

from __future__ import annotations

import contextlib
import csv
import io
import json
import math
import os
import tempfile
from pathlib import Path

from hsgran.errors import InputError

MANIFEST = "sweep.json"
ROWS = "rows"
TRAJECTORIES = "trajectories"
TABLE = "results.csv"
#: Columns of results.csv before the parameters, and after the summaries.
LEAD_COLUMNS = ("index", "case", "status")
TAIL_COLUMNS = ("wall_time", "error")


def prepare(results: str | os.PathLike) -> Path:
    """Create the results folder (and its rows/ folder) if needed.

    Raises:
        InputError: the path is a file, or cannot be created; naming ``-o``.
    """
    root = Path(results)
    if root.exists() and not root.is_dir():
        raise InputError(f"{root} is a file, not a folder", "-o")
    try:
        (root / ROWS).mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise InputError(f"cannot create {root}: {exc.strerror or exc}", "-o") from None
    return root


def row_path(results: str | os.PathLike, case_id: str) -> Path:
    """Row file of a case."""
    return Path(results) / ROWS / f"{case_id}.json"


def trajectory_path(results: str | os.PathLike, case_id: str) -> Path:
    """Trajectory file of a case."""
    return Path(results) / TRAJECTORIES / f"{case_id}.h5"


def atomic_write(path: str | os.PathLike, text: str) -> None:
    """Write a text file so that readers see the old file or the whole new one, never a part.

    The text goes to a temporary file in the same folder, is flushed to disk, then renamed
    over ``path`` (``os.replace`` is atomic within one POSIX file system).
    """
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    handle, name = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".part", dir=path.parent)
    try:
        with os.fdopen(handle, "w", encoding="utf-8") as f:
            f.write(text)
            f.flush()
            os.fsync(f.fileno())
        os.replace(name, path)
    except BaseException:
        with contextlib.suppress(FileNotFoundError):
            os.unlink(name)
        raise


def write_row(path: str | os.PathLike, row: dict) -> None:
    """Write one case's row file atomically (JSON; NaN written as NaN)."""
    atomic_write(path, json.dumps(row, indent=1, allow_nan=True) + "\n")


def read_row(path: str | os.PathLike) -> dict | None:
    """A row file's content, or ``None`` if it is missing or unreadable (then rerun)."""
    try:
        with open(path, encoding="utf-8") as f:
            row = json.load(f)
    except (OSError, ValueError):
        return None
    return row if isinstance(row, dict) and "status" in row else None


def is_done(row: dict | None, summaries, retry_failed: bool) -> bool:
    """Whether a case with this row needs no new run.

    A successful row counts as done when it holds every requested summary (a sweep that adds
    a summary reruns its cases); a failed one unless ``retry_failed``.
    """
    if row is None:
        return False
    if row.get("status") == "ok":
        return all(name in row.get("summaries", {}) for name in summaries)
    return not retry_failed


def write_manifest(results: str | os.PathLike, manifest: dict) -> None:
    """Write ``sweep.json``."""
    atomic_write(Path(results) / MANIFEST, json.dumps(manifest, indent=1) + "\n")


def read_manifest(results: str | os.PathLike) -> dict:
    """Read ``sweep.json``.

    Raises:
        InputError: not a results folder of ``hsgran sweep``.
    """
    path = Path(results) / MANIFEST
    try:
        with open(path, encoding="utf-8") as f:
            return json.load(f)
    except FileNotFoundError:
        raise InputError(f"{results} is not a results folder of 'hsgran sweep' "
                         f"(it has no {MANIFEST})") from None
    except (OSError, ValueError) as exc:
        raise InputError(f"cannot read {path}: {exc.__class__.__name__}") from None


def cell(value) -> str:
    """A value as CSV text: floats in their shortest exact form (read back bit for bit),
    vectors as JSON."""
    if value is None:
        return ""
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, float):
        return repr(value) if math.isfinite(value) else str(value)
    if isinstance(value, (list, dict)):
        return json.dumps(value)
    return str(value)


def write_table(results: str | os.PathLike, rows: list[dict], parameters, summaries,
                seeds: bool) -> Path:
    """Write ``results.csv`` from rows (ordered by case index).

    Columns: index, case (id), status, each swept key, seed (if the sweep has seeds), each
    summary, wall_time [s], error.
    """
    columns = [*LEAD_COLUMNS, *parameters, *(["seed"] if seeds else []), *summaries,
               *TAIL_COLUMNS]
    lines = []
    for row in sorted(rows, key=lambda r: r["index"]):
        values = {"index": row["index"], "case": row["case"], "status": row["status"],
                  **row.get("params", {}), "seed": row.get("seed"),
                  **row.get("summaries", {}), "wall_time": row.get("wall_time"),
                  "error": row.get("error", "")}
        lines.append([cell(values.get(c)) for c in columns])
    text = io.StringIO(newline="")
    writer = csv.writer(text)
    writer.writerow(columns)
    writer.writerows(lines)
    path = Path(results) / TABLE
    atomic_write(path, text.getvalue())
    return path


def read_table(results: str | os.PathLike) -> list[dict[str, str]]:
    """``results.csv`` as a list of dicts of strings.

    Raises:
        InputError: the table is missing.
    """
    path = Path(results) / TABLE
    try:
        with open(path, newline="", encoding="utf-8") as f:
            return list(csv.DictReader(f))
    except FileNotFoundError:
        raise InputError(f"{path} not found: run 'hsgran sweep' first") from None
