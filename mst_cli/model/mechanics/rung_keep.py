"""Where the whole-part rung (:mod:`mst_cli.model.mechanics.whole_part`) keeps its solves between
runs: a store it is given, or none (this process's memo only). The store itself, files in mst's
cache folder, is :mod:`mst_cli.sensor.rung_store`; this module reads and writes nothing, and is
light (no scipy, no mesh), so the api can install a store without loading the rung."""

from __future__ import annotations

from collections.abc import Callable
from typing import Protocol


class RungStore(Protocol):
    """``key``: what a solve depends on, as the rung's in-process memo key; ``value``: plain JSON
    (lists, dicts, numbers)."""

    def load(self, kind: str, key: tuple) -> object | None: ...

    def save(self, kind: str, key: tuple, value: object) -> None: ...


_STORE: list[RungStore] = []  # at most one: set_store's
_LISTENER: list[Callable[[str], None]] = []  # at most one: set_listener's


def set_listener(say: Callable[[str], None] | None) -> None:
    """Tell ``say`` (a command's progress line) whenever the rung starts solves it has not kept
    (None: tell no one). Seconds each: the wait a user should hear about before it starts."""
    _LISTENER[:] = [] if say is None else [say]


def solving(count: int, what: str) -> None:
    """Say that ``count`` solves of ``what`` start now (nothing without a listener)."""
    if _LISTENER and count:
        _LISTENER[0](f"whole-part rung: {count} solves of {what} (seconds each; kept in mst's cache for the next run)")


def set_store(store: RungStore | None) -> None:
    """Keep the rung's solves in ``store`` from now on (None: in this process only)."""
    _STORE[:] = [] if store is None else [store]


def stored(kind: str, key: tuple) -> object | None:
    """The value kept for ``key`` (None: no store, or nothing kept)."""
    return _STORE[0].load(kind, key) if _STORE else None


def store(kind: str, key: tuple, value: object) -> None:
    """Keep ``value`` for ``key`` (nothing without a store)."""
    if _STORE:
        _STORE[0].save(kind, key, value)
