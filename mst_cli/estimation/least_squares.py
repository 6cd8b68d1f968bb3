"""The one least-squares solver of the load estimators: Levenberg-Marquardt over a batch of
readings at once (issue 45), a single reading being a batch of one.

Every row of ``theta`` (m, p) is fitted to its reading (m, K) on its own damping: the chi^2 is
the squared residual (model - reading) / noise, the step solves (J^T J + lambda D) step = -J^T r
over the free unknowns, D = diag(J^T J) (Marquardt's scaling, so the units of the unknowns do not
count), and the trial is clipped to the model's domain by the caller's ``clip``. A step that does
not raise chi^2 is taken and the damping divided by :attr:`Damping.factor` (floored); one that
does is refused, the damping multiplied by it, and the row tries again at the next iteration from
the same Jacobian (an iteration is one trial per row, taken or not: the batch moves in lock step).
A row ends once its step is within ``step_tol`` of its bound's sigma in every unknown
(|step_i| sqrt(D_ii) <= step_tol: step_tol of a 1-sigma, since sqrt(D_ii) / noise is unknown i's
information) or lowers chi^2 by less than step_tol^2 of chi^2 (or of 1, whichever is more); once
such a short step at Gauss-Newton's damping (:attr:`Damping.gauss_newton`) is no better (the
minimum to round-off: more damping only shortens it); or once its damping passes
:attr:`Damping.ceiling`. A model that has no answer at a load (a layer's equilibrium not found)
returns NaN there, a chi^2 of inf: such a trial is refused, such a start taken from at once.

``siblings``: rows in runs of that many starts of one reading (a multi-start fit); a row ends once
within ``merge_sigma`` of its step's scale of a sibling of lower chi^2 (the same minimum).

Who calls it: the exact general-load reader (:class:`~mst_cli.estimation.shear_reading.ShearReader`,
the scalar model per load, its Jacobian by differences), and the two-chip reader
(:mod:`~mst_cli.estimation.two_chip_table`: first on the tabulated states, then on the exact ones,
with their tangent's Jacobian).

Two other solves are not this one, on purpose: the offset estimator's projected Gauss-Newton
(:mod:`~mst_cli.estimation.offset_reading`) and the one-chip tables' cell-bounded Gauss-Newton
(:mod:`~mst_cli.estimation.inverse_table`, and its C twin in the header). Both solve a square
system, three field axes for three unknowns, for a root inside a box (the force range and the face,
or the table's cells); there is no residual left to minimise, only a root to find or to miss. So
they take undamped Gauss-Newton steps, hold a coordinate that sits on the box's face, cut a step
that leaves the box and halve one that does not lower the misfit a fixed few times, and stop when
the step would move the field by a fraction of the noise; a solve that ends off the reading found
no root (``no_fit``), and two that end on different roots are ``ambiguous``. Levenberg damping
would turn a missed root into a least-squares compromise inside the box, and the box is a hard
bound there (the table's cells end; the header cannot search past them), not a clip of a trial.
The cell-bounded one is also written step for step as the header does it in float (Cramer's rule
on 3 x 3, a fixed count of steps and halvings), which this solver's batched linear algebra is not.

Pure: no I/O.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

# loads (m, p) and each row's warm start (the model's own, e.g. the layers' states of a close load;
# None at the first call) -> (fields (m, K), the warm start at those loads, or None)
Model = Callable[[np.ndarray, Any], tuple[np.ndarray, Any]]
# (loads (m, p), their fields (m, K), their warm start) -> dB/dtheta (m, K, len(free))
Jacobian = Callable[[np.ndarray, np.ndarray, Any], np.ndarray]


@dataclass(frozen=True)
class Damping:
    """The Levenberg damping's schedule: its start, floor and ceiling, the factor it moves by,
    and the damping below which a step is Gauss-Newton's."""

    start: float = 1e-3
    floor: float = 1e-6
    ceiling: float = 1e8
    factor: float = 10.0
    gauss_newton: float = 1e-2


DAMPING = Damping()


@dataclass
class Fit:
    """Where every row ended: the loads (m, p), chi^2 (m,), the Jacobian (m, K, len(free)) and
    fields (m, K) there, and the model's warm start there."""

    theta: np.ndarray
    chi2: np.ndarray
    jacobian: np.ndarray
    fields: np.ndarray
    warm: Any


