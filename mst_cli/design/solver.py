"""The design search: a start built layer by layer, Gauss-Newton onto the targets, then the
preference among matching designs (nlopt), with a seeded multi-start behind it.

1. Layer-by-layer start (:mod:`mst_cli.design.seed`): given the gap, each layer's two targets
   pin it alone, so n lookups in one table of cells replace a blind search in 3n dimensions.
2. Match (phase 1): :func:`newton_match` pulls the 2n outputs onto their targets from there
   (Gauss-Newton, minimum-norm steps, violated constraints held); should it stall, an nlopt
   run goes on from its best point. Only if that fails too does the old multi-start search
   run: a seeded batch of random candidates through the vectorised problem in one call, the
   best by (match objective + penalty x constraint violation) as starts for nlopt runs,
   until one reaches every target within MATCH_FRACTION x tolerance.
3. Preference (phase 2): from that point, minimise the weighted preference of
   ``design.objective`` (:meth:`DesignProblem.preference`: height, force resolution, print
   robustness) with every target kept within BAND_FRACTION x tolerance as extra constraints.
4. Re-match (phase 3): the polish may sit anywhere in that band; Gauss-Newton (or, should it
   stall, a short nlopt match run with a small step) pulls every target back within
   MATCH_FRACTION x tolerance without leaving the robust region.
5. Final polish (phase 4): the preference again from there, with the band narrowed to
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
from collections import OrderedDict
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any, NamedTuple

import numpy as np

from mst_cli.design import seed
from mst_cli.design.problem import DesignProblem, Evaluation, robustness_of_shifts
from mst_cli.parallel import fork_map, workers

if TYPE_CHECKING:
    from collections.abc import Callable

    from numpy.typing import ArrayLike

INITIAL_STEP = 0.1  # fraction of every (normalised) variable's range
MATCH_FRACTION = 0.05  # phase 1 ends when every |error| <= this x tolerance
BAND_FRACTION = 0.5  # phase 2 keeps every |error| <= this x tolerance
ROUNDING_SAFETY = 1e-3  # constraint slack (nozzles / log units) so that the rounded
# design written to design.yaml still satisfies every rule
SCREEN_PER_DIM = 400  # screening batch size per design variable
N_STARTS = 24  # starting points kept from the screening
FD_STEP = 1e-6  # central-difference step in normalised variables
FEASIBILITY_TOL = 1e-9  # SLSQP lands on active constraints to ~1e-13; far inside the
# ROUNDING_SAFETY slack, so such points count as feasible
NEWTON_STEPS = 8  # Gauss-Newton steps of a match before SLSQP takes over
NEWTON_ACTIVE_PASSES = 4  # times a step's set of held constraints may grow
NEWTON_BACKTRACK = (1.0, 0.5, 0.25, 0.125)  # step fractions tried, in one batch
MAX_TIME_S = 120.0  # safety net only; normal runs stop on evaluation counts
LOCAL_METHODS = ("slsqp", "cobyla")


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


@dataclass
class SolveResult:
    u: np.ndarray  # best point (normalised)
    matched: bool  # phase 1 reached MATCH_FRACTION x tolerance
    evaluations: int  # candidate designs through the kernels (preference: 3 each)
    starts_used: int
    preference_before: float | None  # preference (design.objective) at the phase-1 point
    preference_after: float | None
    local: str = "slsqp"
    stops: list[str] = field(default_factory=list)  # how each nlopt run ended
    u_matched: np.ndarray | None = None  # the phase-1 point the preference started from


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


def _finite(a: np.ndarray, fill: float) -> np.ndarray:
    """``a`` with every non-finite entry ``fill``; ``a`` itself when all are finite (a finite
    sum says so in one reduction; one that overflows takes the full path, as a NaN does)."""
    if math.isfinite(np.add.reduce(a, axis=None)):
        return a
    return np.where(np.isfinite(a), a, fill)


def _point_of(score: np.ndarray, g: np.ndarray, dim: int) -> tuple:
    """(f, g, df, dg, violation) of a callback's batch: the nominal point's score and
    constraints (non-finite ones replaced), their central differences when ``dim`` (a stencil
    of 2 dim + 1 points), and the point's constraint violation (np.sum's reduction without its
    wrapper: a 1-d sum, the same bits)."""
    score, g = _finite(score, 1e30), _finite(g, 1e6)
    df = dg = None
    if dim:
        df = (score[1 : dim + 1] - score[dim + 1 :]) / (2 * FD_STEP)
        dg = ((g[1 : dim + 1] - g[dim + 1 :]) / (2 * FD_STEP)).T
    return float(score[0]), g[0], df, dg, float(np.add.reduce(np.maximum(g[0], 0.0), axis=None))


class _PreferenceBatch:
    """The preference phases' batch function: (preference, g, cost per point, worst error) of
    points U, g the constraints with the rounding slack, then every log error within +- band
    (two smooth constraints per output: |x| has no derivative where the error is 0)."""

    cost = 3  # kernel stacks per point: the nominal walls and both print shifts

    def __init__(self, problem, weights, band: float):
        self.problem, self.weights, self.band = problem, weights, band

    def __call__(self, U):
        ev, terms = self.problem.evaluate_terms(U)
        g = preference_constraints(_safe_constraints(ev), ev.log_err, self.band)
        return self.problem.preference(ev, self.weights, terms), g, self.cost, float(_max_err(ev)[0])


def preference_constraints(safe: np.ndarray, log_err: np.ndarray, band) -> np.ndarray:
    """The preference phases' constraints: ``safe`` (with the rounding slack), then
    log_err - band and -log_err - band (``band`` a number, or one per row as (k, 1))."""
    return np.concatenate([safe, log_err - band, -log_err - band], axis=-1)


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
        # a batched run's preference callbacks: one round computes every run's (_point_rows)
        self.shared = getattr(problem, "preference_point", None) if isinstance(batch, _PreferenceBatch) else None

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
        if self.shared is not None:
            self.f, self.g, df, dg, violation, err = self.shared(U, self.batch.weights, self.batch.band)
            cost = _PreferenceBatch.cost
        else:
            score, g, cost, err = self.batch(U)
            self.f, self.g, df, dg, violation = _point_of(score, g, dim if want_grad else 0)
        if want_grad:
            self.df, self.dg = df, dg
        self.key = key
        self.tracker.offer(u, self.f, violation)
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
        import nlopt  # deferred: the optimiser loads when a design is searched, not at start-up

        NLOPT_FAILURES = _nlopt_failures()
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
            stops.append(
                {1: "success", 2: "stopval", 3: "ftol", 4: "xtol", 5: "maxeval", 6: "maxtime"}.get(code, str(code))
            )
        except _Stop as stop:
            stops.append(stop.reason)
        except nlopt.ForcedStop:
            stops.append("forced stop")
        except nlopt.RoundoffLimited:
            stops.append("roundoff-limited")
        except (RuntimeError, *NLOPT_FAILURES):  # nlopt's generic failure (SLSQP line search)
            stops.append("nlopt failure")


def _per_iter(problem, local):
    """Evaluations one local iteration costs: u and its 2 dim neighbours with gradients."""
    return 2 * problem.dim + 1 if local == "slsqp" else 1


def _iters_per_start(problem, local):
    return 60 * problem.dim if local == "slsqp" else 200 * problem.dim


def _safe_constraints(ev):
    if isinstance(ev, _Rows):  # the batched polish's rows: computed once per round
        return ev.safe_constraints
    return ev.constraints + ROUNDING_SAFETY


def _max_err(ev):
    if isinstance(ev, _Rows):
        return ev.max_err
    return np.max(np.abs(ev.rel_err), axis=-1)


class _Matcher:
    """Phase-1 pieces shared by the first match and the re-match."""

    def __init__(self, problem: DesignProblem):
        self.problem = problem
        self.match_log = math.log1p(MATCH_FRACTION * problem.tolerance_rel)

    def batch(self, U):
        ev = self.problem.evaluate(U)
        return ev.objective, _safe_constraints(ev), 1, float(_max_err(ev)[0])

    def goal(self, f, g, err):
        return (
            bool(np.all(g <= FEASIBILITY_TOL))
            and math.log1p(err) <= self.match_log
            and math.log1p(-err) >= -self.match_log
        )

    def matched_at(self, u) -> bool:
        return self.matched(self.problem.evaluate(u))

    def matched(self, e) -> bool:
        """Every constraint (with the rounding slack) and every target within MATCH_FRACTION x
        tolerance, of one evaluated point."""
        return bool(np.all(_safe_constraints(e) <= FEASIBILITY_TOL) and np.max(np.abs(e.log_err)) <= self.match_log)


def newton_match(problem: DesignProblem, u0: np.ndarray, tracker: Tracker, budget: _Budget, phase: str) -> bool:
    """Pull the 2n outputs onto their targets by Gauss-Newton; True when the match goal is met.

    Matching is an underdetermined least-squares problem: 2n log errors in 3n unknowns, zero
    at the solution. A quasi-Newton method (SLSQP) has to learn its curvature over dozens of
    iterations, 3n-dimensional ones; Gauss-Newton has it from one Jacobian (the same batched
    central differences SLSQP uses) and converges in a handful of steps from a few per cent
    away. Each step is the minimum-norm solution of J du = -r, so the spare freedom per layer
    stays where it was (the preference phases chose it). Constraints the linearised step
    would break, and bounds it would cross, are held at zero as extra equations and the step
    is solved again; a backtracking search on the screening's merit keeps it from overshooting.
    Every point evaluated is offered to ``tracker``. False: the caller's SLSQP goes on from
    ``tracker.u``.
    """
    m = _Matcher(problem)
    dim = problem.dim
    u = np.clip(np.asarray(u0, float), 0.0, 1.0)
    eye = np.eye(dim) * FD_STEP
    for _ in range(NEWTON_STEPS):
        if budget.left < 2 * dim + 1 + len(NEWTON_BACKTRACK):
            return False
        ev = problem.evaluate(np.concatenate([u[None], u + eye, u - eye]))
        r, g = ev.log_err, _safe_constraints(ev)
        merit = ev.merit(ROUNDING_SAFETY)
        err = float(_max_err(ev)[0])
        budget.spend(2 * dim + 1, phase, err)
        tracker.offer(u, float(ev.objective[0]), float(np.sum(np.maximum(g[0], 0.0))))
        if m.goal(float(ev.objective[0]), g[0], err):
            return True
        if not (np.all(np.isfinite(r)) and np.all(np.isfinite(g))):
            return False
        J = ((r[1 : dim + 1] - r[dim + 1 :]) / (2 * FD_STEP)).T  # (2n, dim)
        G = ((g[1 : dim + 1] - g[dim + 1 :]) / (2 * FD_STEP)).T  # (m, dim)
        rows, rhs = [J], [-r[0]]
        held_g = np.zeros(len(g[0]), bool)
        held_u = np.zeros(dim, bool)
        for _ in range(NEWTON_ACTIVE_PASSES):
            du = np.linalg.lstsq(np.concatenate(rows), np.concatenate(rhs), rcond=None)[0]
            new_g = (g[0] + G @ du > 0.0) & ~held_g
            new_u = ((u + du < 0.0) | (u + du > 1.0)) & ~held_u
            if not (new_g.any() or new_u.any()):
                break
            rows += [G[new_g], np.eye(dim)[new_u]]
            rhs += [-g[0][new_g], np.where(u + du < 0.0, -u, 1.0 - u)[new_u]]
            held_g |= new_g
            held_u |= new_u
        trials = np.clip(u + np.asarray(NEWTON_BACKTRACK)[:, None] * du, 0.0, 1.0)
        et = problem.evaluate(trials)
        budget.spend(len(trials), phase, float(_max_err(et).min()))
        better = np.flatnonzero(et.merit(ROUNDING_SAFETY) < merit[0])
        if len(better) == 0:
            return False
        u = trials[better[0]]
    return False


def _match(problem, rng, budget, local, stops):
    """Screening and phase 1: (best u, matched, starts used)."""
    dim = problem.dim
    per_iter, iters = _per_iter(problem, local), _iters_per_start(problem, local)
    m = _Matcher(problem)
    best = Tracker()
    starts_used = 0
    # -- the layer-by-layer start (mst_cli.design.seed): n searches in 3 dimensions in one
    # table of cells; a cell is one layer law, 1/n of a candidate (at most a quarter of the budget)
    grid = seed.grid_within(problem.n * budget.left / 4)
    u0 = None
    if math.prod(grid) <= problem.n * budget.left / 4:
        table = seed.CellTable(problem, ROUNDING_SAFETY, grid)
        u0, stacks = seed.seed_start(problem, ROUNDING_SAFETY, table)
        budget.spend(math.ceil(table.cells / problem.n) + stacks, "seed", math.inf)
    if u0 is not None and budget.left > 0:
        starts_used += 1
        if newton_match(problem, u0, best, budget, "match"):
            stops.append("newton: goal reached")
            return best.u, True, starts_used
        u0 = best.u
        phase = _Phase(problem, m.batch, problem.n_constraints, best, budget, "match", m.goal)
        phase.run(u0, local, min(iters, budget.left // per_iter), INITIAL_STEP, stops)
        if m.matched_at(best.u):
            return best.u, True, starts_used
    # -- screening: one vectorised batch
    n_screen = int(max(1, min(SCREEN_PER_DIM * dim, budget.left // 4)))
    U = rng.random((n_screen, dim))
    ev = problem.evaluate(U)
    viol = np.sum(np.maximum(_safe_constraints(ev), 0.0), axis=-1)
    order = np.argsort(ev.merit(ROUNDING_SAFETY), kind="stable")
    starts = U[order[:N_STARTS]]
    budget.spend(n_screen, "screening", float(_max_err(ev).min()))

    i0 = int(order[0])
    best.offer(U[i0], float(ev.objective[i0]), float(viol[i0]))
    for x0 in starts:
        if budget.left <= 0:
            break
        starts_used += 1
        phase = _Phase(problem, m.batch, problem.n_constraints, best, budget, "match", m.goal)
        phase.run(x0, local, min(iters, budget.left // per_iter), INITIAL_STEP, stops)
        if m.matched_at(best.u):
            return best.u, True, starts_used
    return best.u, False, starts_used


def prefer(
    problem: DesignProblem,
    u_matched: np.ndarray,
    budget: _Budget,
    local: str,
    stops: list,
    weights: ArrayLike | None = None,
) -> tuple[np.ndarray, float, float]:
    """Phases 2-4 from a matched point: the design that meets the targets and minimises the
    preference (:meth:`DesignProblem.preference` with ``weights``, default design.objective).
    Returns (u, preference before, preference after)."""
    per_iter, iters = _per_iter(problem, local), _iters_per_start(problem, local)
    m = _Matcher(problem)
    tol = problem.tolerance_rel

    def pref_at(u):
        """(evaluation, preference) of one point: one kernel call, the print-shifted stacks in it."""
        ev, terms = problem.evaluate_terms(u)
        return ev, float(problem.preference(ev, weights, terms))

    def polish_run(u0, pref0, band, step):
        pref_batch = _PreferenceBatch(problem, weights, band)
        tracker = Tracker()
        tracker.offer(u0, pref0, 0.0)
        if budget.left > 3 * per_iter:
            phase = _Phase(problem, pref_batch, problem.n_constraints + 4 * problem.n, tracker, budget, "preference")
            phase.run(u0, local, min(iters, budget.left // (3 * per_iter)), step, stops)
        return tracker.u

    e, before = pref_at(u_matched)
    band = max(math.log1p(BAND_FRACTION * tol), float(np.max(np.abs(e.log_err))))
    polished = polish_run(u_matched, before, band, 0.5 * INITIAL_STEP)

    # -- phase 3: pull the targets back to MATCH_FRACTION x tolerance, with a small step
    rematch = Tracker()
    e = problem.evaluate(polished)
    rematch.offer(polished, float(e.objective), 0.0)
    polished_matched = m.matched(e)
    newton = not polished_matched and newton_match(problem, polished, rematch, budget, "re-match")
    if newton:
        stops.append("newton: goal reached")
    elif not polished_matched and budget.left > per_iter:
        phase = _Phase(problem, m.batch, problem.n_constraints, rematch, budget, "re-match", m.goal)
        phase.run(polished, local, min(iters, budget.left // per_iter), 0.02 * INITIAL_STEP, stops)
    final = rematch.u if rematch.u is not None and m.matched_at(rematch.u) else u_matched

    # -- phase 4: the preference once more, inside the narrow band
    e, after = pref_at(final)
    narrow = max(m.match_log, float(np.max(np.abs(e.log_err))))
    candidate = polish_run(final, after, narrow, 0.02 * INITIAL_STEP)
    if m.matched_at(candidate):
        final = candidate
        after = pref_at(final)[1]
    return final, before, after


def _matched(problem: DesignProblem, seed: int, max_evaluations: int, progress, local: str, max_time_s: float):
    """Screening and phase 1 under a fresh budget: (SolveResult of the match, that budget)."""
    if local not in LOCAL_METHODS:
        raise ValueError(f"local method {local!r}: choose from {', '.join(LOCAL_METHODS)}")
    budget = _Budget(max_evaluations, progress, max_time_s)
    stops: list[str] = []
    u, matched, starts_used = _match(problem, np.random.default_rng(seed), budget, local, stops)
    return SolveResult(
        u=u,
        matched=matched,
        evaluations=budget.used,
        starts_used=starts_used,
        preference_before=None,
        preference_after=None,
        local=local,
        stops=stops,
    ), budget


def solve(
    problem: DesignProblem,
    *,
    seed: int = 0,
    max_evaluations: int = 20000,
    progress: Callable | None = None,
    local: str = "slsqp",
    max_time_s: float = MAX_TIME_S,
    weights: ArrayLike | None = None,
) -> SolveResult:
    """Find normalised variables meeting the targets, then minimise the preference (one budget)."""
    result, budget = _matched(problem, seed, max_evaluations, progress, local, max_time_s)
    if result.matched:
        result.u_matched = result.u
    if not result.matched or budget.left <= 3 * _per_iter(problem, local):
        return result
    result.u, result.preference_before, result.preference_after = prefer(
        problem, result.u, budget, local, result.stops, weights
    )
    result.evaluations = budget.used
    return result


def pareto_weights(count: int) -> np.ndarray:
    """``count`` weight vectors over OBJECTIVE_TERMS spread over the simplex (deterministic):
    the three corners first, then a triangular lattice, refined until there are enough."""
    corners = [np.eye(3)[i] for i in range(3)]
    out = list(corners)
    seen = {tuple(np.round(w, 12)) for w in out}
    level = 2
    while len(out) < count:
        for i in range(level + 1):
            for j in range(level + 1 - i):
                w = np.array([i, j, level - i - j], dtype=float) / level
                key = tuple(np.round(w, 12))
                if key not in seen:
                    seen.add(key)
                    out.append(w)
        level *= 2
    return np.array(out[:count])


# --------------------------------------------------------------------------- many weightings at once
RECENT_EVALUATIONS = 64  # per run: the points SLSQP asks for again (a stalled line search)


class _SharedEvaluations:
    """Local runs of several weightings in lockstep, their evaluations batched into one kernel call.

    nlopt drives each run through callbacks, so runs cannot hand over a batch themselves: each
    runs in a greenlet of its own against a :class:`_BatchedProblem`, whose ``evaluate`` hands
    its points to the calling greenlet and is resumed with its rows. When every live run has
    handed over, the caller evaluates all their points in one call (with the preference terms,
    the print-shifted stacks included) and resumes each run, in a fixed order, with its rows.
    The runs take turns in one thread (a switch costs a microsecond, where a thread's wake-up
    costs tens), so the result depends on the inputs only.
    """

    def __init__(self, problem: DesignProblem):
        self.problem = problem
        self.caller: Any = None  # the greenlet that serves the batch

    def ask(self, job: int, u):
        """Evaluation and preference terms of ``u`` (one point (dim,) or a batch (k, dim)),
        each row's bits as :meth:`DesignProblem.evaluate` alone gives them; for a
        :class:`_PointAsk`, what :func:`_point_rows` gives."""
        return self.caller.switch(u)

    def _serve(self, pending: dict[int, Any]) -> dict[int, tuple]:
        jobs = sorted(pending)
        problem = self.problem
        asked = {j: pending[j].U if isinstance(pending[j], _PointAsk) else pending[j] for j in jobs}
        U = np.concatenate([asked[j].reshape(-1, problem.dim) for j in jobs])
        ev, shifts = problem.evaluate_with_shifts(U)
        # ln height and ln force resolution are elementwise or row-wise: one call for the batch
        terms = problem.objective_terms(ev, np.zeros(len(U)))
        rows_of: dict[int, int | slice] = {}
        start = 0
        for j in jobs:
            flat = asked[j].ndim == 1
            rows_of[j] = start if flat else slice(start, start + len(asked[j]))
            start += 1 if flat else len(asked[j])
        terms[:, -1] = _robustness_by_job(shifts, rows_of)
        batch = _BatchRows(ev)
        points = {j: (rows_of.pop(j), pending[j]) for j in jobs if isinstance(pending[j], _PointAsk)}
        out = {j: (_Rows(batch, rows), terms[rows]) for j, rows in rows_of.items()}
        if points:
            out.update(_point_rows(problem, batch, terms, points))
        return out

    def run(self, jobs: list[Callable[[DesignProblem], object]]) -> list:
        """Each job called with its own batched view of the problem; their results in order.
        A job's Exception is raised once every other job has finished; anything else (an
        interrupt) at once."""
        from greenlet import getcurrent, greenlet  # deferred: only the batched polish of many weightings runs them

        out: list = [None] * len(jobs)
        errors: list[Exception] = []
        self.caller = getcurrent()

        def body(i, job):
            try:
                out[i] = job(_BatchedProblem(self, i))
            except Exception as exc:  # handed to the caller below
                errors.append(exc)
            return _DONE

        runs = [greenlet(body) for _ in jobs]
        pending: dict[int, np.ndarray] = {}
        for i, (run, job) in enumerate(zip(runs, jobs)):
            asked = run.switch(i, job)
            if asked is not _DONE:
                pending[i] = asked
        while pending:
            results = self._serve(pending)
            pending = {}
            for j in sorted(results):
                asked = runs[j].switch(results[j])
                if asked is not _DONE:
                    pending[j] = asked
        if errors:
            raise errors[0]
        return out


_DONE = object()  # what a finished run hands back instead of points


class _PointAsk(NamedTuple):
    """A preference phase's request: the callback's points U (its point, or the point and its
    central-difference stencil), the run's weights and its band."""

    U: np.ndarray
    weights: Any
    band: float


