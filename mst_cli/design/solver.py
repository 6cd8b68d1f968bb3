"""nlopt driver: seeded multi-start local search for the match, then a tie-break polish.

1. Screening: a seeded batch of random candidates in the unit box goes through the vectorised
   problem in one call; the best by (match objective + penalty x constraint violation) become
   the starting points.
2. Match (phase 1): a local nlopt run from each start in turn, on the normalised variables,
   until one reaches every target within MATCH_FRACTION x tolerance.
3. Tie-break (phase 2): from that point, minimise the print-error sensitivity
   (:meth:`DesignProblem.tie_break`) with every target kept within BAND_FRACTION x tolerance
   as extra constraints.
4. Re-match (phase 3): the polish may sit anywhere in that band; a short match run with a
   small step pulls every target back within MATCH_FRACTION x tolerance without leaving the
   robust region.
5. Final polish (phase 4): the tie-break again from there, with the band narrowed to
   MATCH_FRACTION x tolerance, so the design is the most robust one among those that meet
   every target to that tighter band (phase 3 alone can slide off a bound, for example).

The local method is nlopt's LD_SLSQP by default: the problem is smooth and vectorised, so a
central-difference gradient of the objective and all constraints is *one* batched kernel
call of 6n + 1 candidates, and SLSQP converges in a few dozen iterations where LN_COBYLA
needs thousands of single calls (benchmarks/bench_design.py measures both; ``local="cobyla"``
selects the derivative-free one). Both honour the nonlinear inequality constraints (MLSL
would not).

Every run has maxeval and maxtime set. A local run can return its last iterate rather than
its best, and a ForcedStop discards what it found, so :class:`Tracker` records the best
point seen by any callback; RoundoffLimited, ForcedStop and nlopt's generic failure end a
run normally. The result depends only on the spec and the seed (the wall-clock limit is a
safety net that normal runs never reach), so the same seed gives the same design.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field

import numpy as np

from .problem import DesignProblem

INITIAL_STEP = 0.1           # fraction of every (normalised) variable's range
MATCH_FRACTION = 0.05        # phase 1 ends when every |error| <= this x tolerance
BAND_FRACTION = 0.5          # phase 2 keeps every |error| <= this x tolerance
ROUNDING_SAFETY = 1e-3       # constraint slack (nozzles / log units) so that the rounded
                             # design written to design.yaml still satisfies every rule
SCREEN_PER_DIM = 400         # screening batch size per design variable
N_STARTS = 24                # starting points kept from the screening
FD_STEP = 1e-6               # central-difference step in normalised variables
FEASIBILITY_TOL = 1e-9       # SLSQP lands on active constraints to ~1e-13; far inside the
                             # ROUNDING_SAFETY slack, so such points count as feasible
MAX_TIME_S = 120.0           # safety net only; normal runs stop on evaluation counts
LOCAL_METHODS = ("slsqp", "cobyla")


@dataclass
class Tracker:
    """Best point of one phase: feasible beats infeasible; then lower score, lower violation."""

    u: np.ndarray | None = None
    score: float = math.inf
    violation: float = math.inf
    feasible: bool = False

    def offer(self, u, score: float, violation: float) -> bool:
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


@dataclass
class SolveResult:
    u: np.ndarray                    # best point (normalised)
    matched: bool                    # phase 1 reached MATCH_FRACTION x tolerance
    evaluations: int                 # candidate designs through the kernels (tie-break: 3 each)
    starts_used: int
    tie_break_before: float | None   # tie-break value at the phase-1 point
    tie_break_after: float | None
    local: str = "slsqp"
    stops: list[str] = field(default_factory=list)   # how each nlopt run ended


class _Budget:
    def __init__(self, max_evaluations: int, progress, max_time_s: float):
        self.max = int(max_evaluations)
        self.used = 0
        self.progress = progress
        self.deadline = time.monotonic() + max_time_s
        self._next_report = 0

    @property
    def left(self) -> int:
        return self.max - self.used

    def spend(self, n: int, phase: str, best_err: float):
        self.used += n
        if self.progress is not None and self.used >= self._next_report:
            self._next_report = self.used + max(self.max // 100, 1)
            self.progress(min(self.used, self.max), self.max, phase, best_err)

    def time_left(self) -> float:
        return max(self.deadline - time.monotonic(), 1e-3)


class _Stop(Exception):
    """Raised inside a callback when the budget is gone or the phase's goal is reached."""

    def __init__(self, reason: str):
        super().__init__(reason)
        self.reason = reason


