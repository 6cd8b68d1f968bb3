"""What ``mst design`` found: :class:`DesignResult` (the design, its achieved numbers, the checks
and the exit status) and the constants its judgement uses. Pure: no I/O."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Protocol

import numpy as np

from mst_cli.model.assembly import SensorGeometry
from mst_cli.model.response import Response
from mst_cli.sensor.document import Document, document_to_dict
from mst_cli.simulation.report import height_budget_line, load_path_line

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
    shear_bound: dict | None = None  # two chips or more: what the layout tells apart (when computed)
    notes: list[str] = field(default_factory=list)  # lines the terminal shows before the warnings

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
                "warnings": list(self.warnings),  # the design's own, as the terminal shows them
            }
            | ({"off_centre": self.off_centre} if self.off_centre is not None else {})
            | ({"shear_bound": self.shear_bound} if self.shear_bound is not None else {})
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
        lines.append(load_path_line(self.document, g, resp))
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
        if self.shear_bound is not None:
            from mst_cli.model.load_bound import shear_bound_lines  # deferred: the general load's model, 5 ms

            lines += shear_bound_lines(self.shear_bound)
        lines += self.notes
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
