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

Every nlopt run goes through the phase runner (:mod:`mst_cli.design.phase`: bounds, callbacks,
stopping rules, the best point kept however a run ends). The result depends only on the spec
and the seed, so the same seed gives the same design. Many weightings' polishes at once, their
kernel calls batched, are :mod:`mst_cli.design.batching`'s.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import TYPE_CHECKING

import numpy as np

from mst_cli.design import seed
from mst_cli.design.phase import (
    FD_STEP,
    FEASIBILITY_TOL,
    LOCAL_METHODS,
    MAX_TIME_S,
    STALL_CALLS,
    Batch,
    Budget,
    LocalRun,
    Phase,
    PointValues,
    Tracker,
)
from mst_cli.design.problem import ROUNDING_SAFETY, DesignProblem

if TYPE_CHECKING:
    from collections.abc import Callable

    from numpy.typing import ArrayLike

    # a preference callback's values from (U, weights, band): see _PreferenceBatch
    PreferencePoints = Callable[[np.ndarray, ArrayLike | None, float], PointValues]

INITIAL_STEP = 0.1  # fraction of every (normalised) variable's range
MATCH_FRACTION = 0.05  # phase 1 ends when every |error| <= this x tolerance
BAND_FRACTION = 0.5  # phase 2 keeps every |error| <= this x tolerance
SCREEN_PER_DIM = 400  # screening batch size per design variable
N_STARTS = 24  # starting points kept from the screening
NEWTON_STEPS = 8  # Gauss-Newton steps of a match before SLSQP takes over
NEWTON_ACTIVE_PASSES = 4  # times a step's set of held constraints may grow
NEWTON_BACKTRACK = (1.0, 0.5, 0.25, 0.125)  # step fractions tried, in one batch


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


@dataclass
class Search:
    """What the phases of one search share: its budget, the local method, and how each nlopt
    run ended (``stops``, in order)."""

    budget: Budget
    local: str = "slsqp"
    stops: list[str] = field(default_factory=list)

    def run(self, phase: Phase, x0, maxeval: int, step: float) -> None:
        """One local run of ``phase`` from ``x0`` with this search's method."""
        self.stops.append(phase.run(x0, LocalRun(self.local, maxeval, step)))


class _PreferenceBatch(Batch):
    """The preference phases' batch function: (preference, g, worst error) of points U, g the
    constraints with the rounding slack, then every log error within +- band (two smooth
    constraints per output: |x| has no derivative where the error is 0).

    ``points``, when given, computes a callback's :class:`~mst_cli.design.phase.PointValues`
    instead, from (U, weights, band): the batching engine's shared rounds
    (:mod:`mst_cli.design.batching`), the same bits."""

    cost = 3  # kernel stacks per point: the nominal walls and both print shifts

    def __init__(self, problem, weights, band: float, points: PreferencePoints | None = None):
        self.problem, self.weights, self.band, self.points = problem, weights, band, points
        self.m = problem.n_constraints + 4 * problem.n

    def __call__(self, U):
        ev, terms = self.problem.evaluate_terms(U)
        g = preference_constraints(ev.safe_constraints, ev.log_err, self.band)
        return self.problem.preference(ev, self.weights, terms), g, float(ev.max_err[0])

    def point(self, U: np.ndarray, dim: int) -> PointValues:
        if self.points is not None:
            return self.points(U, self.weights, self.band)
        return super().point(U, dim)


def preference_constraints(safe: np.ndarray, log_err: np.ndarray, band) -> np.ndarray:
    """The preference phases' constraints: ``safe`` (with the rounding slack), then
    log_err - band and -log_err - band (``band`` a number, or one per row as (k, 1))."""
    return np.concatenate([safe, log_err - band, -log_err - band], axis=-1)


def _per_iter(problem, local):
    """Evaluations one local iteration costs: u and its 2 dim neighbours with gradients."""
    return 2 * problem.dim + 1 if local == "slsqp" else 1


def _iters_per_start(problem, local):
    return 60 * problem.dim if local == "slsqp" else 200 * problem.dim


