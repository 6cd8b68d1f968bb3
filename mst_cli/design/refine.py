"""Refining an L0 design with a dearer mechanics rung by output space mapping.

The optimiser's inner model is always L0 (``spring``: microseconds, vectorised). A dearer rung
(``frame`` or ``continuum``) is too slow to sit inside the search, but its prediction differs
from L0's by a smooth, slowly varying factor. Output space mapping (defect correction, Bandler
et al., IEEE Trans. MTT 52 (2004) 337) corrects the *targets* given to L0 by that factor:

    s_{k+1} = S_L0(x_k) * S_target / S_dear(x_k),   r_{k+1} = R_L0(x_k) * R_target / R_dear(x_k),

where x_k is the L0 design for targets (s_k, r_k) (so S_L0(x_k) = s_k when the match meets them).
At a fixed point the dear model meets the real targets. From the second step on, a secant
(Broyden) estimate of how the dear outputs follow the L0 targets scales the correction
(:class:`_SecantMapping`): on the reference spec the plain step over-corrects by a third each
time, and every step costs dear solves.

Each step costs one warm-started L0 match (tens of milliseconds: batched SLSQP, one evaluation
per point) and one dear simulation (one law per layer; the rungs cache laws per cell, so the
final judgement of the best iterate solves nothing again). The best iterate by the dear model's
max |log error| is kept and judged by the dear model (:func:`mst_cli.design.verify_design`):
every achieved number reported comes from it. The print-error sensitivity is measured with L0
unless the spec asks for more accuracy (:func:`print_error_rung`), and report.json says which.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable
from dataclasses import dataclass, field, replace
from typing import Any

import numpy as np

from mst_cli.design.document import design_document
from mst_cli.design.phase import CONVERGED, FEASIBILITY_TOL, MAX_TIME_S, Budget, LocalRun, Phase, Tracker
from mst_cli.design.problem import DesignProblem
from mst_cli.design.result import ROUND_DECIMALS, DesignResult, _layer_outputs
from mst_cli.design.solver import _Matcher
from mst_cli.design.verify import verify_design
from mst_cli.errors import InputError
from mst_cli.model.ladder import USER_LADDER, choose_mechanics, load_ladder_errors, rung_errors
from mst_cli.model.response import simulate
from mst_cli.sensor.as_printed import as_printed
from mst_cli.sensor.document import Document

REFINE_MODELS = ("frame", "continuum")
ASKED = "asked for by the caller"  # why the print error's rung is the one named
MAX_ITERATIONS = 6
STOP_FRACTION = 0.5  # iterate until the dear model is within this x tolerance (margin)
LOCAL_STEP = 0.02  # initial step of the COBYLA fallback (unit variables)
LOCAL_TRUST = 0.15  # the warm-started match moves at most this far (unit variables)
LOCAL_MATCH_LOG = 1e-6  # it ends when every L0 output is this close (log) to its target:
# far below the dear rung's own numerical noise
LOCAL_MAX_EVALUATIONS = 4000  # L0 candidate designs per warm-started match (batched)
LOCAL_FALLBACK_EVALUATIONS = 1000  # of which COBYLA may use after an unmatched SLSQP run: targets
# out of reach in the trust box stay out of reach for it too


@dataclass
class RefinedResult(DesignResult):
    """A design judged by the dear model, with the record of its refinement."""

    refinement: dict = field(default_factory=dict)

    def report_extra(self) -> dict:
        return {**super().report_extra(), "refinement": self.refinement}

    def table(self) -> str:
        lines = [
            f"refined for mechanics={self.refinement['model']} by output space mapping "
            f"(inner model L0 spring): max |error| per iteration "
            + ", ".join(f"{100 * it['max_abs_error_rel']:.2f} %" for it in self.refinement["iterations"])
        ]
        return "\n".join(lines) + "\n" + super().table()


class _SecantMapping:
    """Broyden's secant estimate J of d(dear log outputs)/d(L0 log targets), from J = I.

    Plain output space mapping steps z -= e: right when the dear/L0 ratio does not move with
    the design. On the reference spec it over-corrects by about a third every iteration (the
    errors alternate in sign and shrink 3x per dear solve); one rank-1 update from two iterates
    learns that, and z -= J^-1 e then lands in one step (aggressive space mapping, Bandler et
    al. 2004). Dear solves are most of the cost, so an iteration saved is worth it. The plain step is
    used, and J reset, when the last step made the worst error grow or J is near singular:
    contact and the dear mesh make the map only piecewise smooth.
    """

    MAX_COND = 1e3  # J beyond this is a secant taken across a jump
    MAX_STEP_RATIO = 3.0  # a step this many times the plain one is not trusted

    def __init__(self, size: int):
        self.J = np.eye(size)
        self.prev: tuple[np.ndarray, np.ndarray] | None = None

    def next_targets(self, z, e):
        """Next L0 log targets from L0's log outputs ``z`` at the current design and the dear
        model's log errors ``e`` there; returns (z_next, "secant" | "plain")."""
        plain = z - e
        if self.prev is not None:
            z0, e0 = self.prev
            dz, de = z - z0, e - e0
            if np.max(np.abs(e)) >= np.max(np.abs(e0)):
                self.J = np.eye(len(z))  # the last step did not help: start afresh
            elif float(dz @ dz) > 0.0:
                self.J = self.J + np.outer(de - self.J @ dz, dz) / float(dz @ dz)
        self.prev = (z, e)
        if np.linalg.cond(self.J) > self.MAX_COND:
            self.J = np.eye(len(z))
            return plain, "plain"
        step = -np.linalg.solve(self.J, e)
        if not np.all(np.isfinite(step)) or np.linalg.norm(step) > self.MAX_STEP_RATIO * np.linalg.norm(e):
            self.J = np.eye(len(z))
            return plain, "plain"
        return z + step, "plain" if np.allclose(self.J, np.eye(len(z))) else "secant"


