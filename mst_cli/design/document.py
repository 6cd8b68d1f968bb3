"""Inverse design: from target sensitivities S_i and lock forces R_i to theta, t, h per layer.

:func:`design_document` is the library entry point of ``mst design``:

1. :func:`explain.check_contradictions` rejects a self-contradictory spec (InputError, exit 2);
2. :func:`solver.solve` searches the normalised variables (vectorised problem, nlopt);
3. the result is rounded to ROUND_DECIMALS (0.1 um, 1e-4 deg: far below what a printer
   resolves, and inside the optimiser's rounding slack so every rule still holds), written
   into a copy of the spec (targets kept), and **re-simulated with the forward model**
   (:func:`mst_cli.model.response.simulate`): every achieved number reported comes from that run;
4. the verification decides the status: every target within tolerance and every constraint
   held -> exit 0; otherwise exit 1 with the binding reason (:func:`explain.diagnose`).

The design is judged as printed: the written design.yaml keeps the walls as drawn (what
``mst export`` draws) and its ``printer`` section says how they print; every simulation here
runs :func:`mst_cli.sensor.as_printed.as_printed` of it (walls + printer.wall_offset_mm, modulus x
printer.modulus_factor, gap + printer.gap_offset_mm).

The print-error sensitivity (the robustness term of the preference, :mod:`.problem`) is re-measured the same
way: the forward model on the printed design with every wall printer.wall_tolerance_mm thicker and
thinner (with L0 when a refined design does not ask for more:
:func:`mst_cli.design.refine.print_error_rung`); report.json names the rung
(``print_error_sensitivity.mechanics``) and gives the RMS and the worst relative change.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable
from dataclasses import dataclass, field, replace
from typing import Protocol

import numpy as np
from numpy.typing import ArrayLike

from mst_cli.design import explain
from mst_cli.design.problem import DesignProblem
from mst_cli.design.solver import solve
from mst_cli.errors import InputError
from mst_cli.model.assembly import SensorGeometry
from mst_cli.model.printer import Printer
from mst_cli.model.response import Response, simulate
from mst_cli.sensor.as_printed import as_printed
from mst_cli.sensor.document import Document, document_to_dict
from mst_cli.sensor.sections import LayerEntry
from mst_cli.simulation.report import height_budget_line

ROUND_DECIMALS = 4
EXIT_MET, EXIT_NOT_MET = 0, 1
SAME_RUNG_RULE = "the rung that judges the design"  # print error's rung when the caller names none
WARN_PRINT_DEVIATION_REL = 0.25  # above this worst change a design without a limit says so
PRINT_DEVIATION_CHECK = "print deviation"  # the check design.max_print_deviation_rel fails


class SolverFacts(Protocol):
    """What :func:`verify_design` reports of the search that found a design: a
    :class:`~mst_cli.design.solver.SolveResult`, or the facts a refinement gathers of its own."""

    @property
    def matched(self) -> bool: ...
    @property
    def evaluations(self) -> int: ...
    @property
    def local(self) -> str: ...
    @property
    def starts_used(self) -> int: ...
    @property
    def preference_before(self) -> float | None: ...
    @property
    def preference_after(self) -> float | None: ...
    @property
    def stops(self) -> list | dict: ...


@dataclass
class DesignResult:
    """A designed document, its forward-model response and the diagnostics."""

    document: Document
    geometry: SensorGeometry
    response: Response
    status: str  # "met" or "not met"
    binding: str | None  # what binds when not met
    reasons: list[str]
    targets: list[dict]  # per layer: target vs achieved (forward model)
    checks: dict  # failed constraint name -> message (empty when all hold)
    print_error: dict  # print robustness per layer (forward model)
    seed: int
    evaluations: int
    max_evaluations: int
    solver: dict
    elapsed_s: float = 0.0
    warnings: list[str] = field(default_factory=list)
    objective: dict = field(default_factory=dict)  # design.objective's weights and terms
    off_centre: dict | None = None  # design.offcentre_region_mm's figure (api.design fills it)

    @property
    def exit_code(self) -> int:
        return EXIT_MET if self.status == "met" else EXIT_NOT_MET

    def design_yaml_dict(self) -> dict:
        """design.yaml: the spec with theta, t, h filled in (loadable by ``mst simulate``)."""
        return design_dict(self.document)

    def report_extra(self) -> dict:
        """The ``design`` block of report.json (reproducible: no wall-clock numbers)."""
        return {
            "design": {
                "status": self.status,
                "exit_code": self.exit_code,
                "binding": self.binding,
                "reasons": self.reasons,
                "tolerance_rel": self.document.design["tolerance_rel"],
                "targets": self.targets,
                "constraints_failed": self.checks,
                "print_error_sensitivity": self.print_error,
                "objective": self.objective,
                "seed": self.seed,
                "evaluations": self.evaluations,
                "max_evaluations": self.max_evaluations,
                "solver": self.solver,
            }
            | ({"off_centre": self.off_centre} if self.off_centre is not None else {})
        }

    def table(self) -> str:
        """Target against achieved per layer (forward model), as ``mst design`` prints it."""
        tol = self.document.design["tolerance_rel"]
        pe = self.print_error
        shift = f"t+-{pe['print_error_t_mm']:g}mm: dS"
        lines = [
            f"{self.document.name}: {len(self.targets)} layers designed, tolerance "
            f"{100 * tol:g} %, seed {self.seed}, {self.evaluations} evaluations",
            f"{'layer':>5} {'theta':>7} {'t':>6} {'h':>6} | {'S target':>8} {'S got':>8} {'err':>6} | "
            f"{'R target':>8} {'R got':>8} {'err':>6} | {shift:>13} {'dR':>6}",
            f"{'':>5} {'[deg]':>7} {'[mm]':>6} {'[mm]':>6} | {'[1/N]':>8} {'[1/N]':>8} {'[%]':>6} | "
            f"{'[N]':>8} {'[N]':>8} {'[%]':>6} | {'[%]':>13} {'[%]':>6}",
        ]
        for row, pl in zip(self.targets, self.print_error["layers"]):
            ok = "" if row["within_tolerance"] else "  <-- missed"
            lines.append(
                f"{row['layer']:>5} {row['theta_deg']:>7.2f} {row['t_mm']:>6.3f} {row['h_mm']:>6.3f} | "
                f"{row['target_sensitivity_per_N']:>8.4g} {row['achieved_sensitivity_per_N']:>8.4g} "
                f"{100 * row['sensitivity_error_rel']:>+6.2f} | "
                f"{row['target_range_N']:>8.4g} {row['achieved_range_N']:>8.4g} "
                f"{100 * row['range_error_rel']:>+6.2f} | "
                f"{100 * pl['dS_rel_worst']:>13.1f} {100 * pl['dR_rel_worst']:>6.1f}{ok}"
            )
        lines += self._table_footer()
        return "\n".join(lines)

    def _table_footer(self) -> list[str]:
        """The lines under the table: field and gap, height, print sensitivity, the verdict."""
        tol = self.document.design["tolerance_rel"]
        lines: list[str] = []
        resp, g = self.response, self.geometry
        lines.append(
            f"gap {resp.gap0_mm:.2f} -> {resp.gap_min_mm:.2f} mm, B0 {resp.B0_T * 1e3:.3f} mT, "
            f"B full load {resp.B_full_T * 1e3:.3f} mT, worst force resolution "
            f"{1e3 * max(r.force_resolution_N for r in resp.regimes):.1f} mN"
        )
        lines.append(height_budget_line(g))
        pe = self.print_error
        limit = pe.get("max_print_deviation_rel")
        lines.append(
            f"print: walls +-{pe['print_error_t_mm']:g} mm change S_i, R_i by "
            f"{100 * pe['worst_change_rel']:.1f} % at worst, {100 * pe['rms_log_change']:.1f} % RMS"
            + (f" (limit {100 * limit:g} %)" if limit is not None else "")
        )
        pr = self.document.printer
        if (pr.wall_offset_mm, pr.modulus_factor, pr.gap_offset_mm) != (0.0, 1.0, 0.0):
            lines.append(
                f"designed as printed: walls print {pr.wall_offset_mm:+.4f} mm off the t above (drawn), "
                f"modulus x {pr.modulus_factor:.4f}, gap {pr.gap_offset_mm:+.4f} mm (design.yaml's printer "
                "section)"
            )
        pe_mechanics = self.print_error.get("mechanics", resp.mechanics)
        if pe_mechanics != resp.mechanics or self.print_error.get("mechanics_rule") != SAME_RUNG_RULE:
            lines.append(
                f"print error (t+-{self.print_error['print_error_t_mm']:g} mm columns) measured with "
                f"mechanics={pe_mechanics}: {self.print_error['mechanics_rule']}"
            )
        if self.status == "met":
            lines.append(
                f"all {2 * len(self.targets)} targets met within {100 * tol:g} % "
                f"(forward model, mechanics={resp.mechanics}, field={resp.field_model})"
            )
        else:
            lines.append(f"NOT MET -- binding: {self.binding}")
            lines += [f"  - {r}" for r in self.reasons]
        if self.off_centre is not None:
            oc = self.off_centre
            x, y = oc["region_mm"]
            lines.append(
                f"off centre: a touch within +-{x:g} x +-{y:g} mm read as axial is off by "
                + ", ".join(f"{100 * abs(r['worst_read_error_rel']):.1f} %" for r in oc["regimes"])
                + " at worst in the regimes (design.offcentre_region_mm; mst read --estimate-offset corrects it)"
            )
        for w in self.warnings:
            lines.append(f"warning: {w}")
        return lines


def design_dict(doc: Document) -> dict:
    """document_to_dict plus the spec's ``design`` section, so the file can be designed again."""
    out = document_to_dict(doc)
    d = {}
    for key, value in doc.design.items():
        d[key] = list(value) if isinstance(value, tuple) else value
    layers = out.pop("layers")
    out["design"] = d
    out["layers"] = layers
    return out


