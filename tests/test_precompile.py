"""``hsgran compile`` fills numba's on-disk cache with the versions of the event loop that a run
looks up, and refuses bad arguments in one line."""

import subprocess
import sys

import numba
import pytest

from hsgran.cli import main
from hsgran.precompile import VERSIONS, compile_all, default_jobs
from tests.cli_errors import run_error


@pytest.mark.parametrize(("argv", "expected"), [
    (["compile", "gravty"], "unknown version 'gravty' (did you mean 'gravity'?)"),
    (["compile", "--jobs", "0"], "--jobs must be a whole number >= 1, not '0'"),
    (["compile", "--jobs", "two"], "--jobs must be a whole number >= 1, not 'two'"),
])
def test_bad_arguments_give_one_error_line_and_exit_code_2(capsys, argv, expected):
    assert expected in run_error(capsys, argv)


def test_default_jobs_are_between_one_and_the_number_of_versions():
    assert 1 <= default_jobs() <= len(VERSIONS)


@pytest.mark.skipif(numba.config.DISABLE_JIT, reason="needs the compiled kernels")
def test_a_compiled_version_is_then_loaded_from_the_cache():
    # compiled here (or already in the cache from setup or an earlier test) ...
    compile_all(["free"], jobs=1, report=lambda line: None)
    # ... so that a fresh interpreter loads it instead of compiling it again: a cold compile
    # takes a minute, a cache hit well under a second; the dispatcher says which it was
    code = ("from hsgran import _loop\n"
            "from hsgran.precompile import compile_version\n"
            "compile_version('free')\n"
            "stats = _loop.run_loop_free.stats\n"
            "print(sum(stats.cache_hits.values()), sum(stats.cache_misses.values()))\n")
    out = subprocess.run([sys.executable, "-c", code], check=True, capture_output=True,
                         text=True, timeout=600).stdout.split()
    hits, misses = int(out[0]), int(out[1])
    assert (hits, misses) == (1, 0)


def test_without_jit_there_is_nothing_to_compile(capsys, monkeypatch):
    monkeypatch.setattr(numba.config, "DISABLE_JIT", True)
    assert main(["compile"]) == 0
    assert "nothing to compile" in capsys.readouterr().out


@pytest.mark.skipif(numba.config.DISABLE_JIT, reason="needs the compiled kernels")
def test_the_command_says_what_it_compiles_then_each_time_and_the_total(capsys):
    assert main(["compile", "free", "--jobs", "1"]) == 0
    lines = capsys.readouterr().out.splitlines()
    assert len(lines) == 3
    assert lines[0].startswith("compiling the event loop (free) with 1 job(s)")
    assert lines[1].startswith("free: ")
    assert lines[1].endswith(" s")
    assert lines[2].startswith("compiled 1 version(s) of the event loop in ")
