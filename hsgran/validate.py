"""``hsgran validate``: run the validation cases and write the report (layer 6).

The work is in :mod:`hsgran.validation`; this module is the command-line face. The ``hsgran``
command line plugs it in with :func:`add_validate_parser` and :func:`cmd_validate`; it also runs
on its own: ``python -m hsgran.validate [--out DIR] [--case NAME] ...``.

Exit codes: 0 when every case passes, 1 when a case fails its tolerance (or stops with an
error), 2 on bad input (one line on stderr, no traceback).
"""

from __future__ import annotations

import argparse
import sys

from hsgran.errors import EXIT_BAD_INPUT, InputError, MissingDependency

#: Exit code when a case fails.
EXIT_FAILED = 1
#: Default output directory (the same as :data:`hsgran.validation.DEFAULT_OUT`; spelled out
#: here so that building the parser does not import the cases, the engine and scipy).
DEFAULT_OUT_NAME = "validation-report"

DESCRIPTION = (
    "Run hsgran's validation cases (the paper's normal, adhesive, oblique, spin, plate, "
    "incline and particle-particle cases and the Chung & Ooi benchmark tests 1-7) through the "
    "event-driven engine, compare each with its reference (closed forms, digitised benchmark "
    "curves, MODEL §7.1 anchors), and write one figure per case and report.md into the "
    "output directory. Exit code 1 when a case fails its tolerance.")


EPILOG = """\
'hsgran validate --list' lists the cases (* marks the --fast subset).
examples:
  hsgran validate
  hsgran validate --out report/ --case co4 --case kharaz_oblique
  hsgran validate --fast --no-progress
"""


def add_validate_parser(subparsers) -> argparse.ArgumentParser:
    """Add the ``validate`` subcommand to an argparse subparsers object; returns its parser."""
    p = subparsers.add_parser(
        "validate", help="run the validation cases and write a report with figures",
        description=DESCRIPTION, epilog=EPILOG,
        formatter_class=argparse.RawDescriptionHelpFormatter)
    _add_arguments(p)
    return p


def _add_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("--out", metavar="DIR", default=DEFAULT_OUT_NAME,
                   help="output directory for report.md and figures/ (default: "
                        f"{DEFAULT_OUT_NAME})")
    p.add_argument("--case", metavar="NAME", action="append",
                   help="run only this case (repeat, or separate names by commas)")
    p.add_argument("--fast", action="store_true",
                   help="run only the quick subset used by the test suite")
    p.add_argument("--list", action="store_true", help="list the cases and exit")
    p.add_argument("--scenes", metavar="DIR",
                   help="directory of the scene files (default: scenarios/validation of the "
                        "source tree, else the copies built into hsgran)")
    p.add_argument("--write-scenes", metavar="DIR",
                   help="write the validation scene files into DIR and exit")
    p.add_argument("--no-progress", action="store_true", help="no progress bar")


def cmd_validate(args: argparse.Namespace) -> int:
    """Handler of ``hsgran validate``.

    Returns:
        0 all cases pass, 1 a case failed, 2 bad input or missing matplotlib.

    Raises:
        InputError: an unknown case or a bad path (the command line prints it and exits 2).
    """
    from hsgran.validation import CASES, FAST_CASES, run_validation, write_scenes

    if args.list:
        for c in CASES:
            print(f"{c.name}: {c.title}{' *' if c.name in FAST_CASES else ''}")
        return 0
    if args.write_scenes:
        for path in write_scenes(args.write_scenes):
            print(f"wrote {path}")
        return 0
    if args.fast and args.case:
        raise InputError("give --fast or --case, not both", "--fast")
    try:
        report = run_validation(args.out, args.case, progress=not args.no_progress,
                                fast=args.fast, scenes_dir=args.scenes)
    except MissingDependency as exc:
        print(f"hsgran: error: {' '.join(str(exc).split())}", file=sys.stderr)
        return EXIT_BAD_INPUT
    print(summary_line(report))
    print(f"report: {report.report_path}")
    return 0 if report.passed else EXIT_FAILED


def summary_line(report) -> str:
    """One line: how many cases passed, the failures, the wall time."""
    n = len(report.cases)
    ok = n - len(report.failed)
    tail = f"; FAILED: {', '.join(report.failed)}" if report.failed else ""
    return f"validation: {ok}/{n} cases passed in {report.wall_time:.1f} s{tail}"


class _Parser(argparse.ArgumentParser):
    """Stand-alone parser whose usage errors are InputErrors (one line, exit 2)."""

    def error(self, message: str):
        raise InputError(f"{message} (see '{self.prog} --help')")


def main(argv: list[str] | None = None) -> int:
    """``python -m hsgran.validate``: the ``validate`` subcommand on its own.

    Returns:
        The exit code of :func:`cmd_validate`; 2 on bad input.
    """
    parser = _Parser(prog="hsgran validate", description=DESCRIPTION, epilog=EPILOG,
                     formatter_class=argparse.RawDescriptionHelpFormatter, allow_abbrev=False)
    _add_arguments(parser)
    try:
        try:
            args = parser.parse_args(argv)
        except SystemExit as exc:  # --help
            return exc.code if isinstance(exc.code, int) else 0
        return cmd_validate(args)
    except InputError as exc:
        print(f"hsgran: error: {' '.join(str(exc).split())}", file=sys.stderr)
        return EXIT_BAD_INPUT


if __name__ == "__main__":
    sys.exit(main())
