"""Hysteresis, stress softening and creep of a rig's load test (issue 38), measured at matched
field.

The field at the chip follows the deflection; the force the rig reads at a deflection depends
on the path. So every comparison here is at matched |B|: a branch's force against the force
the reference branch (the loading rows) reads at the same |B|. The reference is a local linear
fit of force against |B| over the ``neighbours`` loading rows nearest in |B| (no bias on a
straight piece, a noise of sigma_F / sqrt(neighbours)).

* :func:`measure_hysteresis`: per regime (force band), the largest loading-minus-unloading
  force at matched |B|, in % of the band: the largest value over the band's loads of a
  least-squares quadratic of the difference against the loading force (a smooth loop has
  its largest opening inside a band or at its edge; a bin mean would cut an edge maximum by
  half a bin, the quadratic follows it with the noise of a few parameters);
* :func:`fit_unloading`: the unloading branch relative to the loading one,
  F_unload(B) = F_load(B) - h(F_load, F_turn), with F_turn the force at the turning point the
  unloading started from and h = F_turn (c0 + c1 x + c2 x^2 + c3 x^3), x = F_load / F_turn,
  plus e x^4 on an unloading that follows a hold (issue 47). The form: the loop scales with
  its excursion (Masing's rule: h / F_turn depends on x only), so a reader that knows the
  branch and the last turning force uses one curve for every cycle; a real loop may have either
  sign along the force (about -3 % of full scale near no load, -0.4..+2 % mid-range on a
  printed TPU sensor) and stay open at no load and, after a hold (the sensor crept at the
  turn), at the turn: so no end is forced to close. Linear in the coefficients: ordinary least
  squares, each with its sigma;
* :func:`first_cycle`: cycle 1's loading against the later cycles' at matched |B|, as a
  relative stiffness p (F_1 = (1 + p) F_later), with its z score against the scatter;
  :func:`rows_without_first_cycle` drops cycle 1 when it differs;
* :func:`creep`: over a hold, the reading (as force, or |B| with the local slope) against
  log10(t - t_start): % of the held force per decade, with its 1-sigma.

Pure: no file or terminal I/O.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from mst_cli.calibration.branches import LOADING, UNLOADING
from mst_cli.errors import CalibrationFailed

NEIGHBOURS = 12  # loading rows in the local linear fit of force against |B|
HYSTERESIS_DEGREE = 2  # polynomial of the loading-minus-unloading force against the load, per regime
FIRST_CYCLE_Z = 5.0  # cycle 1 differs when its relative stiffness is this many sigma from 0
FIRST_CYCLE_MIN_FORCE_REL = 0.1  # ... compared on rows above this fraction of the full scale
UNLOADING_DEGREE = 3  # the unloading model's polynomial in the force fraction
CREEP_FROM_S = 0.2  # creep is fitted from this long into a hold (the ramp's stop, the force's lag before it)


def force_at_field_N(
    B_ref: np.ndarray,
    F_ref: np.ndarray,
    B_query: np.ndarray,
    neighbours: int = NEIGHBOURS,
    edges_N: Sequence[float] | None = None,
) -> np.ndarray:
    """Force of the reference rows (|B|, F) at ``B_query``: a linear fit of F against |B| over
    the ``neighbours`` reference rows nearest in |B|. With ``edges_N`` (the lock forces) a
    query whose first estimate falls in a band is fitted again on that band's reference rows
    only: a window across a lock, where the slope jumps, would bias it."""
    F = _local_linear(B_ref, F_ref, B_query, neighbours)
    if edges_N is None:
        return F
    F_ref = np.asarray(F_ref, float)
    first = F.copy()
    for lo, hi in zip(edges_N[:-1], edges_N[1:]):
        ref = (F_ref >= lo) & (F_ref <= hi)
        q = (first >= lo) & (first <= hi)
        if ref.sum() >= 2 and q.any():
            F[q] = _local_linear(np.asarray(B_ref)[ref], F_ref[ref], np.atleast_1d(B_query)[q], neighbours)
    return F


def _local_linear(B_ref: np.ndarray, F_ref: np.ndarray, B_query: np.ndarray, neighbours: int) -> np.ndarray:
    order = np.argsort(B_ref)
    B, F = np.asarray(B_ref, float)[order], np.asarray(F_ref, float)[order]
    q = np.atleast_1d(np.asarray(B_query, dtype=float))
    k = min(neighbours, len(B))
    if k < 2:
        raise CalibrationFailed("fewer than 2 reference rows: no force at matched field")
    start = np.clip(np.searchsorted(B, q) - k // 2, 0, len(B) - k)
    idx = start[:, None] + np.arange(k)
    Bw, Fw = B[idx], F[idx]
    Bm, Fm = Bw.mean(axis=1), Fw.mean(axis=1)
    var = ((Bw - Bm[:, None]) ** 2).sum(axis=1)
    slope = np.where(var > 0, ((Bw - Bm[:, None]) * (Fw - Fm[:, None])).sum(axis=1) / np.where(var > 0, var, 1), 0)
    return Fm + slope * (q - Bm)


@dataclass(frozen=True)
class RegimeHysteresis:
    lo_N: float
    hi_N: float
    max_N: float  # largest loading-minus-unloading force at matched |B| (bin mean)
    max_pct: float  # ... in % of the band hi - lo
    at_force_N: float  # loading-branch force where it occurs
    samples: int  # unloading rows in the band


def _regime_peak(lo: float, hi: float, F_load: np.ndarray, d: np.ndarray, degree: int) -> RegimeHysteresis:
    """The largest value of a least-squares polynomial of d against F_load over the band's
    loads (fewer than degree + 2 rows: the largest row)."""
    if len(d) == 0:
        return RegimeHysteresis(lo, hi, float("nan"), float("nan"), float("nan"), 0)
    if len(d) < degree + 2:
        j = int(np.argmax(d))
        return RegimeHysteresis(lo, hi, float(d[j]), float(100 * d[j] / (hi - lo)), float(F_load[j]), len(d))
    mid, half = 0.5 * (lo + hi), 0.5 * (hi - lo)
    coef = np.polynomial.polynomial.polyfit((F_load - mid) / half, d, degree)
    grid = np.linspace(F_load.min(), F_load.max(), 401)
    fitted = np.polynomial.polynomial.polyval((grid - mid) / half, coef)
    j = int(np.argmax(fitted))
    return RegimeHysteresis(lo, hi, float(fitted[j]), float(100 * fitted[j] / (hi - lo)), float(grid[j]), len(d))


def _masks(label: np.ndarray, mask: np.ndarray | None) -> tuple[np.ndarray, np.ndarray]:
    keep = np.ones(len(label), bool) if mask is None else np.asarray(mask, bool)
    return (label == LOADING) & keep, (label == UNLOADING) & keep


def measure_hysteresis(
    B_abs_T: Sequence[float] | np.ndarray,
    force_N: Sequence[float] | np.ndarray,
    label: Sequence[str] | np.ndarray,
    regime_edges_N: Sequence[float],
    mask: np.ndarray | None = None,
    degree: int = HYSTERESIS_DEGREE,
) -> list[RegimeHysteresis]:
    """Per regime [edges[i], edges[i+1]]: the largest hysteresis at matched |B| and where.
    ``mask`` keeps rows (e.g. :func:`rows_without_first_cycle`)."""
    B, F, lab = np.asarray(B_abs_T, float), np.asarray(force_N, float), np.asarray(label, dtype=object)
    load, unload = _masks(lab, mask)
    F_load = force_at_field_N(B[load], F[load], B[unload], edges_N=regime_edges_N)
    d = F_load - F[unload]
    out = []
    for lo, hi in zip(regime_edges_N[:-1], regime_edges_N[1:]):
        inside = (F_load >= lo) & (F_load <= hi)
        out.append(_regime_peak(float(lo), float(hi), F_load[inside], d[inside], degree))
    return out


@dataclass(frozen=True)
class UnloadingModel:
    """h(F_load, F_turn) = F_turn (c0 + c1 x + c2 x^2 + c3 x^3 [+ e x^4 after a hold]),
    x = F_load / F_turn (module doc); ``sigma``: each coefficient's 1 sigma."""

    coefficients: tuple[float, ...]
    residual_rms_N: float
    samples: int
    sigma: tuple[float, ...] = ()
    after_hold: float = 0.0
    after_hold_sigma: float | None = None

    def h_N(self, F_load_N, F_turn_N, after_hold=False) -> np.ndarray:
        F_turn = np.asarray(F_turn_N, dtype=float)
        F_load = np.asarray(F_load_N, dtype=float)
        # no turn yet (F_turn = 0): no loop, h = 0 (the limit of F_turn p(x) with p bounded on [0, 1])
        ratio = np.divide(F_load, F_turn, out=np.zeros(np.broadcast(F_load, F_turn).shape), where=F_turn > 0.0)
        x = np.clip(ratio, 0.0, 1.0)
        poly = np.polynomial.polynomial.polyval(x, np.asarray(self.coefficients, float))
        return F_turn * (poly + np.where(after_hold, self.after_hold * x**4, 0.0))

    def unloading_force_N(self, F_load_N, F_turn_N, after_hold=False) -> np.ndarray:
        """The force an unloading reading means, from the loading branch's force at its |B|."""
        return np.asarray(F_load_N, dtype=float) - self.h_N(F_load_N, F_turn_N, after_hold)

    def record(self, full_scale_N: float) -> dict:
        """calibration.json's ``unloading_model``."""
        return {
            "form": "F_unloading = F_loading - F_turn (c0 + c1 x + c2 x^2 + c3 x^3 + after_hold x^4 when the "
            "unloading follows a hold), x = F_loading / F_turn",
            "coefficients": list(self.coefficients),
            "sigma": list(self.sigma),
            "after_hold": self.after_hold,
            "after_hold_sigma": self.after_hold_sigma,
            "residual_rms_N": self.residual_rms_N,
            "residual_pct_of_full_scale": 100 * self.residual_rms_N / full_scale_N if full_scale_N > 0 else None,
            "rows": self.samples,
        }