def _layer_outputs(resp: Response, n: int):
    """(S per regime, R per layer in file order) from a forward-model response."""
    S = np.array([r.sensitivity_secant_per_N for r in resp.regimes])
    R = np.zeros(n)
    for r in resp.regimes:
        R[r.layer - 1] = r.force_to_N
    return S, R


def design_document(
    doc: Document,
    *,
    seed: int | None = None,
    progress: Callable | None = None,
    max_evaluations: int | None = None,
    local: str = "slsqp",
    solution: list | None = None,
    name_height: bool = True,
) -> DesignResult:
    """Design theta, t, h for every layer of the spec ``doc``.

    Parameters
    ----------
    doc : Document
        A spec (every layer has target_sensitivity_per_N and target_range_N).
    seed : int, optional
        Seeds the multi-start screening, should the match need it [default: design.seed of
        the file]. Same spec and seed give the same design.
    progress : callable, optional
        ``progress(evaluations_done, max_evaluations, phase, worst_error_rel)``.
    max_evaluations : int, optional
        Budget of candidate evaluations [default: design.max_evaluations of the file].
    solution : list, optional
        Receives the solver's :class:`~mst_cli.design.solver.SolveResult` (its matched point
        is where :func:`mst_cli.design.pareto.pareto_front` starts every other weighting).
    name_height : bool
        When design.max_print_deviation_rel is what fails, design again to name the lowest part
        height at which it is met (:func:`_name_lowest_height`) [default: True].

    Raises
    ------
    InputError
        Not a spec, or a spec that contradicts itself (exit code 2).
    """
    t_start = time.perf_counter()
    problem = _spec_problem(doc)
    seed = int(doc.design["seed"] if seed is None else seed)
    max_evaluations = int(doc.design["max_evaluations"] if max_evaluations is None else max_evaluations)

    sol = solve(problem, seed=seed, max_evaluations=max_evaluations, progress=progress, local=local)
    theta, t, h = (np.round(a, ROUND_DECIMALS) for a in problem.to_physical(sol.u))
    result = verify_design(
        doc,
        problem,
        theta,
        t,
        h,
        sol,
        seed=seed,
        max_evaluations=max_evaluations,
        mechanics=doc.mechanics,
        t_start=t_start,
    )
    if name_height and result.status != "met" and problem.max_print_deviation_rel is not None:
        _name_lowest_height(doc, result, seed=seed, max_evaluations=max_evaluations, local=local)
    if solution is not None:
        solution.append(sol)
    return result


