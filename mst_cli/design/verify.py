"""Judging a design: re-simulated with the forward model on the part as printed, every target
and constraint checked, the print-error sensitivity re-measured (walls thicker and thinner),
the binding reason named (:func:`verify_design`). Pure: no I/O."""

from __future__ import annotations

import math
import time
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from mst_cli.design import explain
from mst_cli.design.problem import DesignProblem
from mst_cli.design.result import (
    PRINT_DEVIATION_CHECK,
    SAME_RUNG_RULE,
    WARN_PRINT_DEVIATION_REL,
    DesignResult,
    SolverFacts,
    _layer_outputs,
)
from mst_cli.model.assembly import SensorGeometry
from mst_cli.model.plate_joint import FITTED_BOX, LOW_CORNER_WORST_REL, outside_fitted_box
from mst_cli.model.printer import Printer
from mst_cli.model.response import Response, simulate
from mst_cli.sensor.as_printed import as_printed
from mst_cli.sensor.document import Document
from mst_cli.sensor.sections import LayerEntry

if TYPE_CHECKING:
    from numpy.typing import ArrayLike  # annotations only: numpy.typing costs start-up time


def verify_design(
    doc: Document,
    problem: DesignProblem,
    theta: ArrayLike,
    t: ArrayLike,
    h: ArrayLike,
    sol: SolverFacts,
    *,
    seed: int,
    max_evaluations: int,
    mechanics: str,
    t_start: float | None = None,
    print_error_mechanics: str | None = None,
    print_error_rule: str | None = None,
) -> DesignResult:
    """Write (theta, t, h) into the spec ``doc`` and judge it with ``mechanics``'s forward model.

    Every achieved number and constraint check comes from
    :func:`mst_cli.model.response.simulate` with ``mechanics`` on the written (rounded) design;
    ``problem`` (the L0 problem of ``doc``'s targets) only explains a miss. ``sol`` is the
    solver's result (its ``matched``, ``evaluations``, ... are reported). The print-error
    sensitivity is measured with ``print_error_mechanics`` [default: ``mechanics``], nominal and
    shifted designs alike, and reported with that rung and ``print_error_rule`` (why it).
    theta (deg), t and h (mm) have one entry per layer.
    """
    t_start = time.perf_counter() if t_start is None else t_start
    theta, t, h = (np.asarray(a, dtype=float) for a in (theta, t, h))
    designed = with_cells(doc, theta, t, h)
    geometry = designed.geometry()  # as drawn: what export draws
    run = _PrintedRuns(designed, None if doc.field_model == "auto" else doc.field_model, doc.noise_uT_rms)
    resp = run(0.0, mechanics)

    S, R = _layer_outputs(resp, problem.n)
    targets = _target_rows(problem, theta, t, h, S, R)
    checks = _constraint_checks(problem, geometry, doc.printer, resp, R)
    pe_mechanics = mechanics if print_error_mechanics is None else print_error_mechanics
    nominal = (S, R) if pe_mechanics == mechanics else _layer_outputs(run(0.0, pe_mechanics), problem.n)
    rung = (pe_mechanics, print_error_rule or SAME_RUNG_RULE)
    print_error = _print_error(run, nominal, problem, float(doc.printer.wall_tolerance_mm), rung)
    checks.update(_deviation_check(print_error))
    met = all(row["within_tolerance"] for row in targets) and not checks
    binding, reasons = (None, []) if met else _why_not_met(problem, (theta, t, h), (S, R), checks, sol, max_evaluations)
    return DesignResult(
        document=designed,
        geometry=geometry,
        response=resp,
        status="met" if met else "not met",
        binding=binding,
        reasons=reasons,
        targets=targets,
        checks=checks,
        print_error=print_error,
        seed=seed,
        evaluations=sol.evaluations,
        max_evaluations=max_evaluations,
        solver=_solver_info(sol),
        elapsed_s=time.perf_counter() - t_start,
        warnings=_warnings(resp, print_error) + _joint_box_warnings(designed, geometry),
        objective=_objective(doc, geometry, resp, print_error),
    )


def _why_not_met(
    problem: DesignProblem,
    cells: tuple[np.ndarray, np.ndarray, np.ndarray],
    achieved: tuple[np.ndarray, np.ndarray],
    checks: dict[str, str],
    sol: SolverFacts,
    max_evaluations: int,
) -> tuple[str | None, list[str]]:
    """(binding, reasons) of a design that misses: :func:`explain.diagnose`, and the budget when
    the solver spent it unmatched."""
    binding, reasons = explain.diagnose(problem, problem.to_unit(*cells), *achieved, checks)
    if not sol.matched and sol.evaluations >= max_evaluations:
        reasons.append(
            f"the evaluation budget ({max_evaluations}) was spent before the targets were "
            "met: raise design.max_evaluations (or --max-evaluations) to search further"
        )
    return binding, reasons