def rows_after_holds(label: np.ndarray, holds: Sequence[tuple[int, int]]) -> np.ndarray:
    """The unloading rows that follow a hold (up to the next row on another branch)."""
    out = np.zeros(len(label), bool)
    for _, z in holds:
        j = z
        while j < len(label) and label[j] == UNLOADING:
            out[j] = True
            j += 1
    return out


def fit_unloading(
    B_abs_T: Sequence[float] | np.ndarray,
    force_N: Sequence[float] | np.ndarray,
    label: Sequence[str] | np.ndarray,
    turn_force_N: Sequence[float] | np.ndarray,
    mask: np.ndarray | None = None,
    after_hold: np.ndarray | None = None,
) -> UnloadingModel:
    """Least-squares coefficients of the unloading model (each with its sigma) from the unloading
    rows, each against the loading rows' force at its |B|; the after-hold term only when some
    unloading rows follow a hold. The residual RMS is of force (N): what the model leaves
    unexplained."""
    B, F, lab = np.asarray(B_abs_T, float), np.asarray(force_N, float), np.asarray(label, dtype=object)
    load, unload = _masks(lab, mask)
    Ft = np.asarray(turn_force_N, float)[unload]
    F_load = force_at_field_N(B[load], F[load], B[unload])
    ok = np.isfinite(Ft) & (Ft > 0)
    held = (np.zeros(len(lab), bool) if after_hold is None else np.asarray(after_hold, bool))[unload][ok]
    if ok.sum() < UNLOADING_DEGREE + 4:
        raise CalibrationFailed("too few unloading rows after a turning point: no unloading model")
    x = np.clip(F_load[ok] / Ft[ok], 0.0, 1.0)
    cols = [Ft[ok] * x**j for j in range(UNLOADING_DEGREE + 1)]
    with_hold = int(held.sum()) >= 3
    if with_hold:
        cols.append(np.where(held, Ft[ok] * x**4, 0.0))
    A = np.stack(cols, -1)
    d = F_load[ok] - F[unload][ok]
    coef, *_ = np.linalg.lstsq(A, d, rcond=None)
    r = d - A @ coef
    cov = float(np.sum(r**2) / max(len(d) - A.shape[1], 1)) * np.linalg.pinv(A.T @ A)
    sd = np.sqrt(np.maximum(np.diag(cov), 0.0))
    n = UNLOADING_DEGREE + 1
    return UnloadingModel(
        tuple(float(c) for c in coef[:n]), float(np.sqrt(np.mean(r**2))), int(ok.sum()),
        tuple(float(v) for v in sd[:n]), float(coef[n]) if with_hold else 0.0, float(sd[n]) if with_hold else None,
    )  # fmt: skip