def _chi2(fields: np.ndarray, data: np.ndarray, noise: float) -> np.ndarray:
    """(m,) the squared residual in noise units; inf where the model has no answer."""
    c = np.sum(((fields - data) / noise) ** 2, axis=1)
    return np.where(np.isnan(c), np.inf, c)


def _rows(warm: Any, rows: np.ndarray) -> Any:
    return None if warm is None else warm[rows]


def levenberg_marquardt(
    model: Model,
    jacobian: Jacobian,
    data: np.ndarray,
    theta: np.ndarray,
    noise: float,
    clip: Callable[[np.ndarray], np.ndarray],
    max_iter: int,
    step_tol: float,
    free: Sequence[int] | None = None,
    damping: Damping = DAMPING,
    siblings: int = 1,
    merge_sigma: float = 1.0,
) -> Fit:
    """Every row of ``theta`` (m, p) fitted to its reading ``data`` (m, K), the unknowns
    ``free`` (all unless given) moved, the others held (see the module's account)."""
    cols = np.arange(theta.shape[1]) if free is None else np.asarray(free)
    theta = clip(np.array(theta, dtype=float))
    fields, warm = model(theta, None)
    cost = _chi2(fields, data, noise)
    J = jacobian(theta, fields, warm)
    lam = np.full(len(theta), damping.start)
    active = np.arange(len(theta))
    for _ in range(max_iter):
        if not len(active):
            break
        trial, scale = _trial(J[active], fields[active] - data[active], noise, lam[active], theta[active], cols, clip)
        t_fields, t_warm = model(trial, _rows(warm, active))
        t_cost = _chi2(t_fields, data[active], noise)
        better = t_cost <= cost[active]
        short = np.all(np.abs(trial[:, cols] - theta[active][:, cols]) * scale <= step_tol, axis=1)
        small = short | (cost[active] - t_cost <= step_tol**2 * np.maximum(cost[active], 1.0))
        stalled = ~better & short & (lam[active] <= damping.gauss_newton)
        acc = active[better]
        theta[acc], fields[acc], cost[acc] = trial[better], t_fields[better], t_cost[better]
        if warm is not None:
            warm[acc] = t_warm[better]
        lam[acc] = np.maximum(lam[acc] / damping.factor, damping.floor)
        lam[active[~better]] *= damping.factor
        done = (better & small) | stalled | (lam[active] > damping.ceiling)
        if siblings > 1:
            done |= _behind_a_sibling(theta[:, cols], cost, active, scale, siblings, merge_sigma)
        if len(acc):
            J[acc] = jacobian(theta[acc], fields[acc], _rows(warm, acc))
        active = active[~done]
    return Fit(theta, cost, J, fields, warm)


def _trial(
    J: np.ndarray,
    residual: np.ndarray,
    noise: float,
    lam: np.ndarray,
    theta: np.ndarray,
    cols: np.ndarray,
    clip: Callable[[np.ndarray], np.ndarray],
) -> tuple[np.ndarray, np.ndarray]:
    """(the damped step's clipped trial loads, sqrt(diag(J^T J)) of the weighted J: each free
    unknown's inverse sigma per unit noise) of rows whose Jacobians are ``J``."""
    Jw = J / noise
    A = np.einsum("mki,mkj->mij", Jw, Jw)
    g = np.einsum("mki,mk->mi", Jw, residual / noise)
    scale2 = np.maximum(np.diagonal(A, axis1=1, axis2=2), 1e-300)
    damped = A + lam[:, None, None] * (scale2[:, :, None] * np.eye(len(cols)))
    trial = theta.copy()
    trial[:, cols] -= np.linalg.solve(damped, g[:, :, None])[:, :, 0]
    return clip(trial), np.sqrt(scale2)


def _behind_a_sibling(
    theta: np.ndarray, cost: np.ndarray, active: np.ndarray, inv_step: np.ndarray, siblings: int, merge_sigma: float
) -> np.ndarray:
    """Which ``active`` rows lie within ``merge_sigma`` / ``inv_step`` (per unknown) of another row
    of their reading (rows in runs of ``siblings``) whose chi^2 is lower (or equal and first)."""
    first = active - active % siblings
    others = first[:, None] + np.arange(siblings)[None, :]  # (a, S) every row of the reading
    near = np.all(np.abs(theta[others] - theta[active, None, :]) * inv_step[:, None, :] <= merge_sigma, axis=2)
    lower = (cost[others] < cost[active, None]) | ((cost[others] == cost[active, None]) & (others < active[:, None]))
    return np.any(near & lower, axis=1)