class _Matcher(Batch):
    """Phase-1 pieces shared by the first match and the re-match: the batch function
    (match objective, constraints with the rounding slack) and the goal."""

    def __init__(self, problem: DesignProblem):
        self.problem = problem
        self.m = problem.n_constraints
        self.match_log = math.log1p(MATCH_FRACTION * problem.tolerance_rel)

    def __call__(self, U):
        ev = self.problem.evaluate(U)
        return ev.objective, ev.safe_constraints, float(ev.max_err[0])

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
        return bool(np.all(e.safe_constraints <= FEASIBILITY_TOL) and np.max(np.abs(e.log_err)) <= self.match_log)


def newton_match(problem: DesignProblem, u0: np.ndarray, tracker: Tracker, budget: Budget, phase: str) -> bool:
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
        r, g = ev.log_err, ev.safe_constraints
        merit = ev.merit(ROUNDING_SAFETY)
        err = float(ev.max_err[0])
        budget.spend(2 * dim + 1, phase, err)
        tracker.offer(u, float(ev.objective[0]), float(np.sum(np.maximum(g[0], 0.0))))
        if m.goal(float(ev.objective[0]), g[0], err):
            return True
        if not (np.all(np.isfinite(r)) and np.all(np.isfinite(g))):
            return False
        J = ((r[1 : dim + 1] - r[dim + 1 :]) / (2 * FD_STEP)).T  # (2n, dim)
        G = ((g[1 : dim + 1] - g[dim + 1 :]) / (2 * FD_STEP)).T  # (m, dim)
        du, held = _newton_step(u, r[0], J, g[0], G, g[0])
        step, full = _backtrack(problem, u, du, merit[0], budget, phase)
        if step is None and held.any() and budget.left >= len(NEWTON_BACKTRACK):
            # second-order correction: a held constraint the full step broke by its curvature is
            # aimed below zero by what the step overshot, the Jacobians kept (one more batch)
            overshoot = np.where(held, np.maximum(full, 0.0), 0.0)
            du, _ = _newton_step(u, r[0], J, g[0], G, g[0] + overshoot)
            step, _ = _backtrack(problem, u, du, merit[0], budget, phase)
        if step is None:
            return False
        u = step
    return False


def _backtrack(problem, u, du, merit0: float, budget: Budget, phase: str) -> tuple[np.ndarray | None, np.ndarray]:
    """(the longest of the NEWTON_BACKTRACK fractions of ``du`` from ``u`` whose merit is below
    ``merit0``, or None; the full step's constraints), the fractions evaluated in one batch."""
    trials = np.clip(u + np.asarray(NEWTON_BACKTRACK)[:, None] * du, 0.0, 1.0)
    et = problem.evaluate(trials)
    budget.spend(len(trials), phase, float(et.max_err.min()))
    better = np.flatnonzero(et.merit(ROUNDING_SAFETY) < merit0)
    return (trials[better[0]] if len(better) else None), et.safe_constraints[0]


def _newton_step(u, r0, J, g0, G, g_aim) -> tuple[np.ndarray, np.ndarray]:
    """(du, the constraints held) of one Gauss-Newton step from ``u``: the minimum-norm du of
    J du = -r0, with every constraint the linearised step would break (g0 + G du > 0) held at
    g_aim + G du = 0 and every bound it would cross held on the bound, solved again until
    nothing new breaks (NEWTON_ACTIVE_PASSES at most)."""
    dim = len(u)
    rows, rhs = [J], [-r0]
    held_g = np.zeros(len(g0), bool)
    held_u = np.zeros(dim, bool)
    du = np.zeros(dim)
    for _ in range(NEWTON_ACTIVE_PASSES):
        du = np.linalg.lstsq(np.concatenate(rows), np.concatenate(rhs), rcond=None)[0]
        new_g = ((g0 + G @ du > 0.0) | (g_aim > g0)) & ~held_g
        new_u = ((u + du < 0.0) | (u + du > 1.0)) & ~held_u
        if not (new_g.any() or new_u.any()):
            break
        rows += [G[new_g], np.eye(dim)[new_u]]
        rhs += [-g_aim[new_g], np.where(u + du < 0.0, -u, 1.0 - u)[new_u]]
        held_g |= new_g
        held_u |= new_u
    return du, held_g