def _spec_problem(doc: Document) -> DesignProblem:
    """The L0 design problem of the spec ``doc``; InputError when it is not a spec for the spring
    rung or contradicts itself."""
    doc.require_targets()
    if doc.mechanics != "spring":
        raise InputError(
            "model.mechanics",
            doc.mechanics,
            "design_document optimises with the L0 'spring' model: set model.mechanics: "
            "spring, or refine for a dearer rung (mst design --refine frame|continuum, "
            "mst_cli.design.refine.refine_document)",
        )
    problem = DesignProblem(doc)
    explain.check_contradictions(problem)
    return problem


HEIGHT_ONLY = {"height": 1.0, "force_resolution": 0.0, "print_robustness": 0.0}
ROBUSTNESS_ONLY = {"height": 0.0, "force_resolution": 0.0, "print_robustness": 1.0}


def _name_lowest_height(doc: Document, result: DesignResult, **run) -> None:
    """Make design.max_print_deviation_rel the binding reason of ``result`` when it is what keeps
    the spec from being met, naming the lowest part height at which it is met (or that none is).

    It binds when the same spec without the limit is met. The lowest height is the design of
    the spec with the limit, no height limit and the height as the only preference; when that
    misses too, the most robust design the search finds (no limit, robustness the only
    preference) says how close any height comes.
    """
    limit = doc.design["max_print_deviation_rel"]

    def variant(**design):
        return design_document(replace(doc, design={**doc.design, **design}), name_height=False, **run)

    if variant(max_print_deviation_rel=None).status != "met":
        return  # something else binds as well
    lowest = variant(max_height_mm=None, objective=HEIGHT_ONLY)
    tol_mm = doc.printer.wall_tolerance_mm
    if lowest.status == "met":
        height = lowest.geometry.total_height_mm
        reason = (
            f"design.max_print_deviation_rel = {100 * limit:g} % (walls ± {tol_mm:g} mm) is met from a total "
            f"height of {height:.2f} mm (the lowest design found with it"
            + (
                f"; design.max_height_mm is {doc.design['max_height_mm']:g} mm"
                if doc.design.get("max_height_mm") is not None
                else ""
            )
            + f"): allow {height:.2f} mm or more, or relax the limit"
        )
    else:
        best = variant(max_print_deviation_rel=None, max_height_mm=None, objective=ROBUSTNESS_ONLY)
        reason = (
            f"no height meets design.max_print_deviation_rel = {100 * limit:g} % (walls ± {tol_mm:g} mm) "
            f"inside the design bounds: the least print-sensitive design found ("
            f"{best.geometry.total_height_mm:.2f} mm) still changes some S_i or R_i by "
            f"{100 * best.print_error['worst_change_rel']:.1f} %; relax the limit, or calibrate the printer "
            "(--calibration) so that a smaller printer.wall_tolerance_mm holds"
        )
    result.binding = "design.max_print_deviation_rel"
    result.reasons.insert(0, reason)


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
    designed = _with_cells(doc, theta, t, h)
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
        warnings=_warnings(resp, print_error),
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


def _with_cells(doc: Document, theta: np.ndarray, t: np.ndarray, h: np.ndarray) -> Document:
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


__all__ = ["DesignResult", "design_document", "design_dict", "verify_design", "DesignProblem"]