def _point_rows(problem: DesignProblem, batch: _BatchRows, terms: np.ndarray, asks: dict) -> dict[int, tuple]:
    """(f, g, df, dg, violation, worst error) of every preference request of a round, ``asks``
    {job: (its rows, its _PointAsk)}: the constraints, the non-finite guard, the central
    differences and the violations computed once for all of them (elementwise and row-wise),
    each run's numbers to the bit those of :class:`_PreferenceBatch` and :func:`_point_of` on
    its own rows."""
    starts = np.array([rows.start for rows, _ in asks.values()])
    sizes = np.array([rows.stop - rows.start for rows, _ in asks.values()])
    index = _block_rows(starts, sizes)
    bands = np.repeat([a.band for _, a in asks.values()], sizes)[:, None]
    g = _finite(preference_constraints(batch.safe_constraints[index], batch.ev.log_err[index], bands), 1e6)
    # the preference run by run: a matrix product's bits depend on its shape
    score = _finite(np.concatenate([problem.weighted_terms(terms[r], a.weights) for r, a in asks.values()]), 1e30)
    first = np.cumsum(sizes) - sizes
    violation = np.add.reduce(np.maximum(g[first], 0.0), axis=-1)  # row by row: a 1-d sum's bits
    dim = problem.dim
    with_grad = sizes > 1  # u and its stencil of 2 dim points
    plus = _block_rows(first[with_grad] + 1, np.full(int(with_grad.sum()), dim))
    df = ((score[plus] - score[plus + dim]) / (2 * FD_STEP)).reshape(-1, dim)
    dg = ((g[plus] - g[plus + dim]) / (2 * FD_STEP)).reshape(-1, dim, g.shape[-1])
    grad_of = np.cumsum(with_grad) - 1
    rows = zip(
        asks, score[first].tolist(), first, violation.tolist(), batch.max_err[starts].tolist(), with_grad, grad_of
    )
    return {
        j: (f, g[o], df[c] if grad else None, dg[c].T if grad else None, v, err) for j, f, o, v, err, grad, c in rows
    }