def with_cells(doc: Document, theta: np.ndarray, t: np.ndarray, h: np.ndarray) -> Document:
    """The spec ``doc`` with every layer's theta (deg), t, h (mm) written in, targets kept."""
    layers = [
        LayerEntry(float(a), float(b), float(c), la.target_sensitivity_per_N, la.target_range_N, la.weight)
        for a, b, c, la in zip(theta, t, h, doc.layers)
    ]
    return doc.with_layers(layers)


@dataclass(frozen=True)
class _PrintedRuns:
    """The forward model of a design as the printer makes it, every wall ``extra_wall_mm``
    thicker still, with the mechanics rung ``rung``: ``run(extra_wall_mm, rung)``."""

    designed: Document
    field_model: str | None
    noise_uT_rms: float

    def __call__(self, extra_wall_mm: float, rung: str) -> Response:
        printed = as_printed(self.designed, extra_wall_mm)  # as the printer makes it
        return simulate(
            printed.geometry(),
            printed.material,
            mechanics=rung,
            field_model=self.field_model,
            noise_uT_rms=self.noise_uT_rms,
            whole_part=self.designed.whole_part,
            section=self.designed.section_rung,
        )


def _target_rows(
    problem: DesignProblem, theta: np.ndarray, t: np.ndarray, h: np.ndarray, S: np.ndarray, R: np.ndarray
) -> list[dict]:
    """report.json's ``targets``: per layer the cell, the target and achieved S_i, R_i, the errors."""
    tol = problem.tolerance_rel
    targets = []
    for i in range(problem.n):
        eS = S[i] / problem.S_target[i] - 1.0
        eR = R[i] / problem.R_target[i] - 1.0
        targets.append(
            {
                "layer": i + 1,
                "theta_deg": float(theta[i]),
                "t_mm": float(t[i]),
                "h_mm": float(h[i]),
                "target_sensitivity_per_N": float(problem.S_target[i]),
                "achieved_sensitivity_per_N": float(S[i]),
                "sensitivity_error_rel": float(eS),
                "target_range_N": float(problem.R_target[i]),
                "achieved_range_N": float(R[i]),
                "range_error_rel": float(eR),
                "within_tolerance": bool(abs(eS) <= tol and abs(eR) <= tol),
            }
        )
    return targets


def _constraint_checks(
    problem: DesignProblem, geometry: SensorGeometry, printer: Printer, resp: Response, R: np.ndarray
) -> dict[str, str]:
    """The broken constraints (name -> sentence): cell rules, lock order, chip saturation, height."""
    checks = {}
    for v in geometry.violations(printer):
        layer = 1 + (v.layer or 0)
        checks[f"layer {layer} {v.rule}"] = f"layer {layer}: {v.message}"
    for i in range(1, problem.n):
        if R[i] < (1 + problem.lock_margin_rel) * R[i - 1]:
            checks[f"lock order {i}-{i + 1}"] = (
                f"layer {i + 1} locks at {R[i]:.4g} N, less than {1 + problem.lock_margin_rel:g} x "
                f"layer {i}'s {R[i - 1]:.4g} N (design.lock_margin_rel)"
            )
    if resp.saturated or resp.B_full_T > problem.B_limit_T:
        checks["chip saturation"] = (
            f"field at full load {resp.B_full_T * 1e3:.2f} mT exceeds the "
            f"limit {problem.B_limit_T * 1e3:.2f} mT (design.saturation_margin_rel)"
        )
    if problem.max_height_mm is not None and geometry.total_height_mm > problem.max_height_mm:
        checks["total height"] = (
            f"total height {geometry.total_height_mm:.2f} mm exceeds "
            f"design.max_height_mm = {problem.max_height_mm:g} mm"
        )
    return checks


def _print_error(
    run: _PrintedRuns,
    nominal: tuple[np.ndarray, np.ndarray],
    problem: DesignProblem,
    tol_mm: float,
    rung: tuple[str, str],
) -> dict:
    """report.json's ``print_error_sensitivity``: the relative change of every S_i and R_i
    (against ``nominal``) with every wall ``tol_mm`` thicker and thinner, by the mechanics
    ``rung`` = (name, why it). One rung for the nominal and both shifted runs: a ratio of two
    rungs would mix the model gap into the print sensitivity."""
    S_pe, R_pe = nominal
    mechanics, rule = rung
    shifted = {key: _layer_outputs(run(sign * tol_mm, mechanics), problem.n) for sign, key in _SHIFTS}
    pe_layers = []
    logs = []
    for i in range(problem.n):
        row: dict = {"layer": i + 1}
        for key in ("plus", "minus"):
            S2, R2 = shifted[key]
            row[f"dS_rel_t_{key}"] = float(S2[i] / S_pe[i] - 1.0)
            row[f"dR_rel_t_{key}"] = float(R2[i] / R_pe[i] - 1.0)
            logs += [math.log(S2[i] / S_pe[i]), math.log(R2[i] / R_pe[i])]
        row["dS_rel_worst"] = max(abs(row["dS_rel_t_plus"]), abs(row["dS_rel_t_minus"]))
        row["dR_rel_worst"] = max(abs(row["dR_rel_t_plus"]), abs(row["dR_rel_t_minus"]))
        pe_layers.append(row)
    worst = max(max(row["dS_rel_worst"], row["dR_rel_worst"]) for row in pe_layers)
    return {
        "print_error_t_mm": tol_mm,
        "meaning": "relative change of S_i and R_i when every wall is printed printer.wall_tolerance_mm "
        "thicker (plus) or thinner (minus) than expected; its RMS is the print_robustness term of "
        "design.objective's preference, worst_change_rel the largest |change| of any S_i or R_i "
        "(design.max_print_deviation_rel limits it)",
        "rms_log_change": float(np.sqrt(np.mean(np.square(logs)))),
        "worst_change_rel": float(worst),
        "max_print_deviation_rel": problem.max_print_deviation_rel,
        "mechanics": mechanics,
        "mechanics_rule": rule,
        "layers": pe_layers,
    }


