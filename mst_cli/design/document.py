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
from dataclasses import replace

import numpy as np

from mst_cli.design import explain
from mst_cli.design.problem import DesignProblem
from mst_cli.design.result import ROUND_DECIMALS, DesignResult, design_dict
from mst_cli.design.solver import solve
from mst_cli.design.verify import verify_design, with_cells
from mst_cli.errors import InputError
from mst_cli.sensor.as_printed import simulate_as_printed
from mst_cli.sensor.document import Document

# model.load_path section (:func:`_solve_spec`): at most this many designs corrected by the
# whole-part rung, until the correction moves no regime's compliance by more than this share
SECTION_ROUNDS = 3
SECTION_TOL_REL = 0.01
# ... each corrected design within this of the best measured, in the solver's unit coordinates
# (theta linear, t and h logarithmic between their bounds): 0.15 is 10.5 deg, or t times or over 1.35 on 0.4-3 mm
TRUST_RADIUS = 0.15


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

    sol, rounds = _solve_spec(doc, problem, seed, max_evaluations, progress, local)
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
    result.notes += rounds
    if name_height and result.status != "met" and problem.max_print_deviation_rel is not None:
        _name_lowest_height(doc, result, seed=seed, max_evaluations=max_evaluations, local=local)
    if solution is not None:
        solution.append(sol)
    return result


def _solve_spec(doc, problem: DesignProblem, seed: int, max_evaluations: int, progress, local: str) -> tuple:
    """The solver's design of the spec; with model.load_path section, the design's closed form
    corrected by the whole-part rung until the two agree (output space mapping in a trust region).

    Each round measures the rung's correction per regime on a design as printed
    (:func:`~mst_cli.model.mechanics.whole_part.section_members`, 2 solves a regime), then designs
    again with it held, every variable within TRUST_RADIUS (in the solver's unit coordinates) of
    the best design measured so far: the correction moves with the walls, and it holds only near
    where it was measured. A design measured nearer the targets than the best becomes the best;
    one further off halves the radius. The rounds stop once the correction measured on the new
    design moves the part's compliance in every regime by less than SECTION_TOL_REL from the one
    it was designed with, or after SECTION_ROUNDS corrected designs. The best design is returned,
    its correction held for the diagnosis. The forward model that verifies it (:func:`verify_design`)
    measures the rung there once more (the same section: its solves are memoised). Returns
    (the design, the terminal's notes: with section, one line of each design's worst error as
    measured and which was kept)."""
    sol = solve(problem, seed=seed, max_evaluations=max_evaluations, progress=progress, local=local)
    if not doc.section_rung:
        return sol, []
    best: tuple = (math.inf, sol, None, 0)  # (worst log error as measured, design, its correction, which)
    held, radius, measured = None, TRUST_RADIUS, []
    for round_ in range(SECTION_ROUNDS + 1):
        theta, t, h = (np.round(a, ROUND_DECIMALS) for a in problem.to_physical(sol.u))
        if progress is not None:
            progress(round_, SECTION_ROUNDS + 1, f"the whole-part rung on design {round_ + 1}", float("nan"))
        resp = simulate_as_printed(with_cells(doc, theta, t, h), "spring")
        extra = np.asarray(resp.members.regime_extra_mm_per_N, dtype=float)
        compliance = np.array([1.0 / r.k_effective_N_per_mm for r in resp.regimes])
        error = _worst_log_error(problem, resp)
        measured.append(f"{100 * math.expm1(error):.3g} %")
        if error < best[0]:
            best = (error, sol, extra, round_ + 1)
        else:
            radius *= 0.5
        if held is not None and len(held) == len(extra) and np.max(np.abs(extra - held) / compliance) < SECTION_TOL_REL:
            break
        if round_ == SECTION_ROUNDS:
            break
        problem.regime_extra_mm_per_N = held = best[2]
        problem.trust_region = (np.asarray(best[1].u, dtype=float), radius)
        sol = solve(problem, seed=seed, max_evaluations=max_evaluations, progress=progress, local=local)
        problem.trust_region = None
    _, sol, problem.regime_extra_mm_per_N, kept = best
    note = (
        "the whole-part rung (model.load_path: section): the designs' worst error as measured, "
        f"{', '.join(measured)} (the first the closed form's); kept design {kept} (docs/design.md 4.7)"
    )
    return sol, [note]


def _worst_log_error(problem: DesignProblem, resp) -> float:
    """max |log(achieved / target)| over the regimes' S and R of a forward model (inf when its
    regimes are not the targets' or a figure is not positive)."""
    S = np.array([r.sensitivity_secant_per_N for r in resp.regimes], dtype=float)
    R = np.array(resp.lock_forces_N, dtype=float)
    if S.shape != problem.S_target.shape or R.shape != problem.R_target.shape or np.any(S <= 0) or np.any(R <= 0):
        return math.inf
    return float(np.max(np.abs(np.log(np.concatenate([S / problem.S_target, R / problem.R_target])))))


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


__all__ = ["DesignResult", "design_document", "design_dict", "verify_design", "DesignProblem"]
