"""A zero that wanders (issue 47): the field at no load, tracked through a load test and a stream.

A real sensor's field at no load is not one number. Between presses it drifts (the chip's
offset, the temperature: up to 15 uT a minute), and after each unloading it stays off for a
while (the elastomer has not recovered: 1.4-1.8 % of the span 1-3 s after the force reached
zero, more after a run's first press) and comes back by a fixed amount a decade of time. The law,
fitted by least squares to the |B| of the rows at rest (force within the dead band of 0, in runs
of at least :data:`MIN_REST_S`):

    |B|_rest(t) = B0 + d (t - t0) + [after a press] (O_k + R log10(dt / REF_S))

with dt the time since the rest began (the force reached 0), O_k the offset REF_S after the
run's first press (O_1) or a later one (O), R the recovery a decade (of the other sign than O
while it recovers), d the drift. Rows within :data:`SETTLE_S` of the rest's start are left out
(the lag's last rows, the fastest recovery). Applied to every row as baseline(t) = d (t - t0) +
o(dt), o = O_k + R log10(max(dt, SETTLE_S) / REF_S) until it has recovered (crossed 0), then
0: the recovery goes on through the next press. The baseline is removed before the fit; B0 stays
(it is the unloaded field the fit explains). Every sigma is the least squares' (the residuals'
scatter).

:func:`track_zero_T` is the reader's side (``mst read --track-zero``): no force, so a rest is a
run of |B| flat (rolling RMS within :data:`REST_NOISE_FACTOR` x the noise) within
:data:`REST_WINDOW_REL` of the span of the unloaded field; each rest's zero (its rows after
SETTLE_S, less the calibration's o(dt)) sets the shift there, shifts between rests are
interpolated in time (the drift), and o(dt) is added after each rest begins.

Pure: no file or terminal I/O.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np

from mst_cli.calibration.loadtest import Readings
from mst_cli.calibration.record_bounds import checked

MIN_REST_S = 0.5  # a rest lasts at least this long
SETTLE_S = 0.5  # rows this soon after the force reached 0 are left out of the zero's fit
REF_S = 2.0  # the offset after an unloading is quoted this long after the force reached 0
REST_WINDOW_REL = 0.1  # the reader's rest: |B| within this fraction of the span of the unloaded field
REST_NOISE_FACTOR = 2.0  # ... and its rolling RMS about the mean within this many noise sigmas
MAX_GAP_S = 0.25


@dataclass(frozen=True)
class ZeroLaw:
    """The zero's law (module doc); fields in T, s; sigma 1."""

    B0_T: float
    t0_s: float
    drift_T_per_s: float
    drift_sigma: float
    offset_first_T: float | None
    offset_first_sigma: float | None
    offset_T: float | None
    offset_sigma: float | None
    recovery_T_per_decade: float | None
    recovery_sigma: float | None
    span_T: float
    rests: int
    rows: int
    noise_T: float | None = None  # the rest rows' |B| scatter about the law: the chip's noise as logged

    def offset_at_T(self, since_s, first) -> np.ndarray:
        """o(dt) after a rest began (0 where ``since_s`` is NaN, and once recovered)."""
        dt = np.asarray(since_s, float)
        O = np.where(np.asarray(first, bool), self.offset_first_T or 0.0, self.offset_T or 0.0)
        R = self.recovery_T_per_decade or 0.0
        with np.errstate(invalid="ignore"):
            o = O + R * np.log10(np.maximum(np.nan_to_num(dt, nan=REF_S), SETTLE_S) / REF_S)
        return np.where(np.isfinite(dt) & (o * O > 0), o, 0.0)

    def baseline_T(self, time_s, since_s, first) -> np.ndarray:
        return self.drift_T_per_s * (np.asarray(time_s, float) - self.t0_s) + self.offset_at_T(since_s, first)

    def _pct(self, v: float | None) -> float | None:
        return None if v is None or not self.span_T > 0 else 100 * v / self.span_T

    def record(self) -> dict:
        """calibration.json's ``zero``."""
        uT = lambda v: None if v is None else 1e6 * v  # noqa: E731
        return {
            "law": "|B|_rest = B0 + drift (t - t0) + [after a press] (offset + recovery log10(dt / "
            f"{REF_S:g} s)), dt since the force reached 0 (rows before {SETTLE_S:g} s left out); removed "
            "before the fit, B0 kept",
            "rested_zero_uT": 1e6 * self.B0_T,
            "drift_uT_per_min": 60e6 * self.drift_T_per_s,
            "drift_sigma_uT_per_min": 60e6 * self.drift_sigma,
            "offset_after_first_press_uT": uT(self.offset_first_T),
            "offset_after_first_press_sigma_uT": uT(self.offset_first_sigma),
            "offset_after_unloading_uT": uT(self.offset_T),
            "offset_after_unloading_sigma_uT": uT(self.offset_sigma),
            "offset_after_unloading_pct_of_span": self._pct(self.offset_T),
            "recovery_uT_per_decade": uT(self.recovery_T_per_decade),
            "recovery_sigma_uT_per_decade": uT(self.recovery_sigma),
            "span_uT": 1e6 * self.span_T,
            "rests": self.rests,
            "rest_rows": self.rows,
            "rest_noise_uT": uT(self.noise_T),
        }

    def line(self) -> str:
        """The summary's line."""

        def pm(v, s, scale=1e6, unit="uT"):
            return "-" if v is None else f"{scale * v:+.1f} +- {scale * (s or math.nan):.1f} {unit}"

        return (
            f"zero: drift {pm(self.drift_T_per_s, self.drift_sigma, 60e6, 'uT/min')}; {REF_S:g} s after an "
            f"unloading off by {pm(self.offset_T, self.offset_sigma)} (first press "
            f"{pm(self.offset_first_T, self.offset_first_sigma)}), recovering "
            f"{pm(self.recovery_T_per_decade, self.recovery_sigma, 1e6, 'uT')} a decade; removed before the fit "
            f"({self.rests} rests; |B| noise at rest {1e6 * (self.noise_T or math.nan):.2g} uT)"
        )