_SHIFTS = ((1.0, "plus"), (-1.0, "minus"))  # every wall thicker, then thinner


def _deviation_check(print_error: dict) -> dict[str, str]:
    """The print-deviation check that fails when the worst change passes its limit (or none)."""
    limit, worst = print_error["max_print_deviation_rel"], print_error["worst_change_rel"]
    if limit is None or worst <= limit:
        return {}
    return {
        PRINT_DEVIATION_CHECK: f"a wall {print_error['print_error_t_mm']:g} mm off changes some S_i or R_i by "
        f"{100 * worst:.1f} %, more than design.max_print_deviation_rel = {100 * limit:g} %"
    }


def _warnings(resp: Response, print_error: dict) -> list[str]:
    """The forward model's warnings, and one when the print sensitivity is high and unlimited."""
    warnings = list(resp.warnings)
    worst, tol_mm = print_error["worst_change_rel"], print_error["print_error_t_mm"]
    if print_error["max_print_deviation_rel"] is None and worst > WARN_PRINT_DEVIATION_REL:
        warnings.append(
            f"a wall {tol_mm:g} mm off its expected thickness changes some S_i or R_i by up to "
            f"{100 * worst:.0f} %: calibrate a first print and design again with --calibration "
            "(README: From a first print to a second), or trade height for robustness (mst design --pareto 12, "
            "design.max_print_deviation_rel)"
        )
    return warnings


def _joint_box_warnings(doc: Document, geometry: SensorGeometry) -> list[str]:
    """One line when the closed form's plate joints (model.plate_joint) serve a layer outside the
    cells they were fitted on: up to 22 % soft there (docs/design.md 4.7, "The low corner")."""
    if doc.load_path != "part":  # the layers alone have no joints; the section rung measures them
        return []
    cells = geometry.layers
    theta, t, h = ([getattr(c, k) for c in cells] for k in ("theta_deg", "t_mm", "h_mm"))
    out = outside_fitted_box(theta, t, h, geometry.housing.plate_mm)
    if not out:
        return []
    named = " and ".join(f"{i + 1} (θ {theta[i]:.3g}°, t {t[i]:.3g} mm, h {h[i]:.3g} mm)" for i in out)
    (th0, th1), (t0, t1), (h0, h1), (p0, p1) = (FITTED_BOX[k] for k in ("theta_deg", "t_mm", "h_mm", "plate_mm"))
    return [
        f"{'layers' if len(out) > 1 else 'layer'} {named} on {geometry.housing.plate_mm:g} mm plates: outside the "
        f"cells the plate joints were fitted on (θ {th0:g}–{th1:g}°, t {t0:g}–{t1:g} mm, h {h0:g}–{h1:g} mm, "
        f"plates {p0:g}–{p1:g} mm); at h 1.2-1.5 mm they are up to {100 * LOW_CORNER_WORST_REL:.0f} % soft on "
        'the layers and plates (docs/design.md 4.7, "The low corner"): check the part with mst check --whole-part '
        "before printing, or design with model.load_path: section"
    ]


def _objective(doc: Document, geometry: SensorGeometry, resp: Response, print_error: dict) -> dict:
    """report.json's ``objective``: design.objective's weights and the three terms' values."""
    weights = doc.design.get("objective") or {}
    return {
        "weights": dict(weights),
        "meaning": "among the designs that meet every target, the one with the lowest weighted sum of "
        "ln(total_height_mm), ln(worst_force_resolution_N) and print_robustness_rms",
        "total_height_mm": geometry.total_height_mm,
        "worst_force_resolution_N": max(r.force_resolution_N for r in resp.regimes),
        "print_robustness_rms": print_error["rms_log_change"],
    }


def _solver_info(sol: SolverFacts) -> dict:
    """report.json's ``solver``: the method, whether it matched, the starts and the preference."""
    return {
        "method": "layer-by-layer start + Gauss-Newton match, nlopt "
        f"{'LD' if sol.local == 'slsqp' else 'LN'}_{sol.local.upper()} preference polish and "
        "re-match (seeded multi-start if the start fails)",
        "matched": sol.matched,
        "starts_used": sol.starts_used,
        "preference_before": sol.preference_before,
        "preference_after": sol.preference_after,
        "runs_ended": sol.stops,
    }
