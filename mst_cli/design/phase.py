"""The phase runner: one local nlopt run on a batched score/constraint function.

Every nlopt run of the design search (:mod:`mst_cli.design.solver`'s phases) and of the refine
loop's warm-started re-match (:mod:`mst_cli.design.refine`) goes through :meth:`Phase.run`, the
one place that builds an nlopt optimiser: bounds, callbacks, stopping rules, how a run ends.

Every run has maxeval and maxtime set. A local run can return its last iterate rather than
its best, and a ForcedStop discards what it found, so :class:`Tracker` records the best
point seen by any callback; RoundoffLimited, ForcedStop and nlopt's generic failure end a
run normally. The result depends only on the inputs (the wall-clock limit is a safety net
that normal runs never reach).
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass
from typing import TYPE_CHECKING, NamedTuple

import numpy as np

if TYPE_CHECKING:
    from collections.abc import Callable

FD_STEP = 1e-6  # central-difference step in normalised variables
FEASIBILITY_TOL = 1e-9  # SLSQP lands on active constraints to ~1e-13; far inside the
# ROUNDING_SAFETY slack, so such points count as feasible
MAX_TIME_S = 120.0  # safety net only; normal runs stop on evaluation counts
# a run whose callbacks have met feasible points of one score (to STALL_REL of it, or of STALL_FLOOR
# when smaller) STALL_CALLS times in a row has stalled: SLSQP's line searches at a converged point
# repeat its score to 1e-8 without ending (docs/performance.md, "The search stops where it has stalled")
STALL_CALLS = 6
STALL_REL = 1e-8
STALL_FLOOR = 1e-3
LOCAL_METHODS = ("slsqp", "cobyla")
# how a run ends when nlopt stopped on its own rules or the phase's goal was reached (not the
# evaluation count, a failure, roundoff or a forced stop)
CONVERGED = frozenset({"success", "stopval", "ftol", "xtol", "maxtime", "goal reached", "stalled"})


@dataclass
class Tracker:
    """Best point of one phase: feasible beats infeasible; then lower score, lower violation."""

    u: np.ndarray | None = None
    score: float = math.inf
    violation: float = math.inf
    feasible: bool = False

    def offer(self, u: np.ndarray, score: float, violation: float) -> bool:
        feasible = violation <= FEASIBILITY_TOL
        if self.u is None:
            better = True
        elif feasible != self.feasible:
            better = feasible
        elif feasible:
            better = score < self.score
        else:
            better = (violation, score) < (self.violation, self.score)
        if better:
            self.u, self.score, self.violation, self.feasible = np.array(u, float), score, violation, feasible
        return better


class Budget:
    """Candidate designs a search may evaluate, the progress report, and the wall-clock net."""

    def __init__(self, max_evaluations: int, progress, max_time_s: float):
        self.max = int(max_evaluations)
        self.used = 0
        self.progress = progress
        self.deadline = time.monotonic() + max_time_s
        self._next_report = 0

    @property
    def left(self) -> int:
        return self.max - self.used

    def spend(self, n: int, phase: str, best_err: float) -> None:
        self.used += n
        if self.progress is not None and self.used >= self._next_report:
            self._next_report = self.used + max(self.max // 100, 1)
            self.progress(min(self.used, self.max), self.max, phase, best_err)

    def time_left(self) -> float:
        return max(self.deadline - time.monotonic(), 1e-3)


def _nlopt_failures() -> tuple:
    """nlopt's generic failure: Python's RuntimeError up to nlopt 2.10, its own
    ``nlopt.runtime_error`` (not a RuntimeError) from 2.11 on."""
    import nlopt  # deferred: the optimiser loads when a design is searched, not at start-up

    return tuple(e for e in (getattr(nlopt, "runtime_error", None),) if isinstance(e, type))


class _Stop(Exception):
    """Raised inside a callback when the budget is gone or the phase's goal is reached."""

    def __init__(self, reason: str):
        super().__init__(reason)
        self.reason = reason


