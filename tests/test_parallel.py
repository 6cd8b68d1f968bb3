"""Side-by-side work in forked workers (mst_cli/parallel.py)."""

import os
import sys
from concurrent.futures.process import BrokenProcessPool

import pytest

from mst_cli.errors import InputError
from mst_cli.parallel import can_fork, fork_map, one_blas_thread, workers

WORKERS_ALLOWED = "a whole number of worker processes >= 1 (1: work in turn)"

needs_fork = pytest.mark.skipif(not can_fork(), reason="side-by-side work forks, on Linux only")


def _pid_and_square(x):
    if x < 0:
        raise ValueError(f"no square of {x}")
    return os.getpid(), x * x


@needs_fork
def test_results_come_back_in_order_from_other_processes(monkeypatch):
    monkeypatch.setenv("MST_WORKERS", "2")
    out = fork_map(_pid_and_square, list(range(7)))
    assert [sq for _, sq in out] == [x * x for x in range(7)]
    assert os.getpid() not in {pid for pid, _ in out}


@needs_fork
def test_a_closure_runs_as_it_is_without_pickling(monkeypatch):
    monkeypatch.setenv("MST_WORKERS", "2")
    local = {"offset": 10}  # a lambda over a local: forked, never pickled
    assert fork_map(lambda x: x + local["offset"], [1, 2, 3]) == [11, 12, 13]


@needs_fork
def test_an_exception_in_a_worker_is_raised_here(monkeypatch):
    monkeypatch.setenv("MST_WORKERS", "2")
    with pytest.raises(ValueError, match="no square of -3"):
        fork_map(_pid_and_square, [1, -3, 2])


@needs_fork
def test_a_worker_that_dies_is_an_error_not_a_wait(monkeypatch):
    monkeypatch.setenv("MST_WORKERS", "2")
    with pytest.raises(BrokenProcessPool):
        fork_map(lambda x: os._exit(3) if x == 1 else x, [0, 1, 2])


@pytest.mark.parametrize("setting, items", [("1", [1, 2, 3]), ("4", [1])])
def test_one_worker_or_one_item_is_left_to_the_caller(monkeypatch, setting, items):
    monkeypatch.setenv("MST_WORKERS", setting)
    assert fork_map(_pid_and_square, items) is None


@pytest.mark.parametrize("text", ["0", "-1", "two", "1.5"])
def test_a_bad_worker_count_names_the_variable(monkeypatch, text):
    monkeypatch.setenv("MST_WORKERS", text)
    with pytest.raises(InputError, match="MST_WORKERS"):
        workers()


def _start_group(script: str):
    """``python -c script`` with two workers, leading a process group of its own."""
    import subprocess

    return subprocess.Popen(
        [sys.executable, "-c", script],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        start_new_session=True,
        env={**os.environ, "MST_WORKERS": "2"},
    )


@needs_fork
def test_ctrl_c_ends_the_workers_with_their_parent(tmp_path):
    """SIGINT to the process group (a terminal's Ctrl-C) mid-work: the workers end at once and
    quietly, the parent reports the interrupt, and no process of the group is left."""
    import signal
    import time

    # Python's own Ctrl-C handler, as at a terminal: a test run started in the background
    # inherits SIGINT ignored, and Python then installs none
    script = (
        "import signal, time\nsignal.signal(signal.SIGINT, signal.default_int_handler)\n"
        "from mst_cli.parallel import fork_map\nprint('ready', flush=True)\n"
        "fork_map(lambda x: x == 1 or print('working', flush=True) or time.sleep(60), [1, 2])\n"
    )
    proc = _start_group(script)
    assert proc.stdout.readline().strip() == "ready"
    assert proc.stdout.readline().strip() == "working"  # one worker inside its task, one idle
    time.sleep(0.2)
    t0 = time.monotonic()
    os.killpg(proc.pid, signal.SIGINT)
    _, err = proc.communicate(timeout=30)
    assert time.monotonic() - t0 < 10  # not the tasks' 60 s
    assert proc.returncode != 0 and "KeyboardInterrupt" in err
    assert err.count("Traceback") == 1  # the parent's alone
    time.sleep(0.2)
    with pytest.raises(ProcessLookupError):
        os.killpg(proc.pid, 0)


@needs_fork
def test_a_sigint_the_parent_ignores_leaves_its_workers_working():
    """A process that ignores SIGINT (a shell's background job) keeps its workers through one:
    the group's signal ends nothing, and every item comes back."""
    import signal
    import time

    script = (
        "import os, signal, time\nsignal.signal(signal.SIGINT, signal.SIG_IGN)\n"
        "from mst_cli.parallel import fork_map\nprint('ready', flush=True)\n"  # one write a line: two workers
        "print(fork_map(lambda x: os.write(1, b'working\\n') and time.sleep(1) or 10 * x, [1, 2]), flush=True)\n"
    )
    proc = _start_group(script)
    assert proc.stdout.readline().strip() == "ready"
    assert proc.stdout.readline().strip() == "working"
    time.sleep(0.1)
    os.killpg(proc.pid, signal.SIGINT)
    out, err = proc.communicate(timeout=30)
    assert proc.returncode == 0, err
    assert out.strip().splitlines()[-1] == "[10, 20]"


def test_a_bad_worker_count_is_one_line_and_exit_2_from_the_command(tmp_path, monkeypatch):
    from pathlib import Path

    from click.testing import CliRunner

    from mst_cli.cli.app import main

    monkeypatch.setenv("MST_WORKERS", "zero")
    spec = Path(__file__).resolve().parents[1] / "configs" / "mohammadi2021.yaml"
    r = CliRunner().invoke(main, ["design", str(spec), "--pareto", "3", "--out", str(tmp_path / "o"), "-q"])
    assert r.exit_code == 2
    assert r.output.strip().splitlines() == ["mst: invalid input: MST_WORKERS = 'zero': " + WORKERS_ALLOWED]
    assert not (tmp_path / "o").exists()


def _blas_threads() -> list[int]:
    from threadpoolctl import threadpool_info

    return [lib["num_threads"] for lib in threadpool_info() if lib["user_api"] == "blas"]


def test_one_blas_thread_holds_blas_to_one_thread_inside_the_block_only():
    before = _blas_threads()
    assert before, "numpy's BLAS is not visible to threadpoolctl"
    with one_blas_thread():
        assert _blas_threads() == [1] * len(before)
    assert _blas_threads() == before


@pytest.mark.skipif(not can_fork(), reason="fork_map forks on Linux only")
def test_a_worker_runs_one_blas_thread_and_the_block_leaves_it_so(monkeypatch):
    monkeypatch.setenv("MST_WORKERS", "2")
    seen = fork_map(_threads_in_block, [0, 1])
    assert seen == [([1] * len(_blas_threads()),) * 2] * 2


def _threads_in_block(_):
    outside = _blas_threads()
    with one_blas_thread():
        return (outside, _blas_threads())
