"""The check every command-line test of bad input shares."""

from hsgran.cli import main
from hsgran.errors import EXIT_BAD_INPUT


def run_error(capsys, argv) -> str:
    """Run a command that must fail on bad input; return its one stderr line."""
    assert main(argv) == EXIT_BAD_INPUT
    out, err = capsys.readouterr()
    assert out == ""
    assert err.startswith("hsgran: error: ")
    assert err.count("\n") == 1, err
    assert err.endswith("\n")
    assert "Traceback" not in err
    return err