_STENCILS: dict[int, np.ndarray] = {}


def _stencil(dim: int) -> np.ndarray:
    """(2 dim + 1, dim): 0, then +FD_STEP e_i, then -FD_STEP e_i (u - h and u + (-h) are the same
    number); one per dimension, made once."""
    got = _STENCILS.get(dim)
    if got is None:
        eye = np.eye(dim) * FD_STEP
        got = _STENCILS[dim] = np.concatenate([np.zeros((1, dim)), eye, -eye])
    return got


def finite(a: np.ndarray, fill: float) -> np.ndarray:
    """``a`` with every non-finite entry ``fill``; ``a`` itself when all are finite (a finite
    sum says so in one reduction; one that overflows takes the full path, as a NaN does)."""
    if math.isfinite(np.add.reduce(a, axis=None)):
        return a
    return np.where(np.isfinite(a), a, fill)


class PointValues(NamedTuple):
    """What a callback needs of its point: score, constraints, their central differences
    (None without a gradient), the constraint violation and the worst |relative error|."""

    f: float
    g: np.ndarray
    df: np.ndarray | None
    dg: np.ndarray | None
    violation: float
    err: float


def point_values(score: np.ndarray, g: np.ndarray, dim: int, err: float) -> PointValues:
    """A callback's batch reduced to its point: the nominal point's score and constraints
    (non-finite ones replaced), their central differences when ``dim`` (a stencil of 2 dim + 1
    points), and the point's constraint violation (np.sum's reduction without its wrapper: a
    1-d sum, the same bits)."""
    score, g = finite(score, 1e30), finite(g, 1e6)
    df = dg = None
    if dim:
        df = (score[1 : dim + 1] - score[dim + 1 :]) / (2 * FD_STEP)
        dg = ((g[1 : dim + 1] - g[dim + 1 :]) / (2 * FD_STEP)).T
    return PointValues(float(score[0]), g[0], df, dg, float(np.add.reduce(np.maximum(g[0], 0.0), axis=None)), err)


class Batch:
    """A phase's function of points: ``self(U)`` evaluates points U (k, dim) and returns
    (score (k,), g (k, m), worst |relative error| of U[0]); ``m`` constraints per point, each
    point ``cost`` kernel stacks. :meth:`point` is what the runner asks for."""

    m: int
    cost = 1

    def __call__(self, U: np.ndarray) -> tuple[np.ndarray, np.ndarray, float]:
        raise NotImplementedError

    def point(self, U: np.ndarray, dim: int) -> PointValues:
        """The values of U's first point, with central differences when ``dim`` (U is then the
        point and its stencil)."""
        score, g, err = self(U)
        return point_values(score, g, dim, err)


@dataclass(frozen=True)
class LocalRun:
    """The settings of one nlopt run: the method, the evaluation cap, the initial step (unit
    variables) and the box (default the unit cube)."""

    local: str
    maxeval: int
    step: float
    lower: np.ndarray | float = 0.0
    upper: np.ndarray | float = 1.0