@dataclass(frozen=True)
class FirstCycle:
    difference_pct: float  # (cycle 1's force / the later cycles' at matched |B|) - 1, in %
    sigma_pct: float
    z: float
    differs: bool  # |z| > z_threshold
    z_threshold: float
    samples: int


def first_cycle(
    B_abs_T: Sequence[float] | np.ndarray,
    force_N: Sequence[float] | np.ndarray,
    label: Sequence[str] | np.ndarray,
    cycle: Sequence[int] | np.ndarray,
    z_threshold: float = FIRST_CYCLE_Z,
    neighbours: int = NEIGHBOURS,
) -> FirstCycle:
    """Cycle 1's loading branch against the later cycles' loading at matched |B|: the least
    squares p of F_1 - F_later(B) = p F_later(B) over rows above FIRST_CYCLE_MIN_FORCE_REL of
    the full scale, its sigma from the scatter (and the reference's own noise, 1/neighbours of
    a row's), and whether |p / sigma| exceeds ``z_threshold``."""
    B, F = np.asarray(B_abs_T, float), np.asarray(force_N, float)
    lab, cyc = np.asarray(label, dtype=object), np.asarray(cycle)
    later = (lab == LOADING) & (cyc > 1)
    first = (lab == LOADING) & (cyc == 1)
    first &= F > FIRST_CYCLE_MIN_FORCE_REL * np.max(F[later], initial=0.0)
    if first.sum() < 3 or later.sum() < neighbours:
        raise CalibrationFailed("too few loading rows in cycle 1 or after it to compare them")
    Fl = force_at_field_N(B[later], F[later], B[first], neighbours)
    d = F[first] - Fl
    p = float(np.sum(d * Fl) / np.sum(Fl**2))
    r = d - p * Fl
    n = len(d)
    sigma = float(np.sqrt(np.sum(r**2) / max(n - 1, 1)) / np.sqrt(np.sum(Fl**2)) * np.sqrt(1 + 1 / neighbours))
    z = p / sigma if sigma > 0 else float("inf")
    return FirstCycle(100 * p, 100 * sigma, float(z), bool(abs(z) > z_threshold), z_threshold, n)