class _Phase:
    """One local nlopt run on a batched score/constraint function.

    ``batch(U)`` evaluates points U (k, dim) and returns (score (k,), g (k, m), cost per point).
    With a gradient-based method the callback evaluates u and its 2*dim central-difference
    neighbours in one batch. The nominal point of every callback is offered to ``tracker``;
    ``goal(u, score, g)`` True ends the run (ForcedStop, the tracker keeps the point).
    """

    def __init__(self, problem, batch, m, tracker, budget, phase, goal=None):
        self.problem, self.batch, self.m = problem, batch, m
        self.tracker, self.budget, self.phase, self.goal = tracker, budget, phase, goal
        self.key = None

    def _compute(self, u, want_grad):
        key = (u.tobytes(), want_grad)
        if self.key is not None and (self.key[0] == key[0] and (self.key[1] or not want_grad)):
            return
        if self.budget.left <= 0:
            raise _Stop("evaluation budget spent")
        dim = u.size
        if want_grad:
            eye = np.eye(dim) * FD_STEP
            U = np.concatenate([u[None], u + eye, u - eye])
        else:
            U = u[None]
        score, g, cost, err = self.batch(U)
        score = np.where(np.isfinite(score), score, 1e30)
        g = np.where(np.isfinite(g), g, 1e6)
        self.f, self.g = float(score[0]), g[0]
        if want_grad:
            self.df = (score[1:dim + 1] - score[dim + 1:]) / (2 * FD_STEP)
            self.dg = ((g[1:dim + 1] - g[dim + 1:]) / (2 * FD_STEP)).T
        self.key = key
        self.tracker.offer(u, self.f, float(np.sum(np.maximum(self.g, 0.0))))
        self.budget.spend(cost * len(U), self.phase, err)
        if self.goal is not None and self.goal(self.f, self.g, err):
            raise _Stop("goal reached")

    def objective(self, u, grad):
        self._compute(u, grad.size > 0)
        if grad.size > 0:
            grad[:] = self.df
        return self.f

    def constraints(self, result, u, grad):
        self._compute(u, grad.size > 0)
        result[:] = self.g
        if grad.size > 0:
            grad[:] = self.dg

    def run(self, x0, local: str, maxeval: int, step: float, stops: list):
        import nlopt

        dim = self.problem.dim
        alg = nlopt.LD_SLSQP if local == "slsqp" else nlopt.LN_COBYLA
        opt = nlopt.opt(alg, dim)
        opt.set_lower_bounds(np.zeros(dim))
        opt.set_upper_bounds(np.ones(dim))
        opt.set_min_objective(self.objective)
        opt.add_inequality_mconstraint(self.constraints, np.zeros(self.m))
        opt.set_initial_step(np.full(dim, step))
        opt.set_maxeval(max(int(maxeval), 1))
        opt.set_maxtime(self.budget.time_left())
        opt.set_xtol_rel(1e-10)
        opt.set_ftol_abs(1e-16)
        try:
            opt.optimize(np.clip(np.asarray(x0, float), 0.0, 1.0))
            code = opt.last_optimize_result()
            stops.append({1: "success", 2: "stopval", 3: "ftol", 4: "xtol", 5: "maxeval",
                          6: "maxtime"}.get(code, str(code)))
        except _Stop as stop:
            stops.append(stop.reason)
        except nlopt.ForcedStop:
            stops.append("forced stop")
        except nlopt.RoundoffLimited:
            stops.append("roundoff-limited")
        except RuntimeError:               # nlopt's generic failure (e.g. SLSQP line search)
            stops.append("nlopt failure")