class Phase:
    """One local nlopt run on a :class:`Batch`.

    With a gradient-based method the callback evaluates u and its 2*dim central-difference
    neighbours in one batch. The nominal point of every callback is offered to ``tracker``;
    ``goal(f, g, err)`` True ends the run (ForcedStop, the tracker keeps the point). With
    ``stall_calls``, a run whose feasible points have kept one score (to :data:`STALL_REL`) for
    that many callbacks in a row ends "stalled" (a phase with no goal: the preference polish).
    """

    def __init__(
        self, batch: Batch, tracker: Tracker, budget: Budget, label: str, goal: Callable | None = None,
        stall_calls: int = 0,
    ) -> None:  # fmt: skip
        self.batch, self.tracker, self.budget, self.label, self.goal = batch, tracker, budget, label, goal
        self.key: tuple | None = None
        self.stall_calls, self._since = stall_calls, 0
        self._level: float | None = None  # the score the callbacks since the last move stay at

    def _stalled(self, score: float, violation: float) -> bool:
        """Whether the run has stalled: ``stall_calls`` callbacks in a row at feasible points whose
        score stays within STALL_REL (of itself, or of STALL_FLOOR when smaller) of the level the
        first of them set. An infeasible point, or one off the level, sets it again."""
        level = self._level
        moved = level is None or not abs(score - level) <= STALL_REL * max(abs(level), STALL_FLOOR)
        if violation > FEASIBILITY_TOL or moved:
            self._level, self._since = score, 0
            return False
        self._since += 1
        return self._since >= self.stall_calls

    def _compute(self, u, want_grad):
        key = (u.tobytes(), want_grad)
        if self.key is not None and (self.key[0] == key[0] and (self.key[1] or not want_grad)):
            return
        if self.budget.left <= 0:
            raise _Stop("evaluation budget spent")
        dim = u.size
        if want_grad:
            U = u + _stencil(dim)  # u, u + FD_STEP e_i, u - FD_STEP e_i
            U[0] = u
        else:
            U = u[None]
        values = self.batch.point(U, dim if want_grad else 0)
        self.f, self.g = values.f, values.g
        if want_grad:
            self.df, self.dg = values.df, values.dg
        self.key = key
        self.tracker.offer(u, self.f, values.violation)
        self.budget.spend(self.batch.cost * len(U), self.label, values.err)
        if self.goal is not None and self.goal(self.f, self.g, values.err):
            raise _Stop("goal reached")
        if self.stall_calls and self._stalled(self.f, values.violation):
            raise _Stop("stalled")

    def objective(self, u, grad) -> float:
        self._compute(u, grad.size > 0)
        if grad.size > 0:
            grad[:] = self.df
        return self.f

    def constraints(self, result, u, grad) -> None:
        self._compute(u, grad.size > 0)
        result[:] = self.g
        if grad.size > 0:
            grad[:] = self.dg

    def run(self, x0, settings: LocalRun) -> str:
        """Run nlopt from ``x0`` (clipped into the box); how the run ended (:data:`CONVERGED`
        names the ends on nlopt's own rules or the goal). The tracker holds the best point
        seen, however it ended."""
        import nlopt  # deferred: the optimiser loads when a design is searched, not at start-up

        NLOPT_FAILURES = _nlopt_failures()
        dim = len(x0)
        lower, upper = np.broadcast_to(settings.lower, dim), np.broadcast_to(settings.upper, dim)
        opt = nlopt.opt(nlopt.LD_SLSQP if settings.local == "slsqp" else nlopt.LN_COBYLA, dim)
        opt.set_lower_bounds(lower)
        opt.set_upper_bounds(upper)
        opt.set_min_objective(self.objective)
        opt.add_inequality_mconstraint(self.constraints, np.full(self.batch.m, FEASIBILITY_TOL))
        opt.set_initial_step(np.full(dim, settings.step))
        opt.set_maxeval(max(int(settings.maxeval), 1))
        opt.set_maxtime(self.budget.time_left())
        opt.set_xtol_rel(1e-10)
        opt.set_ftol_abs(1e-16)
        opt.set_ftol_rel(1e-12)
        try:
            opt.optimize(np.clip(np.asarray(x0, float), settings.lower, settings.upper))
        except _Stop as stop:
            return stop.reason
        except nlopt.ForcedStop:
            return "forced stop"
        except nlopt.RoundoffLimited:
            return "roundoff-limited"
        except (RuntimeError, *NLOPT_FAILURES):  # nlopt's generic failure (SLSQP line search)
            return "nlopt failure"
        code = opt.last_optimize_result()
        return {1: "success", 2: "stopval", 3: "ftol", 4: "xtol", 5: "maxeval", 6: "maxtime"}.get(code, str(code))