def _match(problem, rng_seed: int, search: Search):
    """Screening and phase 1: (best u, matched, starts used). The screening's generator is
    seeded only when the screening runs: the layer-by-layer start and its match rarely need
    it, and numpy.random's import is about 10 ms of a quick design's start-up."""
    dim, budget = problem.dim, search.budget
    per_iter, iters = _per_iter(problem, search.local), _iters_per_start(problem, search.local)
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
            search.stops.append("newton: goal reached")
            return best.u, True, starts_used
        u0 = best.u
        search.run(Phase(m, best, budget, "match", m.goal), u0, min(iters, budget.left // per_iter), INITIAL_STEP)
        if m.matched_at(best.u):
            return best.u, True, starts_used
    # -- screening: one vectorised batch
    n_screen = int(max(1, min(SCREEN_PER_DIM * dim, budget.left // 4)))
    U = np.random.default_rng(rng_seed).random((n_screen, dim))
    ev = problem.evaluate(U)
    viol = np.sum(np.maximum(ev.safe_constraints, 0.0), axis=-1)
    order = np.argsort(ev.merit(ROUNDING_SAFETY), kind="stable")
    starts = U[order[:N_STARTS]]
    budget.spend(n_screen, "screening", float(ev.max_err.min()))

    i0 = int(order[0])
    best.offer(U[i0], float(ev.objective[i0]), float(viol[i0]))
    for x0 in starts:
        if budget.left <= 0:
            break
        starts_used += 1
        search.run(Phase(m, best, budget, "match", m.goal), x0, min(iters, budget.left // per_iter), INITIAL_STEP)
        if m.matched_at(best.u):
            return best.u, True, starts_used
    return best.u, False, starts_used


def prefer(
    problem: DesignProblem,
    u_matched: np.ndarray,
    search: Search,
    weights: ArrayLike | None = None,
    points: PreferencePoints | None = None,
) -> tuple[np.ndarray, float, float]:
    """Phases 2-4 from a matched point: the design that meets the targets and minimises the
    preference (:meth:`DesignProblem.preference` with ``weights``, default design.objective).
    ``points``: how the preference callbacks get their values (:class:`_PreferenceBatch`).
    Returns (u, preference before, preference after)."""
    budget = search.budget
    per_iter, iters = _per_iter(problem, search.local), _iters_per_start(problem, search.local)
    m = _Matcher(problem)
    tol = problem.tolerance_rel

    def pref_at(u):
        """(evaluation, preference) of one point: one kernel call, the print-shifted stacks in it."""
        ev, terms = problem.evaluate_terms(u)
        return ev, float(problem.preference(ev, weights, terms))

    def polish_run(u0, pref0, band, step):
        tracker = Tracker()
        tracker.offer(u0, pref0, 0.0)
        if budget.left > 3 * per_iter:
            batch = _PreferenceBatch(problem, weights, band, points)
            phase = Phase(batch, tracker, budget, "preference", stall_calls=STALL_CALLS)
            search.run(phase, u0, min(iters, budget.left // (3 * per_iter)), step)
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
        search.stops.append("newton: goal reached")
    elif not polished_matched and budget.left > per_iter:
        phase = Phase(m, rematch, budget, "re-match", m.goal)
        search.run(phase, polished, min(iters, budget.left // per_iter), 0.02 * INITIAL_STEP)
    final = rematch.u if rematch.u is not None and m.matched_at(rematch.u) else u_matched

    # -- phase 4: the preference once more, inside the narrow band
    e, after = pref_at(final)
    narrow = max(m.match_log, float(np.max(np.abs(e.log_err))))
    candidate = polish_run(final, after, narrow, 0.02 * INITIAL_STEP)
    if m.matched_at(candidate):
        final = candidate
        after = pref_at(final)[1]
    return final, before, after


def _matched(problem: DesignProblem, seed: int, search: Search) -> SolveResult:
    """Screening and phase 1 under ``search``'s budget: the SolveResult of the match."""
    u, matched, starts_used = _match(problem, seed, search)
    return SolveResult(
        u=u,
        matched=matched,
        evaluations=search.budget.used,
        starts_used=starts_used,
        preference_before=None,
        preference_after=None,
        local=search.local,
        stops=search.stops,
    )


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
    if local not in LOCAL_METHODS:
        raise ValueError(f"local method {local!r}: choose from {', '.join(LOCAL_METHODS)}")
    search = Search(Budget(max_evaluations, progress, max_time_s), local)
    result = _matched(problem, seed, search)
    if result.matched:
        result.u_matched = result.u
    if not result.matched or search.budget.left <= 3 * _per_iter(problem, local):
        return result
    result.u, result.preference_before, result.preference_after = prefer(problem, result.u, search, weights)
    result.evaluations = search.budget.used
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
