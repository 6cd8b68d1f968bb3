"""The part as printed: what a printer does to a drawing, and the one path from a design to the
part whose physics is simulated, for design, calibration, export and slicing alike.

Print parameters (:data:`PARAMETERS`), each with the scale of a typical print or assembly
deviation (the unit the calibration's fit and its identifiability test work in):

* ``modulus_factor``   effective Young's modulus / the design's;
* ``wall_offset_mm``   added to every layer's wall thickness t;
* ``gap_offset_mm``    added to the unloaded magnet-to-chip gap;
* ``remanence_factor`` the magnet's remanence / the design's.

:func:`apply_parameters` writes values of them into the document's own keys (a file ``mst
simulate`` loads with the same rules and model); :func:`as_printed` applies the deviations a
document's ``printer`` section declares; :func:`with_walls` sets the walls a slicer lays down.
Pure: no file or terminal I/O.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, replace
from typing import TYPE_CHECKING

from mst_cli.model.assembly import Housing
from mst_cli.model.cell import inner_pad_half_width_mm
from mst_cli.model.ladder import choose_mechanics
from mst_cli.model.printer import Printer
from mst_cli.model.response import Response
from mst_cli.model.response import simulate as run_simulation
from mst_cli.sensor.document import Document
from mst_cli.sensor.sections import LayerEntry

if TYPE_CHECKING:
    pass

from mst_cli.errors import CalibrationFailed

# the record of a fitted print beside its calibrated.yaml: mst calibrate writes it, mst read
# trusts the model by it and the readers' tables are keyed by it
CALIBRATION_JSON = "calibration.json"


@dataclass(frozen=True)
class Parameter:
    name: str
    unit: str
    nominal: float
    scale: float  # a typical print/assembly deviation: the fit's unit of this parameter
    description: str


PARAMETERS: dict[str, Parameter] = {
    p.name: p
    for p in (
        Parameter(
            "modulus_factor",
            "",
            1.0,
            0.10,
            "effective Young's modulus / the design's (scales every layer's k, R, k_locked)",
        ),
        Parameter(
            "wall_offset_mm", "mm", 0.0, 0.05, "added to every layer's wall thickness t (changes k, R and d_lock)"
        ),
        Parameter("gap_offset_mm", "mm", 0.0, 0.30, "added to the unloaded magnet-to-chip gap"),
        Parameter("remanence_factor", "", 1.0, 0.05, "magnet remanence / the design's"),
    )
}


# the printer keys that say how a print misses its drawing, at "no miss" (model.printer.Printer)
PRINTER_NOMINAL = {"wall_offset_mm": 0.0, "modulus_factor": 1.0, "gap_offset_mm": 0.0}


def printer_values(doc: Document) -> dict:
    """The print parameters (:data:`PARAMETERS`' names) a document's ``printer`` section declares:
    what its printer is known to do to the drawing (the remanence is the magnet's own key)."""
    pr = doc.printer
    return {
        "modulus_factor": pr.modulus_factor,
        "wall_offset_mm": pr.wall_offset_mm,
        "gap_offset_mm": pr.gap_offset_mm,
        "remanence_factor": 1.0,
    }


def as_printed(doc: Document, extra_wall_mm: float = 0.0) -> Document:
    """The design ``doc`` as its printer makes it (walls + offset + ``extra_wall_mm``, modulus and
    gap as the ``printer`` section says), through :func:`apply_parameters`: the one path from a
    drawing to the part whose physics is simulated, for design and calibration alike."""
    values = printer_values(doc)  # within bounds: geometry.printer_violations at parse time
    values["wall_offset_mm"] += extra_wall_mm
    return apply_parameters(doc, values)[0]


def simulate_as_printed(doc: Document, mechanics: str | None = None, field_model: str | None = None) -> Response:
    """The forward model of a valid design as ``mst simulate`` runs it (:func:`mst_cli.api.simulate`):
    the part as printed (:func:`as_printed`), the mechanics rung the file's accuracy asks for
    (else its ``model.mechanics``), the file's field model unless one is given."""
    field_choice = field_model or doc.field_model
    choice = choose_mechanics(mechanics, doc.accuracy_rel, doc.mechanics)
    printed = as_printed(doc)
    return run_simulation(
        printed.geometry(),
        printed.material,
        mechanics=choice.mechanics,
        field_model=None if field_choice == "auto" else field_choice,
        noise_uT_rms=doc.noise_uT_rms,
        whole_part=doc.whole_part,
        section=doc.section_rung,
    )


def full_values(values: dict) -> dict:
    """Every parameter: the given values, the others at their nominal (design) values."""
    return {n: float(values.get(n, p.nominal)) for n, p in PARAMETERS.items()}


def apply_parameters(
    doc: Document, values: dict, name: str | None = None, mechanics: str | None = None
) -> tuple[Document, list[str]]:
    """The design document with the fitted values written into its own keys, and a list of the
    edits made (each a sentence). Loadable by ``mst simulate`` (same rules, same model).

    * modulus_factor    -> material.youngs_modulus_MPa
    * wall_offset_mm    -> every layers[i].t_mm (and printer.min_wall_mm / min_gap_mm / nozzle_mm
                           lowered when a thinner wall or cavity would break their rules: this
                           file models the sensor as printed, it is not a file to print)
    * gap_offset_mm     -> housing.chip_clearance_mm (what remains below zero from
                           housing.pocket_floor_mm, then housing.cover_mm)
    * remanence_factor  -> magnet.remanence_T
    """
    v = full_values(values)
    edits: list[str] = []
    material = replace(doc.material, youngs_modulus_MPa=doc.material.youngs_modulus_MPa * v["modulus_factor"])
    if v["modulus_factor"] != 1.0:
        edits.append(
            f"material.youngs_modulus_MPa {doc.material.youngs_modulus_MPa:g} -> {material.youngs_modulus_MPa:.6g}"
        )
    dt = v["wall_offset_mm"]
    layers = tuple(replace(la, t_mm=round(la.t_mm + dt, 9)) if la.t_mm is not None else la for la in doc.layers)
    if dt:
        edits.append(f"layers[*].t_mm {dt:+.4g} mm")
    magnet = replace(doc.magnet, remanence_T=doc.magnet.remanence_T * v["remanence_factor"])
    if v["remanence_factor"] != 1.0:
        edits.append(f"magnet.remanence_T {doc.magnet.remanence_T:g} -> {magnet.remanence_T:.6g}")
    housing = _housing_with_gap(doc, v["gap_offset_mm"], edits)
    printer = _printer_as_printed(doc, layers, edits)
    out = replace(
        doc,
        name=name or doc.name,
        layers=layers,
        material=material,
        magnet=magnet,
        housing=housing,
        printer=printer,
        mechanics=mechanics or doc.mechanics,
        accuracy_rel=None,
    )
    assert all(isinstance(la, LayerEntry) for la in out.layers)
    return out, edits


def housing_as_printed(doc: Document) -> Housing:
    """``doc``'s housing as its printer builds it: printer.gap_offset_mm written into its keys as
    :func:`apply_parameters` writes it (so the cover's air, the slot walls' height and the
    magnet-chip gap the design loop sees are those ``mst simulate`` sees)."""
    return _housing_with_gap(doc, doc.printer.gap_offset_mm, [])


def _housing_with_gap(doc: Document, gap_offset_mm: float, edits: list[str]) -> Housing:
    """``doc``'s housing with the gap offset taken from housing.chip_clearance_mm (what remains
    below zero from housing.pocket_floor_mm, then housing.cover_mm); the edit appended."""
    hs = doc.housing
    left = gap_offset_mm
    new = {}
    clearance = hs.chip_clearance_mm + left
    if clearance >= 0:
        new["chip_clearance_mm"] = clearance
    else:
        new["chip_clearance_mm"] = 0.0
        left = clearance
        for key in ("pocket_floor_mm", "cover_mm"):
            take = max(left, -(getattr(hs, key) - 0.01))
            new[key] = getattr(hs, key) + take
            left -= take
        if left < -1e-12:
            raise CalibrationFailed(
                f"gap_offset_mm {gap_offset_mm:.4g} cannot be written into "
                "the housing keys (it would need negative clearances)"
            )
    new = {k: round(val, 9) for k, val in new.items()}
    if gap_offset_mm:
        edits.append(
            "housing."
            + ", housing.".join(f"{k} {getattr(hs, k):g} -> {val:.6g}" for k, val in new.items())
            + f" (gap offset {gap_offset_mm:+.4g} mm)"
        )
    return replace(hs, **new)


def _printer_as_printed(doc: Document, layers: tuple, edits: list[str]) -> Printer:
    """``doc``'s printer with its deviations spent and its rules lowered for the as-printed cells;
    the edits appended."""
    pr = doc.printer
    # the values are the print's own (the fit models the drawn walls and the material's E), so
    # the printer's declared deviations are spent: left in, a simulation would apply them twice
    printer = replace(_rules_for(doc, layers), **PRINTER_NOMINAL)
    spent = [
        f"printer.{key} {getattr(pr, key):g} -> {value:g}"
        for key, value in PRINTER_NOMINAL.items()
        if getattr(pr, key) != value
    ]
    if spent:
        edits.append(", ".join(spent) + " (the values above are the print's)")
    for key in ("min_wall_mm", "min_gap_mm", "nozzle_mm"):
        if getattr(printer, key) != getattr(pr, key):
            edits.append(
                f"printer.{key} {getattr(pr, key):g} -> {getattr(printer, key):g} (the as-printed "
                "cells are thinner than the printing rules: this file models the print, do not print it)"
            )
    return printer


def _rules_for(doc: Document, layers) -> Printer:
    """``doc``'s printer with its printing rules (min_wall_mm, min_gap_mm, nozzle_mm) lowered
    where the cells of ``layers`` break them: a file that models a print, not one to print."""
    pr = doc.printer
    t_min = min(la.t_mm for la in layers)
    cav_min = min(la.h_mm - 2 * la.t_mm for la in layers)
    pad_min = min(
        float(inner_pad_half_width_mm(math.radians(la.theta_deg), la.t_mm, la.h_mm, doc.family.width_mm))
        for la in layers
    )
    return replace(
        pr,
        min_wall_mm=min(pr.min_wall_mm, round(math.floor(t_min * 1e4) / 1e4, 4)),
        min_gap_mm=min(pr.min_gap_mm, round(math.floor(cav_min * 1e4) / 1e4, 4)),
        nozzle_mm=min(pr.nozzle_mm, max(0.05, round(math.floor(pad_min * 1e4) / 1e4, 4))),
    )


def with_walls(doc: Document, t_mm: Sequence[float]) -> Document:
    """The design ``doc`` with layer i's wall thickness set to ``t_mm[i]`` (e.g. the width the
    slicer lays down), everything else as it is, so :func:`mst_cli.api.simulate` predicts the
    part those walls make with the model and printer corrections the design itself is simulated
    with. Printing rules the new walls break are lowered (this models a print, not a drawing)."""
    if len(t_mm) != len(doc.layers):
        raise ValueError(f"{len(t_mm)} wall thicknesses for {len(doc.layers)} layers")
    layers = tuple(replace(la, t_mm=round(float(t), 9)) for la, t in zip(doc.layers, t_mm))
    return replace(doc, layers=layers, printer=_rules_for(doc, layers))
