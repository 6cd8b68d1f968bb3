"""Independent work side by side, one forked worker process per core.

Two places in mst do several pieces of independent, deterministic work whose results are
small: a stack's missing L2 laws (half a second each, :mod:`mst_cli.model.mechanics.law_cache`)
and the Pareto front's weightings (:func:`mst_cli.design.batching.prefer_many`). :func:`fork_map`
runs them in worker processes forked from this one, so a worker starts with everything
already imported and costs milliseconds; each result comes back pickled. Where fork is not
the platform's safe default (not Linux, or another thread running here) or ``MST_WORKERS=1``,
it declines and the caller works in turn. Each result is the same function of its input
either way (the callers' tests compare them bit for bit).
"""

from __future__ import annotations

import contextlib
import os
import signal
import sys
import threading
from collections.abc import Callable, Iterator, Sequence
from typing import Any

from mst_cli.errors import InputError

WORKERS_ENV = "MST_WORKERS"  # worker processes [default: the cores this process may run on]

_TASK: list[Callable[[Any], Any]] = []  # what the forked workers call, inherited through fork


def workers() -> int:
    """Worker processes to use: ``MST_WORKERS`` if set (a whole number >= 1), else the cores
    this process may run on."""
    text = os.environ.get(WORKERS_ENV, "").strip()
    if not text:
        return len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else (os.cpu_count() or 1)
    if not text.isdigit() or int(text) < 1:
        raise InputError(WORKERS_ENV, text, "a whole number of worker processes >= 1 (1: work in turn)")
    return int(text)


def can_fork() -> bool:
    """Fork only where it is the platform's own default and no other thread could hold a lock."""
    return sys.platform.startswith("linux") and threading.active_count() == 1


def _worker() -> None:
    """A worker's first act: Ctrl-C (SIGINT to the terminal's process group) ends it at once and
    quietly, idle or busy, whatever handler it inherited (mst's reports the interrupt); this
    process, which got the same signal, reports it once. Where this process ignores SIGINT (a
    shell starts background jobs so), the worker ignores it too: a signal its parent survives
    must not kill the parent's work."""
    if signal.getsignal(signal.SIGINT) != signal.SIG_IGN:
        signal.signal(signal.SIGINT, signal.SIG_DFL)
    _IN_WORKER[:] = [True]


_IN_WORKER: list[bool] = []  # [True] in a forked worker, whose BLAS already runs one thread


@contextlib.contextmanager
def one_blas_thread() -> Iterator[None]:
    """BLAS limited to one thread inside the block, for many small solves whose threads cost more
    than they give. A no-op in a :func:`fork_map` worker, which runs with one already (setting
    it again there made a three-layer stack's L2 laws 0.1 s slower, 0.59 against 0.48 s in an
    ad hoc paired loop of fresh processes)."""
    if _IN_WORKER:
        yield
        return
    from threadpoolctl import threadpool_limits  # deferred: only where a dear rung solves

    with threadpool_limits(limits=1, user_api="blas"):
        yield


def _call(item: Any) -> Any:
    return _TASK[0](item)


def fork_map(function: Callable[[Any], Any], items: Sequence[Any]) -> list | None:
    """``[function(item) for item in items]`` computed by up to :func:`workers` forked processes,
    in order; None (nothing done) when fewer than two would run or forking is not safe here.
    An exception in a worker is raised here, as in turn it would be."""
    n_workers = min(len(items), workers())
    if n_workers < 2 or not can_fork():
        return None
    import multiprocessing  # deferred: only where workers are forked (with the next, 20 ms of every start)
    from concurrent.futures import ProcessPoolExecutor  # deferred: as multiprocessing

    from threadpoolctl import threadpool_limits  # deferred: only where workers are forked

    _TASK[:] = [function]
    try:
        # one BLAS thread in each worker (they inherit the limit): OpenBLAS's idle threads spin,
        # and two workers' pools on two cores made a stack's L2 laws 80 times slower
        # (a process pool, not multiprocessing.Pool: a worker that dies raises BrokenProcessPool
        # here instead of leaving its task waiting for ever)
        with threadpool_limits(limits=1, user_api="blas"):
            pool = ProcessPoolExecutor(n_workers, mp_context=multiprocessing.get_context("fork"), initializer=_worker)
            try:
                return list(pool.map(_call, items))
            finally:  # interrupted or failed: start nothing more (what runs ends with its worker)
                pool.shutdown(wait=True, cancel_futures=True)
    finally:
        _TASK.clear()