def solve(problem: DesignProblem, *, seed: int = 0, max_evaluations: int = 20000, progress=None,
          local: str = "slsqp", max_time_s: float = MAX_TIME_S) -> SolveResult:
    """Find normalised variables meeting the targets, then polish the tie-break."""
    if local not in LOCAL_METHODS:
        raise ValueError(f"local method {local!r}: choose from {', '.join(LOCAL_METHODS)}")
    rng = np.random.default_rng(seed)
    budget = _Budget(max_evaluations, progress, max_time_s)
    dim, tol = problem.dim, problem.tolerance_rel
    match_log = math.log1p(MATCH_FRACTION * tol)
    stops: list[str] = []
    # a local iteration costs ~6n+1 evaluations with gradients, 1 without
    per_iter = 2 * dim + 1 if local == "slsqp" else 1
    iters_per_start = 60 * dim if local == "slsqp" else 200 * dim

    def safe_constraints(ev):
        return ev.constraints + ROUNDING_SAFETY

    def max_err(ev):
        return np.max(np.abs(ev.rel_err), axis=-1)

    def match_batch(U):
        ev = problem.evaluate(U)
        return ev.objective, safe_constraints(ev), 1, float(max_err(ev)[0])

    def match_goal(f, g, err):
        return bool(np.all(g <= FEASIBILITY_TOL)) and math.log1p(err) <= match_log and math.log1p(-err) >= -match_log

    # -- screening: one vectorised batch
    n_screen = int(max(1, min(SCREEN_PER_DIM * dim, budget.left // 4)))
    U = rng.random((n_screen, dim))
    ev = problem.evaluate(U)
    viol = np.sum(np.maximum(safe_constraints(ev), 0.0), axis=-1)
    merit = np.where(np.isfinite(ev.objective), ev.objective, 1e30) + 10.0 * viol
    order = np.argsort(merit, kind="stable")
    starts = U[order[:N_STARTS]]
    budget.spend(n_screen, "screening", float(max_err(ev).min()))

    def matched_at(u) -> bool:
        e = problem.evaluate(u)
        return bool(np.all(safe_constraints(e) <= FEASIBILITY_TOL)
                    and np.max(np.abs(e.log_err)) <= match_log)

    # -- phase 1: match the targets
    best = Tracker()
    i0 = int(order[0])
    best.offer(U[i0], float(ev.objective[i0]), float(viol[i0]))
    matched = False
    starts_used = 0
    for x0 in starts:
        if budget.left <= 0:
            break
        starts_used += 1
        phase = _Phase(problem, match_batch, problem.n_constraints, best, budget, "match", match_goal)
        phase.run(x0, local, min(iters_per_start, budget.left // per_iter), INITIAL_STEP, stops)
        if matched_at(best.u):
            matched = True
            break

    result = SolveResult(u=best.u, matched=matched, evaluations=budget.used, starts_used=starts_used,
                         tie_break_before=None, tie_break_after=None, local=local, stops=stops)
    if not matched or budget.left <= 3 * per_iter:
        return result

    # -- phase 2: tie-break inside the tolerance band
    e = problem.evaluate(best.u)
    tie0 = float(problem.tie_break(e.theta_deg, e.t_mm, e.h_mm))

    def polish_run(u0, band, step):
        def tie_batch(U):
            ev = problem.evaluate(U)
            tb = problem.tie_break(ev.theta_deg, ev.t_mm, ev.h_mm)
            # two smooth constraints per output (|x| has no derivative where the error is 0)
            g = np.concatenate([safe_constraints(ev), ev.log_err - band, -ev.log_err - band], axis=-1)
            return tb, g, 3, float(max_err(ev)[0])

        tracker = Tracker()
        ev = problem.evaluate(u0)
        tracker.offer(u0, float(problem.tie_break(ev.theta_deg, ev.t_mm, ev.h_mm)), 0.0)
        if budget.left > 3 * per_iter:
            phase = _Phase(problem, tie_batch, problem.n_constraints + 4 * problem.n, tracker, budget,
                           "tie-break")
            phase.run(u0, local, min(iters_per_start, budget.left // (3 * per_iter)), step, stops)
        return tracker.u

    band = max(math.log1p(BAND_FRACTION * tol), float(np.max(np.abs(e.log_err))))
    polished = polish_run(best.u, band, 0.5 * INITIAL_STEP)

    # -- phase 3: pull the targets back to MATCH_FRACTION x tolerance, with a small step
    rematch = Tracker()
    e = problem.evaluate(polished)
    rematch.offer(polished, float(e.objective), 0.0)
    if not matched_at(polished) and budget.left > per_iter:
        phase = _Phase(problem, match_batch, problem.n_constraints, rematch, budget, "re-match", match_goal)
        phase.run(polished, local, min(iters_per_start, budget.left // per_iter), 0.02 * INITIAL_STEP, stops)
    final = rematch.u if matched_at(rematch.u) else best.u

    # -- phase 4: tie-break once more, inside the narrow band
    e = problem.evaluate(final)
    narrow = max(match_log, float(np.max(np.abs(e.log_err))))
    candidate = polish_run(final, narrow, 0.02 * INITIAL_STEP)
    if matched_at(candidate):
        final = candidate
    e = problem.evaluate(final)
    result.u = final
    result.evaluations = budget.used
    result.tie_break_before = tie0
    result.tie_break_after = float(problem.tie_break(e.theta_deg, e.t_mm, e.h_mm))
    return result
