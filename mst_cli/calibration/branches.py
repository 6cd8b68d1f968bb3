"""The branches of a rig's load test (issue 38): loading, unloading and hold rows, the turning
points (the force at each reversal), the cycles.

A rig loads a sensor to a turning force and unloads it, several times; it may hold a force for
a while (the sensor creeps). The rows are in time order (row order, or ``time_s``). The force
column is noisy, so a reversal counts only when the force moves back from its running extreme
by more than a *dead band*: :data:`DEAD_BAND_SIGMAS` times the force noise, which is estimated
from the data (the median absolute second difference: on a ramp of constant step it is the
noise alone, reversals and hold edges are a few outliers), floored at
:data:`DEAD_BAND_FLOOR_REL` of the force span, or given.

Conventions (the synthetic rig of studies/rig_loadtest.py writes its rows the same way):

* the row at a maximum (a peak) is the last *loading* row; the unloading starts after it;
* the row at a minimum (a valley) is the last *unloading* row of its cycle; the next cycle
  starts after it (cycle numbers from 1);
* a hold is a run of at least ``min_hold_rows`` rows (and ``min_hold_s`` seconds, default
  :data:`MIN_HOLD_S`, when times are given) whose force stays within one dead band; its rows
  are labelled ``hold``; a turning point inside a hold is its first row (the row that reached
  the held force, labelled with the
  branch before), the hold's rows follow it;
* ``turn_force_N[i]`` is the force at the last turning point strictly before row ``i`` (NaN
  before the first): for an unloading row, the peak it unloads from.

User hints (a ``branch`` column of loading/unloading/hold and a ``cycle`` column) are used when
given, after a check against the force sequence; a mismatch raises :class:`InputError` naming
the column and the row (``branch[12]``: data row 12 counted from ``first_row``).

Pure: no file or terminal I/O.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from mst_cli.errors import InputError

LOADING, UNLOADING, HOLD = "loading", "unloading", "hold"
LABELS = (LOADING, UNLOADING, HOLD)
DEAD_BAND_SIGMAS = 8.0  # a reversal is a move back by more than this many force-noise sigmas
DEAD_BAND_FLOOR_REL = 0.002  # ... and by more than this fraction of the force span
MIN_HOLD_ROWS = 5
MIN_HOLD_S = 1.0  # with times, a hold lasts at least this long (a 0.1 s pause of five 50 Hz rows is no hold)
MAD_TO_SIGMA = 1.4826  # sigma of a normal variable / its median absolute deviation


@dataclass(frozen=True)
class Branches:
    """The branches of a load test, one entry per row where an array."""

    label: np.ndarray  # "loading" / "unloading" / "hold"
    cycle: np.ndarray  # int, from 1
    turn_force_N: np.ndarray  # force at the last turning point strictly before the row (NaN before the first)
    peak_rows: np.ndarray  # rows of the maxima (turning points from loading to unloading)
    valley_rows: np.ndarray  # rows of the minima
    holds: tuple[tuple[int, int], ...]  # (first row, row after the last) of each hold
    dead_band_N: float
    force_noise_N: float

    @property
    def turn_rows(self) -> np.ndarray:
        return np.sort(np.concatenate([self.peak_rows, self.valley_rows])).astype(int)

    def mask(self, label: str) -> np.ndarray:
        return self.label == label


def force_noise_N(force_N: Sequence[float] | np.ndarray) -> float:
    """Robust force-noise sigma: MAD of the second differences / sqrt(6) (a second difference of
    white noise has variance 6 sigma^2; a ramp of constant step adds nothing)."""
    F = np.asarray(force_N, dtype=float)
    if len(F) < 3:
        return 0.0
    d2 = np.diff(F, 2)
    return float(MAD_TO_SIGMA * np.median(np.abs(d2 - np.median(d2))) / np.sqrt(6.0))


def dead_band_N(force_N: Sequence[float] | np.ndarray) -> float:
    """The dead band a reversal must exceed: DEAD_BAND_SIGMAS x the noise, floored."""
    F = np.asarray(force_N, dtype=float)
    span = float(np.ptp(F)) if len(F) else 0.0
    return max(DEAD_BAND_SIGMAS * force_noise_N(F), DEAD_BAND_FLOOR_REL * span, 1e-12)


def turning_points(force_N: np.ndarray, band_N: float) -> tuple[np.ndarray, np.ndarray]:
    """(peak rows, valley rows): the running extreme is a turning point once the force has moved
    back from it by more than ``band_N``. The first and the last row are never turning points."""
    F = np.asarray(force_N, dtype=float)
    peaks: list[int] = []
    valleys: list[int] = []
    hi = lo = ext = 0
    direction = 0
    for i in range(1, len(F)):
        if direction == 0:
            hi = i if F[i] > F[hi] else hi
            lo = i if F[i] < F[lo] else lo
            if F[hi] - F[lo] > band_N:
                direction, ext = (1, hi) if hi > lo else (-1, lo)
        elif direction * (F[i] - F[ext]) >= 0:
            ext = i
        elif direction * (F[ext] - F[i]) > band_N:
            (peaks if direction == 1 else valleys).append(ext)
            direction, ext = -direction, i
    return np.array(peaks, dtype=int), np.array(valleys, dtype=int)


def hold_segments(
    force_N: np.ndarray,
    band_N: float,
    min_hold_rows: int = MIN_HOLD_ROWS,
    time_s: np.ndarray | None = None,
    min_hold_s: float = 0.0,
) -> tuple[tuple[int, int], ...]:
    """Runs of rows whose force stays within ``band_N`` (peak to peak), at least
    ``min_hold_rows`` rows and ``min_hold_s`` long; (first row, row after the last)."""
    F = np.asarray(force_N, dtype=float)
    out: list[tuple[int, int]] = []
    i, n = 0, len(F)
    while i < n:
        j, lo, hi = i + 1, F[i], F[i]
        while j < n and max(hi, F[j]) - min(lo, F[j]) <= band_N:
            lo, hi, j = min(lo, F[j]), max(hi, F[j]), j + 1
        long_enough = j - i >= min_hold_rows
        if long_enough and time_s is not None:
            long_enough = float(time_s[j - 1] - time_s[i]) >= min_hold_s
        if long_enough:
            out.append((i, j))
            i = j
        else:
            i += 1
    return tuple(out)


def _turns_at_hold_start(
    peaks: np.ndarray, valleys: np.ndarray, holds: tuple[tuple[int, int], ...]
) -> tuple[np.ndarray, np.ndarray, tuple[tuple[int, int], ...]]:
    """A turning point inside a hold moves to the hold's first row (the row at which the force
    reached the held level: the last row of the branch before); the hold starts after it."""
    out_holds = []
    peaks, valleys = peaks.copy(), valleys.copy()
    for a, b in holds:
        inside = False
        for rows in (peaks, valleys):
            hit = (rows >= a) & (rows < b)
            rows[hit] = a
            inside = inside or bool(hit.any())
        out_holds.append((a + 1, b) if inside else (a, b))
    return peaks, valleys, tuple(out_holds)


def _labels(n: int, peaks: np.ndarray, valleys: np.ndarray, force_N: np.ndarray) -> np.ndarray:
    """Loading / unloading per row from the turning points (peak row: loading; valley row:
    unloading); before the first turning point, the direction of the first move."""
    label = np.empty(n, dtype=object)
    turns = sorted([(int(p), UNLOADING) for p in peaks] + [(int(v), LOADING) for v in valleys])
    if turns:
        first = LOADING if turns[0][1] == UNLOADING else UNLOADING
    else:
        first = LOADING if n < 2 or force_N[-1] >= force_N[0] else UNLOADING
    start, current = 0, first
    for row, after in turns:
        label[start : row + 1] = current
        start, current = row + 1, after
    label[start:] = current
    return label


def _cycles(n: int, valleys: np.ndarray) -> np.ndarray:
    cycle = np.ones(n, dtype=int)
    for v in valleys:
        cycle[int(v) + 1 :] += 1
    return cycle


def _turn_force(n: int, turn_rows: np.ndarray, force_N: np.ndarray) -> np.ndarray:
    out = np.full(n, np.nan)
    for r in np.sort(turn_rows):
        out[int(r) + 1 :] = force_N[int(r)]
    return out


def find_branches(
    force_N: Sequence[float] | np.ndarray,
    time_s: Sequence[float] | np.ndarray | None = None,
    *,
    band_N: float | None = None,
    branch: Sequence[str] | None = None,
    cycle: Sequence[int] | None = None,
    min_hold_rows: int = MIN_HOLD_ROWS,
    min_hold_s: float = MIN_HOLD_S,
    first_row: int = 0,
) -> Branches:
    """The branches, turning points, cycles and holds of a load test (see the module doc).

    ``band_N`` is the dead band (default: :func:`dead_band_N` of the data). ``branch`` and
    ``cycle`` are the user's hints: used when given, checked against the force sequence first.
    ``first_row`` is added to a row index named in an error.
    """
    F = np.asarray(force_N, dtype=float)
    n = len(F)
    t = None if time_s is None else np.asarray(time_s, dtype=float)
    if t is not None:
        _check_time(t, first_row)
    band = dead_band_N(F) if band_N is None else float(band_N)
    peaks, valleys = turning_points(F, band)
    holds = hold_segments(F, band, min_hold_rows, t, min_hold_s)
    peaks, valleys, holds = _turns_at_hold_start(peaks, valleys, holds)
    label = _labels(n, peaks, valleys, F)
    for a, b in holds:
        label[a:b] = HOLD
    cycles = _cycles(n, valleys)
    if branch is not None:
        label = _checked_branch(F, branch, band, first_row)
    if cycle is not None:
        cycles = _checked_cycle(F, cycle, valleys, band, first_row)
    return Branches(
        label=label,
        cycle=cycles,
        turn_force_N=_turn_force(n, np.concatenate([peaks, valleys]), F),
        peak_rows=peaks,
        valley_rows=valleys,
        holds=holds,
        dead_band_N=band,
        force_noise_N=force_noise_N(F),
    )


def _check_time(t: np.ndarray, first_row: int) -> None:
    bad = np.flatnonzero(np.diff(t) < 0)
    if len(bad):
        i = int(bad[0]) + 1
        raise InputError(
            f"time_s[{i + first_row}]", float(t[i]), f"times in row order (the row before has {t[i - 1]:g})"
        )


def _checked_branch(F: np.ndarray, branch: Sequence[str], band: float, first_row: int) -> np.ndarray:
    """The user's branch column, checked: a loading run (from the row before it) never falls
    back from its running maximum by more than the dead band, an unloading run never rises from its running minimum by
    more, a hold run stays within twice the band (its first row may still be on the ramp)."""
    label = np.array([str(b).strip().lower() for b in branch], dtype=object)
    if len(label) != len(F):
        raise InputError("branch", len(label), f"one entry per row ({len(F)} rows)")
    start = 0
    for i in range(len(F)):
        if label[i] not in LABELS:
            raise InputError(f"branch[{i + first_row}]", branch[i], "one of loading, unloading, hold")
        if i > 0 and label[i] != label[i - 1]:
            start = i - 1  # a run starts from the row before it (the turning point, or the hold's level)
        run = F[start : i + 1]
        if label[i] == LOADING and run.max() - F[i] > band:
            why = f"the force falls to {F[i]:.4g} N from {run.max():.4g} N on a loading run"
        elif label[i] == UNLOADING and F[i] - run.min() > band:
            why = f"the force rises to {F[i]:.4g} N from {run.min():.4g} N on an unloading run"
        elif label[i] == HOLD and np.ptp(run) > 2 * band:
            why = f"the force moves by {np.ptp(run):.4g} N on a hold (dead band {band:.3g} N)"
        else:
            continue
        raise InputError(f"branch[{i + first_row}]", branch[i], f"a label the force agrees with: {why}")
    return label


def _checked_cycle(F: np.ndarray, cycle: Sequence[int], valleys: np.ndarray, band: float, first_row: int) -> np.ndarray:
    """The user's cycle column, checked: whole numbers that never decrease, and a new cycle
    starts within a dead band of a valley of the force (and every valley starts one)."""
    c = np.asarray(cycle)
    if len(c) != len(F):
        raise InputError("cycle", len(c), f"one entry per row ({len(F)} rows)")
    if not np.all(np.isfinite(c.astype(float))) or np.any(c.astype(float) != np.round(c.astype(float))):
        i = int(np.flatnonzero(~np.isfinite(c.astype(float)) | (c.astype(float) != np.round(c.astype(float))))[0])
        raise InputError(f"cycle[{i + first_row}]", cycle[i], "a whole number")
    c = c.astype(int)
    down = np.flatnonzero(np.diff(c) < 0)
    if len(down):
        i = int(down[0]) + 1
        raise InputError(
            f"cycle[{i + first_row}]", int(c[i]), f"cycle numbers that never decrease (before: {c[i - 1]})"
        )
    starts = np.flatnonzero(np.diff(c) > 0) + 1
    runs = _valley_runs(F, valleys, 2 * band)
    for s in starts:
        if not any(a <= s <= b for a, b in runs):
            raise InputError(
                f"cycle[{s + first_row}]", int(c[s]), f"a new cycle starts at a valley of the force (here {F[s]:.4g} N)"
            )
    for (a, b), v in zip(runs, valleys):
        if not np.any((starts >= a) & (starts <= b)):
            raise InputError(f"cycle[{v + first_row}]", int(c[v]), f"a new cycle after the valley at {F[v]:.4g} N")
    return c


def _valley_runs(F: np.ndarray, valleys: np.ndarray, tol_N: float) -> list[tuple[int, int]]:
    """Per valley: (first row, row after the last) of the run of rows around it within
    ``tol_N`` of its force; a new cycle may start anywhere in it."""
    runs = []
    for v in valleys:
        a = b = int(v)
        while a > 0 and abs(F[a - 1] - F[v]) <= tol_N:
            a -= 1
        while b < len(F) - 1 and abs(F[b + 1] - F[v]) <= tol_N:
            b += 1
        runs.append((a, b + 1))
    return runs
