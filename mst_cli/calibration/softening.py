"""Softening that fades (issue 47): the first presses of a rested sensor are stiffer, most at
light loads, less with every press.

Each press's loading rows are compared with the last press's at matched |B|
(:func:`~mst_cli.calibration.hysteresis.force_at_field_N`): d = F_k / F_last(B) - 1 at the load
fraction x = F_last / F_full. The law, fitted by least squares to every such row of the presses
before the last:

    press k is stiffer than the settled sensor by  A(x) k^-q,   A(x) = exp(a0 + a1 x + a2 x^2)

so d = (1 + A g(k)) / (1 + A g(K)) - 1 with g(k) = k^-q and K the last press (it is itself
slightly stiffer than a sensor pressed forever). Sigmas: the Jacobian's covariance scaled by the
residuals' scatter; A(x)'s by the delta method.

The rule: a press is left out of the elastic fit while the law puts it more than
:data:`SETTLED_PCT` % stiffer than the last press anywhere from 10 to 90 % of full scale (the
presses from the first that is within it are fitted). ``presses_to_settle``: the first press
within SETTLED_PCT % of the settled sensor over the same loads: how many presses to make before
a calibration's load test.

Pure: no file or terminal I/O.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy.optimize import least_squares

from mst_cli.calibration.branches import LOADING
from mst_cli.calibration.hysteresis import force_at_field_N

SETTLED_PCT = 2.0
MIN_FORCE_REL = 0.05  # rows compared from this fraction of the full scale
REPORT_X = (0.1, 0.5, 0.9)
X_GRID = np.linspace(0.1, 0.9, 17)
MIN_ROWS = 20
MIN_PRESSES = 4  # the law's four coefficients need three presses against the last (fewer: hysteresis.first_cycle)


@dataclass(frozen=True)
class Softening:
    """The fitted law (module doc) and the presses it leaves out."""

    coef: tuple[float, float, float, float]  # a0, a1, a2, q
    cov: np.ndarray
    last_press: int
    first_settled: int  # the first press fitted
    presses_to_settle: int
    rows: int
    residual_rms_pct: float

    def extra(self, x, k) -> np.ndarray:
        """A(x) k^-q: press k's extra stiffness over the settled sensor (a fraction)."""
        a0, a1, a2, q = self.coef
        x = np.asarray(x, float)
        return np.exp(a0 + a1 * x + a2 * x**2) * float(k) ** -q

    def _first_press_sigma(self, x: float) -> float:
        A = float(self.extra(x, 1))
        g = np.array([A, A * x, A * x * x, 0.0])
        return float(math.sqrt(max(g @ self.cov @ g, 0.0)))

    def over_last(self, x, k) -> np.ndarray:
        return (1 + self.extra(x, k)) / (1 + self.extra(x, self.last_press)) - 1

    def record(self) -> dict:
        """calibration.json's ``softening``."""
        return {
            "law": "press k is stiffer than the settled sensor by A(x) k^-q, A = exp(a0 + a1 x + a2 x^2), "
            "x = force / full scale, each press against the last at matched |B|",
            "first_press_stiffer_pct": {f"{round(100 * x)}_pct_fs": 100 * float(self.extra(x, 1)) for x in REPORT_X},
            "first_press_sigma_pct": {f"{round(100 * x)}_pct_fs": 100 * self._first_press_sigma(x) for x in REPORT_X},
            "second_over_last_pct": {f"{round(100 * x)}_pct_fs": 100 * float(self.over_last(x, 2)) for x in REPORT_X},
            "decay_q": self.coef[3],
            "decay_q_sigma": float(math.sqrt(max(self.cov[3, 3], 0.0))),
            "coefficients": list(self.coef[:3]),
            "last_press": self.last_press,
            "rule": f"presses more than {SETTLED_PCT:g} % stiffer than the last (10-90 % of full scale) are left "
            "out of the fit",
            "presses_left_out": self.first_settled - 1,
            "presses_to_settle": self.presses_to_settle,
            "rows": self.rows,
            "residual_rms_pct": self.residual_rms_pct,
        }

    def line(self) -> str:
        s = [self._first_press_sigma(x) for x in REPORT_X]
        first = " / ".join(f"{100 * float(self.extra(x, 1)):+.0f}" for x in REPORT_X)
        return (
            f"softening: press 1 stiffer by {first} % at 10/50/90 % of full scale (+- "
            f"{' / '.join(f'{100 * v:.0f}' for v in s)}), fading as press^-{self.coef[3]:.2f} "
            f"(+- {math.sqrt(max(self.cov[3, 3], 0.0)):.2f}); presses 1-{self.first_settled - 1} left out of the "
            f"fit; settled within {SETTLED_PCT:g} % after {self.presses_to_settle} presses"
        )


def _model(p, x, k, K):
    a0, a1, a2, q = p
    A = np.exp(a0 + a1 * x + a2 * x * x)
    return (1 + A * k**-q) / (1 + A * K**-q) - 1


def fit_softening(B_abs_T, force_N, label, cycle) -> Softening | None:
    """The law from the loading rows of every press against the last's (None: fewer than
    MIN_PRESSES presses, or too few rows)."""
    B, F = np.asarray(B_abs_T, float), np.asarray(force_N, float)
    lab, cyc = np.asarray(label, dtype=object), np.asarray(cycle, int)
    load = lab == LOADING
    K = int(cyc[load].max(initial=0))
    ref = load & (cyc == K)
    if K < MIN_PRESSES or ref.sum() < 12:
        return None
    full = float(F[ref].max())
    rows = load & (cyc < K) & (F > MIN_FORCE_REL * full)
    if rows.sum() < MIN_ROWS:
        return None
    F_ref = force_at_field_N(B[ref], F[ref], B[rows])
    ok = F_ref > MIN_FORCE_REL * full
    x, k, d = F_ref[ok] / full, cyc[rows][ok].astype(float), F[rows][ok] / F_ref[ok] - 1
    bounds = ([-10.0, -20.0, -20.0, 0.0], [3.0, 20.0, 20.0, 6.0])
    fit = least_squares(lambda p: _model(p, x, k, K) - d, x0=[math.log(0.3), -2.0, 0.0, 1.0], bounds=bounds)
    r = fit.fun
    dof = max(len(d) - 4, 1)
    try:
        cov = np.linalg.inv(fit.jac.T @ fit.jac) * float(np.sum(r**2) / dof)
    except np.linalg.LinAlgError:
        return None
    coef = tuple(float(v) for v in fit.x)
    if not np.all(np.isfinite(cov)):
        return None
    law = Softening(coef, cov, K, 1, 1, int(len(d)), float(100 * np.sqrt(np.mean(r**2))))  # type: ignore[arg-type]
    first = next((j for j in range(1, K + 1) if np.max(law.over_last(X_GRID, j)) * 100 <= SETTLED_PCT), K)
    settle = next((j for j in range(1, 1000) if np.max(law.extra(X_GRID, j)) * 100 <= SETTLED_PCT), 1000)
    return Softening(coef, cov, K, first, settle, int(len(d)), law.residual_rms_pct)  # type: ignore[arg-type]