def _block_rows(starts: np.ndarray, sizes: np.ndarray) -> np.ndarray:
    """The row indices of consecutive blocks (start, size), one after the other."""
    offsets = np.cumsum(sizes) - sizes  # where each block begins in the result
    return np.arange(int(np.add.reduce(sizes))) + np.repeat(starts - offsets, sizes)


def _robustness_by_job(shifts: np.ndarray, rows_of: dict[int, int | slice]) -> np.ndarray:
    """Print robustness of every row of ``shifts`` (2, N, 2n), each job's rows reduced as a call
    of its own would reduce them: a reduction over two axes sums in an order that depends on
    the array's shape, so the jobs whose requests have one shape (one point, or k points) are
    stacked along a new leading axis, which leaves every row's order of summation as it was."""
    out = np.empty(shifts.shape[1])
    points = [rows for rows in rows_of.values() if isinstance(rows, int)]
    blocks: dict[int, list[int]] = {}
    for rows in rows_of.values():
        if isinstance(rows, slice):
            blocks.setdefault(rows.stop - rows.start, []).append(rows.start)
    groups = [(np.array(points, dtype=np.intp), 0)] if points else []
    groups += [(_block_rows(np.array(starts), np.full(len(starts), k)), k) for k, starts in blocks.items()]
    for index, k in groups:
        d = shifts[:, index].reshape((2, -1, k, shifts.shape[-1]) if k else (2, -1, shifts.shape[-1]))
        d = np.ascontiguousarray(np.moveaxis(d, 1, 0))  # (jobs, 2, [k,] 2n): each job's own layout
        out[index] = robustness_of_shifts(d, first=1).reshape(-1)
    return out


