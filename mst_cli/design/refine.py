"""Refining an L0 design with a dearer mechanics rung by output space mapping.

The optimiser's inner model is always L0 (``spring``: microseconds, vectorised). A dearer rung
(``frame`` or ``continuum``) is too slow to sit inside the search, but its prediction differs
from L0's by a smooth, slowly varying factor. Output space mapping (defect correction, Bandler
et al., IEEE Trans. MTT 52 (2004) 337) corrects the *targets* given to L0 by that factor:

    s_{k+1} = s_k * S_target / S_dear(x_k),   r_{k+1} = r_k * R_target / R_dear(x_k),

where x_k is the L0 design for targets (s_k, r_k). At a fixed point the dear model meets the
real targets. Each step costs one L0 design (about a second) and one dear simulation. The best
iterate by the dear model's max |log error| is kept and judged by the dear model
(:func:`mst_cli.design.verify_design`): every achieved number reported comes from it.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field, replace

import numpy as np

from mst_cli.design.document import ROUND_DECIMALS, DesignResult, _layer_outputs, design_document, verify_design
from mst_cli.design.problem import DesignProblem
from mst_cli.errors import InputError
from mst_cli.io.schema import Document
from mst_cli.model.response import simulate

REFINE_MODELS = ("frame", "continuum")
MAX_ITERATIONS = 6
STOP_FRACTION = 0.5             # iterate until the dear model is within this x tolerance (margin)
LOCAL_STEP = 0.02               # initial COBYLA step of the warm-started L0 match (unit variables)
LOCAL_MAX_EVALUATIONS = 4000    # L0 evaluations per warm-started match (~50 us each)


@dataclass
class RefinedResult(DesignResult):
    """A design judged by the dear model, with the record of its refinement."""

    refinement: dict = field(default_factory=dict)

    def report_extra(self) -> dict:
        return {**super().report_extra(), "refinement": self.refinement}

    def table(self) -> str:
        lines = [f"refined for mechanics={self.refinement['model']} by output space mapping "
                 f"(inner model L0 spring): max |error| per iteration "
                 + ", ".join(f"{100 * it['max_abs_error_rel']:.2f} %"
                             for it in self.refinement["iterations"])]
        return "\n".join(lines) + "\n" + super().table()


@dataclass
class _Iterate:
    theta: np.ndarray
    t: np.ndarray
    h: np.ndarray
    max_log_err: float


def _dear_errors(doc: Document, geometry, model: str, S_t, R_t):
    """(S, R) of the dear model on a design and the log errors against the real targets."""
    field_model = None if doc.field_model == "auto" else doc.field_model
    resp = simulate(geometry, doc.material, mechanics=model, field_model=field_model,
                    noise_uT_rms=doc.noise_uT_rms)
    S, R = _layer_outputs(resp, len(S_t))
    return S, R, np.log(S / S_t), np.log(R / R_t)


def _local_match(problem: DesignProblem, theta, t, h, maxeval: int = LOCAL_MAX_EVALUATIONS):
    """Local L0 match of ``problem``'s targets from (theta, t, h): nlopt COBYLA on the
    normalised variables, every design rule kept (with the solver's rounding slack).

    Returns the rounded (theta, t, h), the evaluations used and whether every L0 output is
    within the tolerance of the (corrected) targets.
    """
    import nlopt

    from mst_cli.design.solver import ROUNDING_SAFETY, _nlopt_failures

    u0 = np.clip(problem.to_unit(theta, t, h), 0.0, 1.0)
    count = [0]
    best = [u0.copy(), np.inf]

    def objective(u, grad):
        count[0] += 1
        ev = problem.evaluate(u)
        f = float(ev.objective)
        if np.all(ev.constraints + ROUNDING_SAFETY <= 0.0) and f < best[1]:
            best[0], best[1] = u.copy(), f
        return f if np.isfinite(f) else 1e30

    def constraints(result, u, grad):
        result[:] = problem.evaluate(u).constraints + ROUNDING_SAFETY

    opt = nlopt.opt(nlopt.LN_COBYLA, problem.dim)
    opt.set_lower_bounds(np.zeros(problem.dim))
    opt.set_upper_bounds(np.ones(problem.dim))
    opt.set_min_objective(objective)
    opt.add_inequality_mconstraint(constraints, np.full(problem.n_constraints, 1e-12))
    opt.set_initial_step(LOCAL_STEP)
    opt.set_maxeval(maxeval)
    opt.set_ftol_abs(1e-14)
    opt.set_xtol_rel(1e-10)
    try:
        opt.optimize(u0)
    except (nlopt.RoundoffLimited, ValueError, RuntimeError, *_nlopt_failures()):
        pass                                    # keep the best feasible point seen
    u = best[0]
    theta2, t2, h2 = (np.round(a, ROUND_DECIMALS) for a in problem.to_physical(u))
    ev = problem.evaluate_physical(theta2, t2, h2)
    met = bool(np.all(np.abs(ev.rel_err) <= problem.tolerance_rel))
    return theta2, t2, h2, count[0], met


def refine_document(doc: Document, model: str, *, seed: int | None = None, progress=None,
                    max_evaluations: int | None = None,
                    max_iterations: int = MAX_ITERATIONS) -> DesignResult:
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

    Returns
    -------
    DesignResult
        Judged by ``model``: ``response``, ``targets``, ``checks``, ``print_error`` all come from
        ``model``'s forward model on the written design; ``refinement`` (in ``report_extra``)
        records the iterations. Status "met" when every target is within design.tolerance_rel.
    """
    if model not in REFINE_MODELS:
        raise InputError("--refine", model, "one of " + ", ".join(REFINE_MODELS))
    t_start = time.perf_counter()
    doc.require_targets()
    tol = float(doc.design["tolerance_rel"])
    S_t = np.array([la.target_sensitivity_per_N for la in doc.layers], dtype=float)
    R_t = np.array([la.target_range_N for la in doc.layers], dtype=float)
    inner_doc = replace(doc, mechanics="spring")
    s, r = S_t.copy(), R_t.copy()
    history, best, evaluations = [], None, 0
    stopped = f"iteration cap ({max_iterations}) reached"
    for k in range(max_iterations):
        layers = [replace(la, target_sensitivity_per_N=float(a), target_range_N=float(b))
                  for la, a, b in zip(doc.layers, s, r)]
        if k == 0:
            # the plain L0 design of the real targets (global search, preference)
            inner = design_document(inner_doc.with_layers(layers), seed=seed, progress=progress,
                                    max_evaluations=max_evaluations)
            evaluations += inner.evaluations
            theta, t, h = (np.array([getattr(la, key) for la in inner.document.layers])
                           for key in ("theta_deg", "t_mm", "h_mm"))
            inner_status = inner.status
        else:
            # warm start: a local L0 match of the corrected targets from the previous design,
            # so the spare freedom (the preference) does not jump to another branch
            problem_k = DesignProblem(inner_doc.with_layers(layers))
            theta, t, h, n_eval, inner_met = _local_match(problem_k, theta, t, h)
            evaluations += n_eval
            inner_status = "met" if inner_met else "not met"
        S, R, lS, lR = _dear_errors(doc, inner_doc.with_layers(
            [replace(la, theta_deg=float(a), t_mm=float(b), h_mm=float(c))
             for la, a, b, c in zip(doc.layers, theta, t, h)]).geometry(), model, S_t, R_t)
        worst = float(max(np.abs(lS).max(), np.abs(lR).max()))
        rel = np.concatenate([S / S_t - 1.0, R / R_t - 1.0])
        history.append({
            "iteration": k + 1, "max_abs_log_error": worst,
            "max_abs_error_rel": float(np.abs(rel).max()),
            "inner_status": inner_status,
            "l0_targets_sensitivity_per_N": s.tolist(), "l0_targets_range_N": r.tolist(),
            "theta_deg": theta.tolist(), "t_mm": t.tolist(), "h_mm": h.tolist(),
        })
        if best is None or worst < best.max_log_err:
            best = _Iterate(theta, t, h, worst)
        if np.all(np.abs(rel) <= STOP_FRACTION * tol):
            stopped = (f"{model} model meets every target within {100 * STOP_FRACTION * tol:g} % "
                       f"(half the tolerance) at iteration {k + 1}")
            break
        # output space mapping: correct the L0 targets by the dear model's miss
        s, r = s * np.exp(-lS), r * np.exp(-lR)

    final_doc = replace(doc, mechanics=model)
    problem = DesignProblem(inner_doc)          # the L0 problem of the real targets: explains a miss
    sol = _SolverFacts.from_result(inner, evaluations)
    result = verify_design(final_doc, problem, best.theta, best.t, best.h, sol,
                           seed=inner.seed, max_evaluations=inner.max_evaluations,
                           mechanics=model, t_start=t_start)
    if result.status != "met":
        worst_row = max(result.targets, key=lambda row: max(abs(row["sensitivity_error_rel"]),
                                                            abs(row["range_error_rel"])))
        which = ("S" if abs(worst_row["sensitivity_error_rel"]) >= abs(worst_row["range_error_rel"])
                 else "R")
        err = worst_row["sensitivity_error_rel" if which == "S" else "range_error_rel"]
        if all(row["within_tolerance"] for row in result.targets):
            pass                                    # a constraint binds: verify_design named it
        else:
            result.binding = f"layer {worst_row['layer']} {which} ({model} model)"
            result.reasons.insert(0, f"after {len(history)} refinement iterations the {model} model "
                                     f"misses layer {worst_row['layer']} {which} by {100 * err:+.2f} % "
                                     f"(tolerance {100 * tol:g} %): {stopped}")
    refinement = {
        "inner_model": "spring", "model": model,
        "method": "output space mapping: L0 targets scaled by target / dear-achieved, L0 re-designed",
        "iterations": history,
        "best_iteration": 1 + min(range(len(history)), key=lambda i: history[i]["max_abs_log_error"]),
        "stopped": stopped, "max_iterations": max_iterations,
        "l0_evaluations_total": evaluations,
    }
    result.elapsed_s = time.perf_counter() - t_start
    return RefinedResult(**vars(result), refinement=refinement)


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
        return cls(s["matched"], evaluations, local, s["starts_used"], s["preference_before"],
                   s["preference_after"], s["runs_ended"])


__all__ = ["refine_document", "RefinedResult", "REFINE_MODELS", "MAX_ITERATIONS"]
