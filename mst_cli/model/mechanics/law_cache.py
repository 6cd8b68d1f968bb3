"""The dear rungs' laws, memoised per process, and the missing ones of a stack solved side by side.

A frame (L1) or continuum (L2) law is a pure function of a frozen, hashable (cell, material),
so each process keeps the ones it has solved (:class:`LawCache`, like ``functools.lru_cache``
but one that can be filled from outside). A stack asks for all its layers' laws at once
(:func:`mst_cli.model.mechanics.layer_laws`). An L2 law takes about half a second, and the
layers are independent, so :meth:`LawCache.solve_many` solves those not yet known in worker
processes, one per core: forked, so a worker starts with everything already imported and
costs milliseconds, and each returns its law pickled (a few kB). Where fork is not the safe
default (not Linux, or threads running in this process) or ``MST_WORKERS=1``, they are solved
in turn. Either way the law of a cell is the same function of it, computed the same way.
"""

from __future__ import annotations

import functools
import multiprocessing
import os
import sys
import threading
from collections import OrderedDict
from collections.abc import Callable, Iterable
from typing import Any, NamedTuple

from mst_cli.errors import InputError

WORKERS_ENV = "MST_WORKERS"  # worker processes for a stack's dear laws [default: the usable cores]


class CacheInfo(NamedTuple):
    hits: int
    misses: int  # laws solved in this process or handed back by a worker
    maxsize: int
    currsize: int


def workers() -> int:
    """Worker processes to use: ``MST_WORKERS`` if set (a whole number >= 1), else the cores
    this process may run on."""
    text = os.environ.get(WORKERS_ENV, "").strip()
    if not text:
        return len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else (os.cpu_count() or 1)
    if not text.isdigit() or int(text) < 1:
        raise InputError(WORKERS_ENV, text, "a whole number of worker processes >= 1 (1: solve in turn)")
    return int(text)


def _can_fork() -> bool:
    """Fork only where it is the platform's own default and no other thread could hold a lock."""
    return sys.platform.startswith("linux") and threading.active_count() == 1


_TASKS: list[tuple[Callable, tuple]] = []  # what the forked workers solve, by index


def _solve_task(index: int) -> Any:
    solve, args = _TASKS[index]
    return solve(*args)


class LawCache:
    """Memo of ``solve(cell, material)`` (the newest ``maxsize`` kept), with ``__wrapped__``
    (the uncached function), ``cache_info()`` and ``cache_clear()`` as lru_cache has."""

    __wrapped__: Callable  # the uncached law (set by update_wrapper)

    def __init__(self, solve: Callable, maxsize: int):
        functools.update_wrapper(self, solve)
        self._solve, self.maxsize = solve, maxsize
        self._laws: OrderedDict = OrderedDict()
        self.hits = self.misses = 0
        self.solved_in_workers = 0  # of the misses: laws a worker solved (each then a hit when asked for)

    def __call__(self, cell, material):
        key = (cell, material)
        law = self._laws.get(key)
        if law is not None:
            self.hits += 1
            self._laws.move_to_end(key)
            return law
        law = self._solve(cell, material)
        self._store(key, law)
        return law

    def _store(self, key, law) -> None:
        self.misses += 1
        self._laws[key] = law
        if len(self._laws) > self.maxsize:
            self._laws.popitem(last=False)

    def solve_many(self, pairs: Iterable[tuple[Any, Any]]) -> None:
        """Solve the laws of the (cell, material) ``pairs`` not yet known, side by side when two
        or more are missing and there is more than one worker; a failure is raised as in turn."""
        todo = [key for key in dict.fromkeys(pairs) if key not in self._laws]
        n_workers = min(len(todo), workers())
        if n_workers < 2 or not _can_fork():
            return  # the caller's own requests solve them in turn
        from threadpoolctl import threadpool_limits  # deferred: only where workers are forked

        _TASKS[:] = [(self._solve, key) for key in todo]
        try:
            # one BLAS thread in each worker (they inherit the limit): OpenBLAS's idle threads
            # spin, and two workers' pools on two cores made a stack's laws 80 times slower
            with (
                threadpool_limits(limits=1, user_api="blas"),
                multiprocessing.get_context("fork").Pool(n_workers) as pool,
            ):
                laws = pool.map(_solve_task, range(len(todo)), chunksize=1)
        finally:
            _TASKS.clear()
        for key, law in zip(todo, laws):
            self._store(key, law)
        self.solved_in_workers += len(todo)

    def cache_info(self) -> CacheInfo:
        return CacheInfo(self.hits, self.misses, self.maxsize, len(self._laws))

    def cache_clear(self) -> None:
        self._laws.clear()
        self.hits = self.misses = self.solved_in_workers = 0


def law_cache(maxsize: int) -> Callable[[Callable], LawCache]:
    """Decorator: ``@law_cache(maxsize=256)`` over a rung's ``law(cell, material)``."""
    return lambda solve: LawCache(solve, maxsize)
