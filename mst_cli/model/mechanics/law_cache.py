"""The dear rungs' laws, memoised per process, and the missing ones of a stack solved side by side.

A frame (L1) or continuum (L2) law is a pure function of a frozen, hashable (cell, material),
so each process keeps the ones it has solved (:class:`LawCache`, like ``functools.lru_cache``
but one that can be filled from outside). A stack asks for all its layers' laws at once
(:func:`mst_cli.model.mechanics.layer_laws`). An L2 law takes a third of a second, and the
layers are independent, so :meth:`LawCache.solve_many` solves those not yet known side by side
(:func:`mst_cli.parallel.fork_map`: a forked worker per core; ``MST_WORKERS=1`` in turn).
"""

from __future__ import annotations

import functools
from collections import OrderedDict
from collections.abc import Callable, Iterable
from typing import Any, NamedTuple

from mst_cli.parallel import fork_map


class CacheInfo(NamedTuple):
    hits: int
    misses: int  # laws solved in this process or handed back by a worker
    maxsize: int
    currsize: int


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
        laws = fork_map(self._solve_pair, todo)
        if laws is None:
            return  # the caller's own requests solve them in turn
        for key, law in zip(todo, laws):
            self._store(key, law)
        self.solved_in_workers += len(todo)

    def _solve_pair(self, key: tuple[Any, Any]) -> Any:
        return self._solve(*key)

    def cache_info(self) -> CacheInfo:
        return CacheInfo(self.hits, self.misses, self.maxsize, len(self._laws))

    def cache_clear(self) -> None:
        self._laws.clear()
        self.hits = self.misses = self.solved_in_workers = 0


def law_cache(maxsize: int) -> Callable[[Callable], LawCache]:
    """Decorator: ``@law_cache(maxsize=256)`` over a rung's ``law(cell, material)``."""
    return lambda solve: LawCache(solve, maxsize)
