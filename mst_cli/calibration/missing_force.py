"""Rows as loggers write them (issue 47): a row without a force.

A logger that merges a force stream and a field stream writes the force on some rows only
(about half of a public sensor's rows), marking the others with an empty cell, ``nan`` or a
sentinel such as -1. Such a row is refused by default, naming the option; with
``--missing-force SENTINEL`` (NaN: empty and ``nan`` cells only) it gets a NaN force: its field
still times the lag (:mod:`~mst_cli.calibration.time_alignment`), it is counted and never fitted.
A load test whose lowest, negative force fills :data:`SENTINEL_SHARE` of its rows is a sentinel
given without the option: refused in one line naming it (not "is the load cell's sign reversed?").

Pure: no file or terminal I/O.
"""

from __future__ import annotations

import numpy as np

from mst_cli.errors import InputError

MISSING_CELLS = ("", "nan", "na", "n/a", "none", "null")  # a logger's row without a force
SENTINEL_SHARE = 0.05  # this share of rows at one negative force is a logger's sentinel, not a reversed cell


def is_missing(where: str, text: str, missing: float | None) -> bool:
    """Whether a force cell marks a row without a force (an empty or ``nan`` cell, or the sentinel
    ``missing``), when ``missing`` is given; without it such a cell is refused, naming the option
    (``where``: the file, line and column)."""
    cell = text.strip()
    if missing is None:
        if cell.lower() in MISSING_CELLS:
            raise InputError(
                where,
                text,
                "a number: a row without a force (empty, nan, or a sentinel such as -1) is skipped only with "
                "--missing-force -1 (the sentinel; nan for empty and nan cells only)",
            )
        return False
    if cell.lower() in MISSING_CELLS:
        return True
    try:
        return float(cell) == missing
    except ValueError:
        return False


def check_force_sentinel(source: str, lines: list[int], force_N: np.ndarray | None, column: str) -> None:
    """A load test whose lowest force, negative, fills SENTINEL_SHARE of its rows: a logger's
    mark for a row without a force (-1), refused in one line naming --missing-force."""
    F = force_N
    if F is None or not len(F) or not np.nanmin(F) < 0:
        return
    i = int(np.nanargmin(F))
    count = int(np.sum(F == F[i]))
    if count >= SENTINEL_SHARE * len(F):
        raise InputError(
            f"{source} line {lines[i]} {column}",
            float(F[i]),
            f"{count} rows hold this one negative force: a logger's mark for a row without a force? "
            f"--missing-force {F[i]:g} skips them (and counts them)",
        )