class _BatchRows:
    """One round's evaluation and what every run derives from it, computed once for the batch
    (elementwise and row-wise: a row gets the bits a call of its own would give)."""

    def __init__(self, ev: Evaluation):
        self.ev = ev
        self.safe_constraints = _safe_constraints(ev)
        self.max_err = _max_err(ev)


class _Rows(Evaluation):
    """A run's rows of a :class:`_BatchRows`: the :class:`Evaluation` of its own points, each
    field sliced out when it is first read (a run reads a few of them)."""

    def __init__(self, batch: _BatchRows, rows: int | slice):  # the fields come lazily
        self._batch, self._rows = batch, rows

    def __getattr__(self, name: str):
        if name.startswith("_"):
            raise AttributeError(name)
        value = getattr(self._batch.ev, name)[self._rows]
        setattr(self, name, value)
        return value

    @property
    def safe_constraints(self) -> np.ndarray:
        return self._batch.safe_constraints[self._rows]

    @property
    def max_err(self) -> np.ndarray:
        return self._batch.max_err[self._rows]


class _BatchedProblem:
    """A :class:`DesignProblem` whose evaluations go through :class:`_SharedEvaluations`."""

    def __init__(self, shared: _SharedEvaluations, job: int):
        self._shared, self._job = shared, job
        self._recent: OrderedDict = OrderedDict()

    def __getattr__(self, name):
        return getattr(self._shared.problem, name)

    def evaluate_terms(self, u) -> tuple[Evaluation, np.ndarray]:
        """The shared round's rows for ``u``; a point among the run's last RECENT_EVALUATIONS
        requests gets its rows again without a round (the same bits: the kernels are exact
        functions of the point)."""
        u = np.asarray(u, dtype=float)
        return self._recall((u.shape, u.tobytes()), u)

    def preference_point(self, U: np.ndarray, weights, band: float) -> tuple:
        """What :class:`_Phase` needs of a preference callback's points ``U``, from the shared
        round (:func:`_point_rows`), or again without one when recently asked."""
        return self._recall(("point", U.shape, U.tobytes(), band), _PointAsk(U, weights, band))

    def _recall(self, key: tuple, request):
        got = self._recent.get(key)
        if got is None:
            got = self._shared.ask(self._job, request)
            self._recent[key] = got
            if len(self._recent) > RECENT_EVALUATIONS:
                self._recent.popitem(last=False)
        else:
            self._recent.move_to_end(key)
        return got

    def evaluate(self, u) -> Evaluation:
        return self.evaluate_terms(u)[0]