def rest_runs(time_s: np.ndarray, at_rest: np.ndarray, min_s: float = MIN_REST_S) -> list[tuple[int, int]]:
    """(first row, row after the last) of each run of rows at rest lasting ``min_s``, no gap inside."""
    runs, i, n = [], 0, len(at_rest)
    while i < n:
        if not at_rest[i]:
            i += 1
            continue
        j = i + 1
        while j < n and at_rest[j] and time_s[j] - time_s[j - 1] <= MAX_GAP_S:
            j += 1
        if time_s[j - 1] - time_s[i] >= min_s:
            runs.append((i, j))
        i = j
    return runs


def since_rest(time_s: np.ndarray, runs: list[tuple[int, int]], loaded: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(seconds since the latest rest that followed a press began, NaN before one; whether that
    press was the first)."""
    n = len(time_s)
    since, first = np.full(n, np.nan), np.zeros(n, bool)
    presses = 0
    for a, _b in runs:
        if not loaded[:a].any():
            continue  # the rest before the first press: the rested zero
        presses += 1
        since[a:] = time_s[a:] - time_s[a]
        first[a:] = presses == 1
    return since, first


def _design(t, t0, since, first, rest_fit):
    cols = {"B0": np.ones(rest_fit.sum()), "drift": (t - t0)[rest_fit]}
    post = np.isfinite(since[rest_fit])
    cols["offset_first"] = (post & first[rest_fit]).astype(float)
    cols["offset"] = (post & ~first[rest_fit]).astype(float)
    with np.errstate(invalid="ignore", divide="ignore"):
        cols["recovery"] = np.where(post, np.log10(np.maximum(since[rest_fit], SETTLE_S) / REF_S), 0.0)
    return {k: v for k, v in cols.items() if np.ptp(v) > 0 or k == "B0"}


def fit_zero(time_s, B_abs_T, force_N, band_N: float) -> ZeroLaw | None:
    """The zero's law from the rows at rest (force within ``band_N`` of 0); None with fewer
    than two rests or too few rows to fit it."""
    t, B, F = np.asarray(time_s, float), np.asarray(B_abs_T, float), np.asarray(force_N, float)
    at_rest = F <= band_N
    runs = rest_runs(t, at_rest)
    if len(runs) < 2:
        return None
    since, first = since_rest(t, runs, ~at_rest)
    in_run = np.zeros(len(t), bool)
    for a, b in runs:
        in_run[a:b] = True
    rest_fit = in_run & ~(np.isfinite(since) & (since < SETTLE_S))
    t0 = float(t[runs[0][0]])
    cols = _design(t, t0, since, first, rest_fit)
    A = np.stack(list(cols.values()), -1)
    y = B[rest_fit]
    if len(y) <= A.shape[1] + 2:
        return None
    coef, *_ = np.linalg.lstsq(A, y, rcond=None)
    r = y - A @ coef
    cov = float(np.sum(r**2) / (len(y) - A.shape[1])) * np.linalg.pinv(A.T @ A)
    got = {k: (float(coef[i]), float(math.sqrt(max(cov[i, i], 0.0)))) for i, k in enumerate(cols)}

    none: tuple[float | None, float | None] = (None, None)
    loaded = ~at_rest
    span = float(np.percentile(B[loaded], 99.5) - coef[0]) if loaded.any() else 0.0
    drift, drift_sigma = got.get("drift", (0.0, 0.0))
    return ZeroLaw(
        got["B0"][0], t0, drift, drift_sigma, *got.get("offset_first", none), *got.get("offset", none),
        *got.get("recovery", none), span_T=abs(span), rests=len(runs), rows=int(rest_fit.sum()),
        noise_T=float(np.sqrt(np.sum(r**2) / max(len(y) - A.shape[1], 1))),
    )  # fmt: skip


def remove_zero(lt: Readings, law: ZeroLaw, time_s: np.ndarray, band_N: float) -> Readings:
    """The rows with the zero's baseline removed from |B| (the field's direction kept)."""
    F = lt.load_N
    runs = rest_runs(time_s, F <= band_N)
    since, first = since_rest(time_s, runs, F > band_N)
    B = lt.B_abs_T
    scale = np.where(B > 0, (B - law.baseline_T(time_s, since, first)) / np.where(B > 0, B, 1.0), 1.0)
    return replace(lt, B_T=lt.B_T * scale[:, None])


def zero_law_of(record: object) -> ZeroLaw | None:
    """The law of calibration.json's ``zero`` (None when absent or a key is missing: the reader
    then re-zeroes at each rest without the recovery and the drift). InputError naming the key
    when a value is not a number inside its physical bound (:mod:`~mst_cli.calibration.record_bounds`)."""
    if not isinstance(record, dict):
        return None
    keys = ("rested_zero_uT", "drift_uT_per_min", "offset_after_unloading_uT", "recovery_uT_per_decade")
    values = [checked(record, "zero", k) for k in keys]
    if any(v is None for v in values):
        return None
    first = checked(record, "zero", "offset_after_first_press_uT")
    B0, drift, offset, recovery = (float(v) for v in values)  # type: ignore[arg-type]  # None ruled out above
    return ZeroLaw(
        1e-6 * B0, 0.0, drift / 60e6, 0.0, None if first is None else 1e-6 * first, None, 1e-6 * offset, None,
        1e-6 * recovery, None, 1e-6 * (checked(record, "zero", "span_uT") or 0.0),
        int(checked(record, "zero", "rests") or 0), 0,
    )  # fmt: skip


def track_zero_T(
    B_abs_T: np.ndarray, time_s: np.ndarray | None, B_unloaded_T: float, span_T: float, law: ZeroLaw | None = None
) -> np.ndarray:
    """The reader's zero shift of each row (module doc): subtract it from |B| before the
    inverse map. All zeros when the stream has no rest. The noise is the stream's own (the
    median absolute second difference)."""
    B = np.asarray(B_abs_T, float)
    n = len(B)
    noise_T = float(np.median(np.abs(np.diff(B, 2)))) * 1.4826 / math.sqrt(6.0) if n > 3 else 0.0
    t = np.arange(n, dtype=float) * 0.02 if time_s is None else np.asarray(time_s, float)
    step = float(np.median(np.diff(t))) if n > 1 else 1.0
    w = max(3, int(round(MIN_REST_S / step)))
    kernel = np.ones(w) / w
    mean = np.convolve(B, kernel, mode="same")
    rms = np.sqrt(np.maximum(np.convolve(B**2, kernel, mode="same") - mean**2, 0.0))
    flat = (rms <= REST_NOISE_FACTOR * max(noise_T, 1e-10)) & (np.abs(mean - B_unloaded_T) <= REST_WINDOW_REL * span_T)
    runs = rest_runs(t, flat)
    if not runs:
        return np.zeros(n)
    since, first = since_rest(t, runs, mean - B_unloaded_T > REST_WINDOW_REL * span_T)  # pressed beyond a rest
    offset = law.offset_at_T(since, first) if law is not None else np.zeros(n)
    times, shifts = [], []
    for a, b in runs:
        use = np.arange(a, b)
        use = use[~(np.isfinite(since[use]) & (since[use] < SETTLE_S))]
        if len(use):
            times.append(float(np.mean(t[use])))
            shifts.append(float(np.median(B[use] - offset[use])) - B_unloaded_T)
    if not shifts:
        return np.zeros(n)
    drift = law.drift_T_per_s if law is not None else 0.0
    shift = np.interp(t, times, shifts)
    shift = np.where(t > times[-1], shifts[-1] + drift * (t - times[-1]), shift)
    return shift + offset