@dataclass
class _Iterate:
    theta: np.ndarray
    t: np.ndarray
    h: np.ndarray
    max_log_err: float

    @property
    def cells(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(theta deg, t mm, h mm), one entry per layer."""
        return self.theta, self.t, self.h


def _dear_errors(designed: Document, model: str, S_t, R_t):
    """(S, R) of the dear model on a design as printed and the log errors against the real targets."""
    field_model = None if designed.field_model == "auto" else designed.field_model
    printed = as_printed(designed)
    resp = simulate(
        printed.geometry(),
        printed.material,
        mechanics=model,
        field_model=field_model,
        noise_uT_rms=designed.noise_uT_rms,
        whole_part=designed.whole_part,
    )
    S, R = _layer_outputs(resp, len(S_t))
    return S, R, np.log(S / S_t), np.log(R / R_t)


def _local_match(problem: DesignProblem, theta, t, h, maxeval: int = LOCAL_MAX_EVALUATIONS):
    """Local L0 match of ``problem``'s targets from (theta, t, h), every design rule kept (with
    the solver's rounding slack), on the normalised variables.

    nlopt LD_SLSQP inside a box of +-LOCAL_TRUST around the start (so the spare freedom stays
    on the previous design's branch), run by the solver's phase runner
    (:class:`~mst_cli.design.phase.Phase`): objective and every constraint of a point come
    from one evaluation (the mconstraint callback fills them all; the last point is cached),
    and a point with its central-difference gradient is one batched kernel call of 2 dim + 1
    candidates. Should SLSQP fail (line search, roundoff) or end on no feasible point, LN_COBYLA
    continues from its best point (single points, still one evaluation each); when SLSQP
    converged short of the targets they are out of reach in the box, and COBYLA is not tried.

    Returns the rounded (theta, t, h), the candidate designs evaluated and whether every L0
    output is within the tolerance of the (corrected) targets.
    """
    u0 = np.clip(problem.to_unit(theta, t, h), 0.0, 1.0)
    lo, hi = np.maximum(u0 - LOCAL_TRUST, 0.0), np.minimum(u0 + LOCAL_TRUST, 1.0)
    matcher = _Matcher(problem)
    budget = Budget(maxeval, None, MAX_TIME_S)
    best = Tracker()

    max_rel = -math.expm1(-LOCAL_MATCH_LOG)  # |rel| below this keeps |log| below LOCAL_MATCH_LOG

    def goal(f, g, err):
        return bool(np.all(g <= FEASIBILITY_TOL)) and err <= max_rel

    def matched(u):
        ev = problem.evaluate(u)
        return bool(np.all(ev.safe_constraints <= FEASIBILITY_TOL) and np.max(np.abs(ev.log_err)) <= LOCAL_MATCH_LOG)

    def run(local: str, x0, maxeval: int) -> bool:
        phase = Phase(matcher, best, budget, "refine match", goal)
        return _converged(phase, x0, LocalRun(local, maxeval, LOCAL_STEP, lo, hi))

    converged = run("slsqp", u0, budget.left // (2 * problem.dim + 1))
    if not matched(best.u) and not (converged and best.feasible) and budget.left > 0:
        run("cobyla", best.u, min(budget.left, LOCAL_FALLBACK_EVALUATIONS))
    u = u0 if best.u is None or not best.feasible else best.u
    theta2, t2, h2 = (np.round(a, ROUND_DECIMALS) for a in problem.to_physical(u))
    ev = problem.evaluate_physical(theta2, t2, h2)
    met = bool(np.all(np.abs(ev.rel_err) <= problem.tolerance_rel))
    return theta2, t2, h2, budget.used, met


def _converged(phase: Phase, x0, settings: LocalRun) -> bool:
    """One run of ``phase``; True when nlopt ended on its own stopping rules or the goal
    (False: a failure, roundoff or the budget). The phase's tracker keeps the best point
    whatever way the run ends."""
    try:
        return phase.run(x0, settings) in CONVERGED
    except ValueError:  # nlopt's invalid arguments (a start it refuses): this loop has always
        return False  # ended such a run like a failure, keeping the best point seen


def print_error_rung(doc: Document, model: str, errors: dict | None = None) -> tuple[str, str]:
    """The rung that measures a refined design's print-error sensitivity, and why (one line).

    The rule: L0 (``spring``), unless the spec's ``model.accuracy_rel`` asks for more than L0's
    measured accuracy; then the rung that accuracy picks (:func:`~mst_cli.model.ladder.choose_mechanics`),
    never dearer than ``model``. The print sensitivity is a ratio of two runs of one model
    (walls +-0.05 mm against nominal), and L0's measured median errors against L2 (about 1 % in
    stiffness and 1.5 % in lock force, ``ladder_errors.json``) are small beside the 10-50 % changes
    it measures; the dear rung there costs 2 solves per layer for a second digit.
    """
    errors = load_ladder_errors() if errors is None else errors
    if doc.accuracy_rel is None:
        err = rung_errors("spring", errors)
        return "spring", (
            f"L0 (measured median error against continuum: stiffness {100 * err['k']:.2g} %, "
            f"lock force {100 * err['lock_force']:.2g} %); a model.accuracy_rel below "
            f"that measures it with a dearer rung"
        )
    asked = choose_mechanics(None, doc.accuracy_rel, "spring", errors).mechanics
    rung = min(asked, model, key=USER_LADDER.index)
    return rung, (
        f"model.accuracy_rel = {doc.accuracy_rel:g} picks {asked}"
        + ("" if rung == asked else f", capped at the refining rung {model}")
    )


def refine_document(
    doc: Document,
    model: str,
    *,
    seed: int | None = None,
    progress: Callable | None = None,
    max_evaluations: int | None = None,
    max_iterations: int = MAX_ITERATIONS,
    print_error_mechanics: str | None = None,
) -> DesignResult:
    """Design ``doc`` with L0, then polish the result for the dear ``model`` by space mapping.

    Parameters
    ----------
    doc : Document
        A spec (targets per layer); its model.mechanics is ignored (L0 is the inner model).
    model : {"frame", "continuum"}
        The rung whose prediction must meet the targets.
    seed, progress, max_evaluations
        As :func:`mst_cli.design.design_document`, for every inner L0 design.
    max_iterations : int
        Dear-model evaluations at most (the first is the plain L0 design). The loop stops
        early once every dear-model error is within STOP_FRACTION x design.tolerance_rel.
    print_error_mechanics : str, optional
        The rung that measures the print-error sensitivity [default: :func:`print_error_rung`].

    Returns
    -------
    DesignResult
        Judged by ``model``: ``response``, ``targets``, ``checks`` come from ``model``'s forward
        model on the written design; ``print_error`` from the rung it names (``mechanics``);
        ``refinement`` (in ``report_extra``) records the iterations. Status "met" when every
        target is within design.tolerance_rel.
    """
    if model not in REFINE_MODELS:
        raise InputError("--refine", model, "one of " + ", ".join(REFINE_MODELS))
    t_start = time.perf_counter()
    doc.require_targets()
    run = _Refinement(doc, model)
    run.iterate(max_iterations, seed=seed, progress=progress, max_evaluations=max_evaluations)
    pe_rung, pe_rule = print_error_rung(doc, model) if print_error_mechanics is None else (print_error_mechanics, ASKED)
    first, best = run.first, run.best
    assert first is not None and best is not None  # max_iterations >= 1: the L0 design ran
    result = verify_design(
        replace(doc, mechanics=model),
        run.problem,
        *best.cells,
        _SolverFacts.from_result(first, run.evaluations),
        seed=first.seed,
        max_evaluations=first.max_evaluations,
        mechanics=model,
        t_start=t_start,
        print_error_mechanics=pe_rung,
        print_error_rule=pe_rule,
    )
    if result.status != "met":
        _name_the_miss(result, model, len(run.history), run.stopped)
    result.elapsed_s = time.perf_counter() - t_start
    return RefinedResult(**vars(result), refinement=run.record(max_iterations))


def _name_the_miss(result: DesignResult, model: str, iterations: int, stopped: str) -> None:
    """Make the worst-missed target of the dear ``model`` the binding reason of ``result`` (unless
    every target is met and a constraint binds: verify_design named it)."""
    if all(row["within_tolerance"] for row in result.targets):
        return
    tol = float(result.document.design["tolerance_rel"])
    worst_row = max(result.targets, key=lambda row: max(abs(row["sensitivity_error_rel"]), abs(row["range_error_rel"])))
    which = "S" if abs(worst_row["sensitivity_error_rel"]) >= abs(worst_row["range_error_rel"]) else "R"
    err = worst_row["sensitivity_error_rel" if which == "S" else "range_error_rel"]
    result.binding = f"layer {worst_row['layer']} {which} ({model} model)"
    result.reasons.insert(
        0,
        f"after {iterations} refinement iterations the {model} model "
        f"misses layer {worst_row['layer']} {which} by {100 * err:+.2f} % "
        f"(tolerance {100 * tol:g} %): {stopped}",
    )


class _Refinement:
    """One output-space-mapping refinement of the spec ``doc`` for the dear ``model``: the L0
    targets (s, r) it asks for, the dear model's verdict on each iterate, the best one."""

    def __init__(self, doc: Document, model: str):
        self.doc, self.model = doc, model
        self.tol = float(doc.design["tolerance_rel"])
        self.S_t = np.array([la.target_sensitivity_per_N for la in doc.layers], dtype=float)
        self.R_t = np.array([la.target_range_N for la in doc.layers], dtype=float)
        self.inner_doc = replace(doc, mechanics="spring")
        self.problem = DesignProblem(self.inner_doc)  # the L0 problem of the real targets (explains a miss)
        self.mapping = _SecantMapping(2 * len(self.S_t))
        self.history: list[dict] = []
        self.best: _Iterate | None = None
        self.first: DesignResult | None = None  # the plain L0 design (iteration 1)
        self.evaluations = 0
        self.stopped = ""

    def iterate(self, max_iterations: int, **design: Any) -> None:
        """Up to ``max_iterations`` L0 designs, each judged by the dear model, until it meets every
        target within STOP_FRACTION x the tolerance; ``design``: design_document's options."""
        self.stopped = f"iteration cap ({max_iterations}) reached"
        s, r = self.S_t.copy(), self.R_t.copy()
        step_kind = "none (the spec's targets)"
        cells: tuple[np.ndarray, np.ndarray, np.ndarray] | None = None
        for k in range(max_iterations):
            cells, inner_status = self._l0_design(k, s, r, cells, design)
            S, R, lS, lR = _dear_errors(self._with_cells(*cells), self.model, self.S_t, self.R_t)
            worst = float(max(np.abs(lS).max(), np.abs(lR).max()))
            rel = np.concatenate([S / self.S_t - 1.0, R / self.R_t - 1.0])
            self.history.append(_history_row(k, worst, rel, inner_status, step_kind, (s, r), cells))
            if self.best is None or worst < self.best.max_log_err:
                self.best = _Iterate(*cells, worst)
            if np.all(np.abs(rel) <= STOP_FRACTION * self.tol):
                self.stopped = (
                    f"{self.model} model meets every target within {100 * STOP_FRACTION * self.tol:g} % "
                    f"(half the tolerance) at iteration {k + 1}"
                )
                return
            # output space mapping: correct the L0 targets by the dear model's miss, through the
            # secant estimate of how the dear outputs follow the L0 targets; start from what L0
            # gives at x_k, not what it was asked for (the same when the local match met them, and
            # a consistent secant pair when it could not)
            ev = self.problem.evaluate_physical(*cells)
            z_l0 = np.log(np.concatenate([ev.S_per_N, ev.R_N]))
            z, step_kind = self.mapping.next_targets(z_l0, np.concatenate([lS, lR]))
            s, r = np.exp(z[: len(s)]), np.exp(z[len(s) :])

    def _l0_design(
        self,
        k: int,
        s: np.ndarray,
        r: np.ndarray,
        cells: tuple[np.ndarray, np.ndarray, np.ndarray] | None,
        design: dict,
    ) -> tuple[tuple[np.ndarray, np.ndarray, np.ndarray], str]:
        """The L0 design (theta, t, h) of the targets (s, r) and whether L0 met them: at k = 0 the
        plain design of the real targets (global search, preference), then a local L0 match
        from the previous ``cells``, so the spare freedom (the preference) does not jump to
        another branch."""
        layers = [
            replace(la, target_sensitivity_per_N=float(a), target_range_N=float(b))
            for la, a, b in zip(self.doc.layers, s, r)
        ]
        if k == 0 or cells is None:
            inner = design_document(self.inner_doc.with_layers(layers), name_height=False, **design)
            self.first = inner
            self.evaluations += inner.evaluations
            theta, t, h = (
                np.array([getattr(la, key) for la in inner.document.layers]) for key in ("theta_deg", "t_mm", "h_mm")
            )
            return (theta, t, h), inner.status
        theta, t, h, n_eval, inner_met = _local_match(DesignProblem(self.inner_doc.with_layers(layers)), *cells)
        self.evaluations += n_eval
        return (theta, t, h), "met" if inner_met else "not met"

    def _with_cells(self, theta: np.ndarray, t: np.ndarray, h: np.ndarray) -> Document:
        return self.inner_doc.with_layers(
            [
                replace(la, theta_deg=float(a), t_mm=float(b), h_mm=float(c))
                for la, a, b, c in zip(self.doc.layers, theta, t, h)
            ]
        )

    def record(self, max_iterations: int) -> dict:
        """report.json's ``refinement``: the method and every iteration."""
        history = self.history
        return {
            "inner_model": "spring",
            "model": self.model,
            "method": "output space mapping: L0 targets corrected by the dear model's log miss (plain, or "
            "through a Broyden secant estimate of d dear / d L0 target), L0 re-matched locally",
            "iterations": history,
            "best_iteration": 1 + min(range(len(history)), key=lambda i: history[i]["max_abs_log_error"]),
            "stopped": self.stopped,
            "max_iterations": max_iterations,
            "l0_evaluations_total": self.evaluations,
        }


def _history_row(
    k: int,
    worst: float,
    rel: np.ndarray,
    inner_status: str,
    step_kind: str,
    targets: tuple[np.ndarray, np.ndarray],
    cells: tuple[np.ndarray, np.ndarray, np.ndarray],
) -> dict:
    """One iteration of report.json's ``refinement.iterations``."""
    (s, r), (theta, t, h) = targets, cells
    return {
        "iteration": k + 1,
        "max_abs_log_error": worst,
        "max_abs_error_rel": float(np.abs(rel).max()),
        "inner_status": inner_status,
        "l0_targets_update": step_kind,
        "l0_targets_sensitivity_per_N": s.tolist(),
        "l0_targets_range_N": r.tolist(),
        "theta_deg": theta.tolist(),
        "t_mm": t.tolist(),
        "h_mm": h.tolist(),
    }


@dataclass
class _SolverFacts:
    """The solver facts verify_design reports, taken from the best inner L0 design."""

    matched: bool
    evaluations: int
    local: str
    starts_used: int
    preference_before: float | None
    preference_after: float | None
    stops: dict

    @classmethod
    def from_result(cls, res: DesignResult, evaluations: int) -> _SolverFacts:
        s = res.solver
        local = "slsqp" if "SLSQP" in s["method"] else "cobyla"
        return cls(
            s["matched"],
            evaluations,
            local,
            s["starts_used"],
            s["preference_before"],
            s["preference_after"],
            s["runs_ended"],
        )


__all__ = ["refine_document", "print_error_rung", "RefinedResult", "REFINE_MODELS", "MAX_ITERATIONS"]
