"""One ``mst simulate`` run as an object: the design, the rung it was simulated with, the
response (and the off-centre press or offset map asked for), the files it writes and the lines
the terminal shows. :func:`mst_cli.api.simulate` and its siblings build it; the command prints it.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

from mst_cli.errors import InputError
from mst_cli.model.assembly import SensorGeometry
from mst_cli.model.ladder import MechanicsChoice, choose_mechanics
from mst_cli.model.load_bound import shear_bound_lines
from mst_cli.model.load_path import FINGERTIP_PATCH_MM
from mst_cli.model.material import Material
from mst_cli.model.offcentre import OffCentreResponse, OffsetMap
from mst_cli.model.response import Response
from mst_cli.sensor.as_printed import PRINTER_NOMINAL, as_printed
from mst_cli.sensor.document import Document
from mst_cli.simulation.offcentre_files import offcentre_lines, offcentre_summary, write_offcentre
from mst_cli.simulation.report import load_path_section, terminal_table, write_simulation


@dataclass(frozen=True)
class PrintedScene:
    """What the off-centre models run on: the part as printed, its rung and field model."""

    geometry: SensorGeometry  # as printed
    material: Material  # as printed
    mechanics: str
    field_model: str | None  # None: auto


def printed_scene(doc: Document, mechanics: str | None, field_model: str | None) -> PrintedScene:
    """The part as printed, the mechanics rung as ``mst simulate`` picks it and the field model
    (InputError for the dipole, which is not exact off the axis)."""
    printed = as_printed(doc)
    choice = field_model or doc.field_model
    if choice == "dipole":
        raise InputError("--field-model", choice, "must be exact off the axis: axial, cylinder or auto")
    mech = choose_mechanics(mechanics, doc.accuracy_rel, doc.mechanics).mechanics
    return PrintedScene(printed.geometry(), printed.material, mech, None if choice == "auto" else choice)


def check_on_top_face(geometry: SensorGeometry, offset_mm: tuple[float, float]) -> None:
    """InputError unless (x0, y0) lies on the top face, |x0| <= W/2 and |y0| <= D/2."""
    half_w, half_d = 0.5 * geometry.width_mm, 0.5 * geometry.depth_mm
    x0, y0 = offset_mm
    if not (abs(x0) <= half_w and abs(y0) <= half_d):
        raise InputError(
            "--load-offset-mm",
            f"{x0:g},{y0:g}",
            f"must lie on the top face: |x| <= {half_w:g} mm, |y| <= {half_d:g} mm",
        )


@dataclass
class Simulation:
    """A design's forward model as ``mst simulate`` runs it, and what it writes and prints."""

    document: Document
    geometry: SensorGeometry  # as drawn (the report's geometry section)
    choice: MechanicsChoice
    press_width_mm: float = FINGERTIP_PATCH_MM  # the press's contact patch (report.json's load_path)
    response: Response | None = None
    off_centre: OffCentreResponse | None = None
    offset_map: OffsetMap | None = None
    shear_bound: dict | None = None  # report.json's shear_bound (LayoutBound.summary), with --shear-ratio
    report: dict | None = field(default=None, repr=False)  # report.json, once written

    def __post_init__(self):
        face = self.geometry.width_mm
        if not 0.0 < self.press_width_mm <= face:  # nan fails too: refused before any work
            raise InputError(
                "--press-width-mm", self.press_width_mm, f"must be a width above 0 and up to the face's {face:g} mm"
            )

    def model_lines(self) -> list[str]:
        """The mechanics rung picked for the file, and the print parameters that differ from nominal."""
        message = self.choice.message()
        lines = [message] if message else []
        pr = self.document.printer
        deviations = {key: getattr(pr, key) for key in PRINTER_NOMINAL if getattr(pr, key) != PRINTER_NOMINAL[key]}
        if deviations:
            lines.append(
                "as printed: "
                + ", ".join(f"printer.{k} = {v:g}" for k, v in deviations.items())
                + " (the walls drawn are the file's t_mm)"
            )
        return lines

    def off_centre_summary(self) -> dict | None:
        """report.json's off_centre section (None without an off-centre press)."""
        return None if self.off_centre is None else offcentre_summary(self.off_centre)

    def write(self, out: Path, plot: bool = True) -> dict:
        """report.json, response.csv, response.png (``plot``) and the off-centre files asked for
        into ``out``, atomically (files of an older run that this one does not write are removed);
        returns the report (also kept as ``.report``)."""
        assert self.response is not None  # simulated before written
        extra: dict = {"as_printed": {f"printer.{k}": getattr(self.document.printer, k) for k in PRINTER_NOMINAL}}
        summary = self.off_centre_summary()
        if summary is not None:
            extra["off_centre"] = summary
        if self.shear_bound is not None:
            extra["shear_bound"] = self.shear_bound
        if self.press_width_mm != FINGERTIP_PATCH_MM:
            extra["load_path"] = load_path_section(self.document, self.geometry, self.response, self.press_width_mm)
        self.report = write_simulation(
            self.document,
            self.geometry,
            self.response,
            out,
            plot=plot,
            extra_report=extra,
            more=lambda st: write_offcentre(st, self.off_centre, self.offset_map, plot),
        )
        return self.report

    def table(self) -> str:
        """The terminal's per-regime table (and the off-centre lines)."""
        assert self.response is not None  # simulated before shown
        lines = [terminal_table(self.document, self.geometry, self.response, self.press_width_mm)]
        summary = self.off_centre_summary()
        if summary is not None:
            lines += offcentre_lines(summary)
        if self.shear_bound is not None:
            lines += shear_bound_lines(self.shear_bound)
        return "\n".join(lines)

    def file_names(self, plot: bool = True) -> list[str]:
        """The files :meth:`write` writes, in the order the command names them."""
        names = ["report.json", "response.csv"] + (["response.png"] if plot else [])
        for stem, present in (("offcentre", self.off_centre), ("offset_map", self.offset_map)):
            names += [f"{stem}.csv"] + ([f"{stem}.png"] if plot else []) if present is not None else []
        return names