def prefer_many(
    problem: DesignProblem,
    starts: list[np.ndarray],
    weightings: list[ArrayLike],
    *,
    max_evaluations: int,
    local: str = "slsqp",
    max_time_s: float = MAX_TIME_S,
    stops: list | None = None,
) -> list[tuple[np.ndarray, int]]:
    """Phases 2-4 (:func:`prefer`) for every (start, weighting) pair, each with a fresh
    ``max_evaluations`` budget, their kernel calls batched across the weightings.
    Returns (u, evaluations) per pair, in order.

    With more than one core the pairs are dealt round-robin to forked workers
    (:func:`mst_cli.parallel.fork_map`), each batching its share: a pair's polish is the same
    to the bit in any batch (:class:`_SharedEvaluations`), so the answer is too."""
    n = len(starts)
    n_hands = max(1, min(n, workers()))
    hands = [list(range(i, n, n_hands)) for i in range(n_hands)]

    def polish(hand: list[int]) -> tuple[list, list[list[str]]]:
        return _prefer_hand(problem, starts, weightings, hand, max_evaluations, local, max_time_s)

    dealt = fork_map(polish, hands)
    if dealt is None:  # one worker, or no fork here: all of them in this process
        hands = [list(range(n))]
        dealt = [polish(hands[0])]
    out: list = [None] * n
    run_stops: list[list[str]] = [[] for _ in range(n)]
    for hand, (results, hand_stops) in zip(hands, dealt):
        for k, result, s in zip(hand, results, hand_stops):
            out[k], run_stops[k] = result, s
    if stops is not None:
        for s in run_stops:
            stops.extend(s)
    return out


def _prefer_hand(
    problem: DesignProblem,
    starts: list[np.ndarray],
    weightings: list[ArrayLike],
    hand: list[int],
    max_evaluations: int,
    local: str,
    max_time_s: float,
) -> tuple[list, list[list[str]]]:
    """:func:`prefer_many` on the pairs numbered ``hand``, batched: ([(u, evaluations)], [stops])."""
    run_stops: list[list[str]] = [[] for _ in hand]

    def job(k, i):
        def run(batched):
            budget = _Budget(max_evaluations, None, max_time_s)
            u, _, _ = prefer(batched, starts[k], budget, local, run_stops[i], weightings[k])
            return u, budget.used

        return run

    return _SharedEvaluations(problem).run([job(k, i) for i, k in enumerate(hand)]), run_stops
