"""``mst read`` on a rig's stream (issue 38): tare, no load, and the branch of each reading.

* tare (``--tare N``): the first N readings are taken at no load; their mean |B| replaces the
  calibration's unloaded field (every |B| shifted by the difference: the chip's offset and the
  magnet's placement move the whole curve, not its shape);
* track zero (``--track-zero``, issue 47): re-zero at every rest of the stream (|B| flat near the
  unloaded field), with the calibration's recovery after each unloading and its drift between
  rests (:func:`~mst_cli.calibration.zero_drift.track_zero_T`);
* no load: a reading below the unloaded field by less than :data:`NO_LOAD_SIGMAS` field
  resolutions (the chip's noise between presses) reads 0 N, flagged ok; only a reading further
  below is below_range;
* the branch: the loading-branch force of each reading (the inverse map) is followed in time
  order, counted in local force resolutions (:func:`in_resolutions`); a reversal counts once it
  moves back by more than the dead band of the stream's own noise
  (:func:`~mst_cli.calibration.branches.find_branches`); an unloading reading means the force the
  calibration's unloading model gives from the loading force and the last turning
  force (:class:`~mst_cli.calibration.hysteresis.UnloadingModel`); a hold keeps the loading force;
* the uncertainty of each force: the local force resolution, the unloading model's residual on
  unloading rows, and half the hysteresis the reader cannot resolve on hold rows (the sensor may
  sit anywhere between its loading and unloading curves there).

Pure: no file or terminal I/O.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from mst_cli.calibration.branches import HOLD, LOADING, UNLOADING, find_branches
from mst_cli.calibration.hysteresis import UnloadingModel, rows_after_holds
from mst_cli.calibration.record_bounds import checked, checked_list, unloading_loop
from mst_cli.calibration.zero_drift import track_zero_T, zero_law_of
from mst_cli.errors import InputError

NO_LOAD_SIGMAS = 6.0  # a reading this many field resolutions below no load is below_range; closer, 0 N
MIN_BRANCH_ROWS = 5  # fewer in-range readings: no branch is followed (every reading loading)


def unloading_model_of(hysteresis: object) -> UnloadingModel | None:
    """The unloading model of calibration.json's hysteresis section (None when it holds none:
    the reader then reads every sample on the loading branch). InputError naming the key when a
    term is not a number inside its physical bound (:mod:`~mst_cli.calibration.record_bounds`)."""
    if not isinstance(hysteresis, dict) or not isinstance(hysteresis.get("unloading_model"), dict):
        return None
    m, path = hysteresis["unloading_model"], "hysteresis.unloading_model"
    coef = checked_list(m, path, "coefficients")
    if coef is None:  # mst 0.17's h = F_turn x (1 - x) (a + b x), as the polynomial it is
        a, b = checked(m, path, "a"), checked(m, path, "b")
        coef = [0.0, a, b - a, -b] if a is not None and b is not None else None
    residual = checked(m, path, "residual_rms_N")
    if coef is None or residual is None:
        return None
    hold = checked(m, path, "after_hold") or 0.0
    unloading_loop(coef, hold)
    rows = int(checked(m, path, "rows") or 0)
    return UnloadingModel(tuple(coef), residual, rows, (), hold)


def tare_shift_T(B_abs_T: np.ndarray, tare: int, B_unloaded_T: float, source: str) -> float:
    """The |B| shift that puts the mean of the first ``tare`` readings on the unloaded field."""
    if not 1 <= tare <= len(B_abs_T):
        raise InputError("--tare", tare, f"a number of readings at no load, 1..{len(B_abs_T)} (the rows of {source})")
    return float(np.mean(B_abs_T[:tare]) - B_unloaded_T)


def zero_shift_T(
    B_abs_T: np.ndarray, time_s: np.ndarray | None, imap_B_abs_T: np.ndarray, tare: int, track: bool,
    zero_record: object, source: str,
) -> np.ndarray | float:  # fmt: skip
    """The |B| shift to subtract before the inverse map: ``tare`` (the first readings at no load),
    ``track`` (re-zero at every rest, with the calibration's recovery after each unloading and its
    drift: :func:`~mst_cli.calibration.zero_drift.track_zero_T`), or 0."""
    B0 = float(imap_B_abs_T[0])
    if track:
        span = float(imap_B_abs_T[-1] - imap_B_abs_T[0])
        law = zero_law_of(zero_record)
        # rests go where the calibration's rest rows sat (the fit's curve may pass a little off them)
        return track_zero_T(B_abs_T, time_s, law.B0_T if law is not None else B0, span, law)
    return tare_shift_T(B_abs_T, tare, B0, source) if tare else 0.0


def no_load_rows(B_abs_T: np.ndarray, flag: np.ndarray, B_unloaded_T: float, resolution_T: float) -> np.ndarray:
    """below_range readings within NO_LOAD_SIGMAS field resolutions of no load."""
    return (flag == "below_range") & (B_abs_T >= B_unloaded_T - NO_LOAD_SIGMAS * resolution_T)


@dataclass
class BranchForces:
    force_N: np.ndarray
    branch: np.ndarray  # loading / unloading / hold ("" where flagged)
    uncertainty_N: np.ndarray
    model_used: bool = False  # unloading readings read with the calibration's unloading model


def _sorted(x: np.ndarray, y: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    order = np.argsort(x, kind="stable")
    return x[order], y[order]


def in_resolutions(F_N: np.ndarray, resolution_N: np.ndarray) -> np.ndarray:
    """The force as a count of local resolutions from the smallest (u = integral of dF / dF_res):
    a reading's noise is one unit at every load, so one dead band finds the turning points in the
    soft regime and the stiff one alike (a dead band in newtons is noise-wide at one end only)."""
    F, res = _sorted(np.asarray(F_N, float), np.maximum(np.asarray(resolution_N, float), 1e-12))
    u = np.concatenate([[0.0], np.cumsum(np.diff(F) * 0.5 * (1 / res[1:] + 1 / res[:-1]))])
    return np.interp(F_N, F, u)


def follow_branches(
    F_load_N: np.ndarray, resolution_N: np.ndarray, model: UnloadingModel | None, time_s: np.ndarray | None = None
) -> BranchForces:
    """Each reading on its branch (module doc): ``F_load_N`` the loading-branch force (NaN where
    flagged), ``resolution_N`` the local force resolution of each."""
    n = len(F_load_N)
    ok = np.isfinite(F_load_N)
    F = F_load_N.copy()
    branch = np.full(n, "", dtype=object)
    unc = np.where(ok, resolution_N, np.nan)
    branch[ok] = LOADING
    if ok.sum() < MIN_BRANCH_ROWS:
        return BranchForces(F, branch, unc)
    idx = np.flatnonzero(ok)
    u = in_resolutions(F_load_N[idx], resolution_N[idx])
    b = find_branches(u, None if time_s is None else time_s[idx])
    branch[idx] = b.label
    if model is None:
        return BranchForces(F, branch, unc)
    turn = np.interp(b.turn_force_N, *_sorted(u, F_load_N[idx]))  # the force at each turning point
    un = (b.label == UNLOADING) & np.isfinite(turn) & (turn > 0)
    held = rows_after_holds(b.label, b.holds)[un]
    F[idx[un]] = model.unloading_force_N(F_load_N[idx[un]], turn[un], held)
    unc[idx[un]] = np.hypot(unc[idx[un]], model.residual_rms_N)
    hold = b.label == HOLD
    if hold.any():
        top = np.maximum.accumulate(F_load_N[idx])[hold]
        unc[idx[hold]] = np.hypot(unc[idx[hold]], 0.5 * model.h_N(F_load_N[idx[hold]], top))
    return BranchForces(F, branch, unc, True)
