"""One ``mst design`` run as an object: the spec as used (an earlier print's calibration applied),
the rung the design is judged by, the design (and the Pareto front, when one is mapped), the
files it writes and what the terminal shows. :func:`mst_cli.api.run_design` builds it."""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import TYPE_CHECKING

from mst_cli.design.document import design_document
from mst_cli.design.files import write_design_files
from mst_cli.design.result import DesignResult
from mst_cli.errors import InputError
from mst_cli.model.ladder import MechanicsChoice, choose_mechanics
from mst_cli.sensor.document import Document

if TYPE_CHECKING:
    from mst_cli.calibration.calibration_json import PrinterCalibration
    from mst_cli.design.pareto import ParetoDesign


def design_choice(doc: Document, refine: str | None, pareto_count: int | None) -> MechanicsChoice:
    """The rung the design is judged by; a Pareto front (mapped with L0) refuses a dearer one."""
    choice = choose_mechanics(refine, doc.accuracy_rel, doc.mechanics)
    if pareto_count is not None and choice.mechanics != "spring":
        raise InputError(
            "--pareto",
            pareto_count,
            f"maps the front with the L0 spring model; drop "
            f"--refine/model.accuracy_rel (asked for {choice.mechanics}) or refine one "
            f"front design afterwards with --pareto-designs and mst design --refine",
        )
    return choice


@dataclass
class DesignRun:
    """A spec designed as ``mst design`` designs it."""

    spec: Document  # calibration applied
    choice: MechanicsChoice
    calibration: PrinterCalibration | None = None
    pareto_count: int | None = None
    result: DesignResult | None = None
    front: list[ParetoDesign] | None = None
    report: dict | None = field(default=None, repr=False)  # report.json, once written

    def choice_lines(self) -> list[str]:
        """The mechanics rung picked (and that the L0 design is refined with it), the calibration taken."""
        lines = []
        message = self.choice.message()
        if message:
            refined = "" if self.choice.mechanics == "spring" else f": L0 design refined with {self.choice.mechanics}"
            lines.append(message + refined)
        if self.calibration is not None:
            lines += self.calibration.lines()
        return lines

    def solve(self, seed: int | None, max_evaluations: int | None, progress: Callable | None) -> DesignResult:
        """The design (and, with ``pareto_count``, the front), kept as ``.result`` / ``.front``."""
        if self.pareto_count is not None:
            from mst_cli.design.pareto import pareto_front  # deferred: --pareto's layer, 8 ms with refine's

            self.result, self.front = pareto_front(
                replace(self.spec, mechanics="spring"),
                self.pareto_count,
                seed=seed,
                max_evaluations=max_evaluations,
                progress=progress,
            )
            return self.result
        if self.choice.mechanics == "spring":
            result = design_document(
                replace(self.spec, mechanics="spring"), seed=seed, max_evaluations=max_evaluations, progress=progress
            )
        else:
            from mst_cli.design.refine import refine_document  # deferred: --refine's layer

            result = refine_document(
                self.spec, self.choice.mechanics, seed=seed, max_evaluations=max_evaluations, progress=progress
            )
        self.result = with_shear_bound(with_offcentre_figure(result, self.spec.design.get("offcentre_region_mm")))
        return self.result

    def write(self, out: Path, pareto_designs: bool = False, plot: bool = True) -> dict:
        """design.yaml, report.json, response.csv/png and the front's files into ``out``,
        atomically; returns the report (also kept as ``.report``)."""
        assert self.result is not None  # solved before written
        self.report = write_design_files(
            self.result, self.front, self.calibration, out, self.pareto_count, pareto_designs, plot, self.spec.name
        )
        return self.report

    def summary(self, out: Path, pareto_designs: bool, plot: bool, seconds: float) -> str:
        """The design table, the front's table (if mapped) and the files written."""
        assert self.result is not None  # solved before shown
        lines = [self.result.table()]
        front = self.front
        if front:
            from mst_cli.design.pareto import front_table  # deferred: as pareto_front

            lines.append(front_table(front))
        elif self.pareto_count is not None:
            lines.append("Pareto front: not mapped (the targets are not met)")
        files = (
            "design.yaml, report.json, response.csv"
            + (", response.png" if plot else "")
            + (", pareto.csv" + (", pareto.png" if plot else "") if front else "")
            + (f", pareto/ ({len(front)} designs)" if front and pareto_designs else "")
        )
        lines.append(f"wrote {out}/{files} ({seconds:.2f} s)")
        return "\n".join(lines)


def with_offcentre_figure(result: DesignResult, region: Sequence[float] | None) -> DesignResult:
    """``result`` with design.offcentre_region_mm's figure filled in (when the spec sets one)."""
    if region is not None:
        # deferred: the off-centre model (its tilt laws and poses, 5 ms of a quick design's start)
        from mst_cli.model.offcentre import offset_map, worst_read_errors
        from mst_cli.simulation.run import printed_scene

        mech = result.response.mechanics
        scene = printed_scene(result.document, mech, None)
        doc = result.document
        omap = offset_map(
            scene.geometry,
            scene.material,
            scene.mechanics,
            scene.field_model,
            region_mm=(region[0], region[1]),
            whole_part=doc.whole_part,
            section=doc.section_rung,
        )
        result.off_centre = worst_read_errors(omap) | {"mechanics": mech}
    return result


def with_shear_bound(result: DesignResult) -> DesignResult:
    """``result`` with a pointer to what its chips tell apart when the spec places two or more
    (magnetometer.positions_mm): the Cramer-Rao bound over the face takes a general-load solve
    per press and chip (16 s on a two-chip spec, against 0.6 s for the whole design), so the
    design loop leaves it to ``mst simulate design.yaml --shear-ratio 0.2,0.1``, which states it
    for the same layout."""
    doc = result.document
    if len(doc.chips_mm) > 1:
        from mst_cli.model.load_bound import DESIGN_SHEAR_RATIO  # deferred: the general load's model, as above

        rx, ry = DESIGN_SHEAR_RATIO
        result.notes.append(
            f"{len(doc.chips_mm)} chips: what they tell apart (each estimate's Cramer-Rao bound over the face) "
            f"is stated by mst simulate design.yaml --shear-ratio {rx:g},{ry:g}, off the design loop"
        )
    return result
