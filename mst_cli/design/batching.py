"""Many weightings' preference polishes at once, their kernel calls batched into one.

:func:`prefer_many` runs phases 2-4 (:func:`mst_cli.design.solver.prefer`) for every (start,
weighting) pair of a Pareto front. Each pair keeps its own local runs; only their evaluations
are pooled: each run sees a :class:`_BatchedProblem` (the :class:`DesignProblem` interface:
``evaluate``, ``evaluate_terms``, and :class:`Evaluation` rows that carry ``safe_constraints``
and ``max_err`` like any other) and hands :func:`~mst_cli.design.solver.prefer` the
``preference_point`` hook for its preference callbacks. A pair's polish is the same to the bit
in any batch, so the answer is too.
"""

from __future__ import annotations

from collections import OrderedDict
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, NamedTuple

import numpy as np

from mst_cli.design.phase import FD_STEP, MAX_TIME_S, Budget, PointValues, finite
from mst_cli.design.problem import DesignProblem, Evaluation, robustness_of_shifts
from mst_cli.design.solver import Search, prefer, preference_constraints
from mst_cli.parallel import fork_map, workers

if TYPE_CHECKING:
    from collections.abc import Callable

    from numpy.typing import ArrayLike

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
        # a job's (Evaluation rows, preference terms), or a preference request's PointValues
        out: dict[int, tuple] = {j: (_Rows(batch, rows), terms[rows]) for j, rows in rows_of.items()}
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


def _point_rows(problem: DesignProblem, batch: _BatchRows, terms: np.ndarray, asks: dict) -> dict[int, PointValues]:
    """The :class:`PointValues` of every preference request of a round, ``asks`` {job: (its
    rows, its _PointAsk)}: the constraints, the non-finite guard, the central differences and
    the violations computed once for all of them (elementwise and row-wise), each run's numbers
    to the bit those of :class:`~mst_cli.design.solver._PreferenceBatch` on its own rows."""
    starts = np.array([rows.start for rows, _ in asks.values()])
    sizes = np.array([rows.stop - rows.start for rows, _ in asks.values()])
    index = _block_rows(starts, sizes)
    bands = np.repeat([a.band for _, a in asks.values()], sizes)[:, None]
    g = finite(preference_constraints(batch.safe_constraints[index], batch.ev.log_err[index], bands), 1e6)
    # the preference run by run: a matrix product's bits depend on its shape
    score = finite(np.concatenate([problem.weighted_terms(terms[r], a.weights) for r, a in asks.values()]), 1e30)
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
        j: PointValues(f, g[o], df[c] if grad else None, dg[c].T if grad else None, v, err)
        for j, f, o, v, err, grad, c in rows
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
        self.safe_constraints = ev.safe_constraints
        self.max_err = ev.max_err


class _Rows(Evaluation):
    """A run's rows of a :class:`_BatchRows`: the :class:`Evaluation` of its own points, each
    field sliced out when it is first read (a run reads a few of them); ``safe_constraints``
    and ``max_err`` are the round's, computed once for the batch."""

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

    def preference_point(self, U: np.ndarray, weights, band: float) -> PointValues:
        """What the phase runner needs of a preference callback's points ``U``, from the shared
        round (:func:`_point_rows`), or again without one when recently asked: the ``points``
        hook of :func:`~mst_cli.design.solver.prefer`."""
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
    """Phases 2-4 (:func:`~mst_cli.design.solver.prefer`) for every (start, weighting) pair,
    each with a fresh ``max_evaluations`` budget, their kernel calls batched across the
    weightings. Returns (u, evaluations) per pair, in order.

    With more than one core the pairs are dealt round-robin to forked workers
    (:func:`mst_cli.parallel.fork_map`), each batching its share: a pair's polish is the same
    to the bit in any batch (:class:`_SharedEvaluations`), so the answer is too."""
    n = len(starts)
    n_hands = max(1, min(n, workers()))
    hands = [list(range(i, n, n_hands)) for i in range(n_hands)]
    polishes = _Polishes(problem, starts, weightings, max_evaluations, local, max_time_s)
    dealt = fork_map(polishes.hand, hands)
    if dealt is None:  # one worker, or no fork here: all of them in this process
        hands = [list(range(n))]
        dealt = [polishes.hand(hands[0])]
    out: list = [None] * n
    run_stops: list[list[str]] = [[] for _ in range(n)]
    for hand, (results, hand_stops) in zip(hands, dealt):
        for k, result, s in zip(hand, results, hand_stops):
            out[k], run_stops[k] = result, s
    if stops is not None:
        for s in run_stops:
            stops.extend(s)
    return out


@dataclass(frozen=True)
class _Polishes:
    """The settings of one :func:`prefer_many` call, shared by its hands."""

    problem: DesignProblem
    starts: list[np.ndarray]
    weightings: list[ArrayLike]
    max_evaluations: int
    local: str
    max_time_s: float

    def hand(self, hand: list[int]) -> tuple[list, list[list[str]]]:
        """The pairs numbered ``hand``, batched: ([(u, evaluations)], [stops])."""
        run_stops: list[list[str]] = [[] for _ in hand]

        def job(k, i):
            def run(batched):
                search = Search(Budget(self.max_evaluations, None, self.max_time_s), self.local, run_stops[i])
                u, _, _ = prefer(batched, self.starts[k], search, self.weightings[k], batched.preference_point)
                return u, search.budget.used

            return run

        return _SharedEvaluations(self.problem).run([job(k, i) for i, k in enumerate(hand)]), run_stops