def rows_without_first_cycle(cycle: Sequence[int] | np.ndarray, result: FirstCycle) -> np.ndarray:
    """Row mask: every row, but cycle 1's when it differs from the later cycles."""
    cyc = np.asarray(cycle)
    return cyc != 1 if result.differs else np.ones(len(cyc), bool)


@dataclass(frozen=True)
class Creep:
    pct_per_decade: float  # of the held force, per decade of t - t_start
    sigma_pct: float  # 1 sigma
    held_force_N: float
    samples: int


def creep(
    time_s: Sequence[float] | np.ndarray,
    reading: Sequence[float] | np.ndarray,
    hold: tuple[int, int],
    held_force_N: float | None = None,
    field_slope_T_per_N: float | None = None,
    t_start_s: float | None = None,
) -> Creep:
    """Creep over the hold rows [hold[0], hold[1]): ordinary least squares of the reading
    against log10(t - t_start) (t_start: the row before the hold, the one that reached the
    force), from CREEP_FROM_S into the hold. ``reading`` is a force (N), or |B| (T) when
    ``field_slope_T_per_N`` (d|B|/dF at the held force) is given. The held force defaults to the
    fit's value at t - t_start = 1 s."""
    a, b = hold
    t = np.asarray(time_s, float)
    y = np.asarray(reading, float)[a:b]
    t0 = float(t[a - 1]) if t_start_s is None and a > 0 else float(t_start_s if t_start_s is not None else t[a])
    keep = t[a:b] - t0 >= min(CREEP_FROM_S, 0.5 * float(t[b - 1] - t0))  # the ramp's stop is no creep
    L, y = np.log10(t[a:b][keep] - t0), y[keep]
    if len(y) < 3 or np.ptp(L) <= 0:
        raise CalibrationFailed("a hold needs 3 rows spread in time to measure creep")
    A = np.stack([np.ones_like(L), L], -1)
    coef, *_ = np.linalg.lstsq(A, y, rcond=None)
    r = y - A @ coef
    s2 = float(np.sum(r**2) / (len(y) - 2))
    cov = s2 * np.linalg.inv(A.T @ A)
    scale = 1.0 / field_slope_T_per_N if field_slope_T_per_N else 1.0
    level = held_force_N if held_force_N is not None else float(coef[0]) * scale
    if field_slope_T_per_N and held_force_N is None:
        raise CalibrationFailed("creep of |B| needs the held force")
    return Creep(
        float(100 * coef[1] * scale / level), float(100 * np.sqrt(cov[1, 1]) * abs(scale) / level), level, len(y)
    )
