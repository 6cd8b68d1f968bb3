"""``calibration.json``: what ``mst calibrate`` fitted, how well, and what ``mst read`` needs to
trust a calibrated.yaml (its hash, the load test's largest force, a few points of the curve).
``mst design --calibration`` reads the fitted printer back strictly (:func:`read_calibration`).

:class:`CalibrationRecord` is the file, one field a key in the file's order (units in the
keys); the nested sections stay JSON mappings. :meth:`~CalibrationRecord.from_json` reads a
record back leniently: it sits beside a model file a user may have edited, so anything
missing or malformed is None and only costs ``mst read`` its warning, never the reading.

What one print taught about its printer, read back for the next design (issue 21).

``mst calibrate`` fits a print's wall offset, modulus factor, gap offset and remanence factor to
its load test and writes them to calibration.json. The fit models the walls as drawn and the
material's data-sheet modulus (:class:`~mst_cli.calibration.fit.ForwardModel` reads neither the
design's ``printer`` deviations nor anything else of the print), so the fitted values describe
the printer and filament themselves, whatever design was printed. :func:`read_calibration`
reads them back and :func:`apply_calibration` writes them into a spec's ``printer`` section
(and the magnet's remanence), so ``mst design --calibration`` designs the next print for the
printer as it is. A parameter the calibration held (not identifiable from that load test, or
not requested) is not used and is named.

Bad input (a file that is missing, not JSON, not a calibration record, or fitted on another
material) raises :class:`~mst_cli.errors.InputError` naming ``--calibration``: exit 2, one line.
"""

from __future__ import annotations

import hashlib
import json
import math
from dataclasses import asdict, dataclass, field, fields, replace
from pathlib import Path
from typing import Any, NoReturn

import numpy as np

from mst_cli.calibration.record_bounds import checked
from mst_cli.errors import InputError
from mst_cli.estimation.inverse_map import InverseMap
from mst_cli.io.files import read_input_text
from mst_cli.io.outputs import finite_or_none
from mst_cli.io.yaml_io import MAX_INPUT_BYTES
from mst_cli.model.assembly import printer_violations
from mst_cli.sensor.as_printed import CALIBRATION_JSON, PARAMETERS
from mst_cli.sensor.document import Document, load_document
from mst_cli.sensor.sections import SECTIONS

CALIBRATED_YAML = "calibrated.yaml"
SCHEMA_VERSION = 1
CURVE_CHECK_POINTS = 9


def sha256_text(text: str) -> str:
    return hashlib.sha256(text.encode()).hexdigest()


@dataclass
class CalibrationRecord:
    """The calibration.json of one calibration (docs/calibration.md describes every key)."""

    schema_version: int
    design: str
    load_test: str
    # what the fitted factors multiply: mst design --calibration reads them (:func:`read_calibration`)
    design_constants: dict | None
    calibrated_yaml: str
    calibrated_yaml_sha256: str | None
    models: dict
    samples: int
    force_range_N: list[float]
    fitted_quantity: str
    chip_setting: dict | None
    noise_sigma_uT: float
    parameters: dict[str, dict]
    identifiability: dict
    residuals: dict
    force_errors_in_sample: dict
    regimes: list[dict]
    range_N: dict
    calibrated_to_N: float | None
    edits: list[str]
    lookup_table: dict
    limitations: list[str]
    mst_version: str | None
    # the calibrated curve at a few forces: mst read recomputes it and warns when the model code
    # has changed since (the file's keys alone would then mean another curve)
    curve_check: dict | None
    fit: dict
    # presses at known offsets (x_mm, y_mm columns): the tilt rung's fitted lever factor
    tilt: dict | None = None
    # a rig's load test (issue 38): branches, hysteresis per regime, the unloading model, first
    # cycle, creep; and whether the fit's misfit is noise (fit_quality)
    hysteresis: dict | None = None
    fit_quality: dict | None = None
    # a load test with T_C (issue 38): the modulus temperature coefficient, fitted or held
    temperature: dict | None = None
    # a rig's log (issue 47): the force's lag behind the field and the rows without a force, the
    # zero's drift and recovery after each unloading, the first presses' softening; each with sigma
    time_alignment: dict | None = None
    zero: dict | None = None
    softening: dict | None = None

    def to_json(self) -> dict[str, Any]:
        """The file's JSON-ready mapping (non-finite numbers are null: JSON holds no NaN)."""
        return finite_or_none(asdict(self))

    @classmethod
    def from_json(cls, data: Any) -> CalibrationRecord:
        """A record from a parsed calibration.json; a missing key is None. ValueError when it is
        not a mapping."""
        if not isinstance(data, dict):
            raise ValueError(f"{CALIBRATION_JSON} is not a mapping")
        values: dict[str, Any] = {f.name: data.get(f.name) for f in fields(cls)}
        return cls(**values)

    @staticmethod
    def curve_points(imap: InverseMap) -> dict:
        """:attr:`curve_check` of an inverse map: |B| at evenly spaced forces up to the last lock."""
        F = np.linspace(0.0, imap.force_N[-1], CURVE_CHECK_POINTS)
        return {
            "force_N": [float(f) for f in F],
            "B_abs_uT": [float(b) * 1e6 for b in np.interp(F, imap.force_N, imap.B_abs_T)],
        }

    def lever_factor(self) -> float:
        """The tilt rung's lever factor fitted from presses at known offsets (1 without any).
        InputError when the file holds something else there."""
        if self.tilt is None:
            return 1.0
        tilt = self.tilt if isinstance(self.tilt, dict) else {"lever_factor": self.tilt}
        value = checked(tilt, "tilt", "lever_factor")  # InputError beyond the fit's bounds
        return 1.0 if value is None else value

    def rest_noise_uT(self) -> float | None:
        """The chip's noise the load test logged at rest (``zero.rest_noise_uT``, uT): the noise
        a reader of this calibration states its 1-sigma with; None when the log had no rests.
        InputError when the file holds something else there."""
        noise = checked(self.zero, "zero", "rest_noise_uT")
        return noise if noise is not None and noise > 0.0 else None

    def calibrated_top_N(self) -> float | None:
        """The load test's largest force, when the record holds a usable one."""
        top = self.calibrated_to_N
        if isinstance(top, (int, float)) and not isinstance(top, bool) and math.isfinite(top) and top > 0:
            return float(top)
        return None

    def curve_changed(self, imap: InverseMap) -> str | None:
        """A warning when the model no longer gives the curve this record holds (None: it does,
        or the record holds no usable curve)."""
        check = self.curve_check
        if not isinstance(check, dict):  # a record without a usable curve
            return None
        try:
            F = np.asarray(check["force_N"], dtype=np.float64)
            B = np.asarray(check["B_abs_uT"], dtype=np.float64) * 1e-6
        except (TypeError, KeyError, ValueError, OverflowError):
            return None
        if F.ndim != 1 or F.shape != B.shape or not (np.all(np.isfinite(F)) and np.all(np.isfinite(B))):
            return None  # not a curve: nothing to compare
        now = np.interp(F, imap.force_N, imap.B_abs_T)
        worst = float(np.max(np.abs(now - B))) if len(F) else 0.0
        if worst > imap.field_resolution_T:
            return (
                f"the model now gives a calibrated curve up to {worst * 1e6:.3g} uT away from the one "
                f"recorded at calibration (mst {self.mst_version or '?'}; field resolution "
                f"{imap.field_resolution_T * 1e6:.3g} uT): the model code changed, re-run mst calibrate"
            )
        return None


def record_beside(model_file: Path) -> tuple[str | None, CalibrationRecord | None]:
    """(None, the record) when MODEL has a matching calibration.json beside it, else (a warning
    sentence, None): the hash of the model file's text must be the one recorded."""
    sidecar = Path(model_file).with_name(CALIBRATION_JSON)
    try:  # regular files only: a FIFO in their place must not block
        data = json.loads(read_input_text(sidecar, MAX_INPUT_BYTES, field=CALIBRATION_JSON))
        text = read_input_text(model_file, MAX_INPUT_BYTES)
    except (ValueError, RecursionError):  # InputError (unreadable, not a file), bad or too deep JSON
        return (
            f"{Path(model_file).name} has no {CALIBRATION_JSON} beside it: forces come from the "
            "design as drawn, not as printed (run mst calibrate; expect errors of tens of percent)"
        ), None
    record = CalibrationRecord.from_json(data) if isinstance(data, dict) else None
    if record is None or record.calibrated_yaml_sha256 != sha256_text(text):
        return (
            f"{CALIBRATION_JSON} beside {Path(model_file).name} belongs to another file: forces may not be calibrated"
        ), None
    return None, record


OPTION = "--calibration"
CONSTANTS_KEY = "design_constants"  # calibration.json: what the fitted factors multiply
# where each fitted parameter goes in the next spec
TARGET_KEY = {
    "wall_offset_mm": "printer.wall_offset_mm",
    "modulus_factor": "printer.modulus_factor",
    "gap_offset_mm": "printer.gap_offset_mm",
    "remanence_factor": "magnet.remanence_T",
}


def design_constants(doc: Document) -> dict:
    """The calibrated design's constants the fitted factors are relative to (calibration.json
    keeps them, so that another design can use the factors): material and remanence."""
    return {
        "material_name": doc.material.name,
        "youngs_modulus_MPa": doc.material.youngs_modulus_MPa,
        "remanence_T": doc.magnet.remanence_T,
    }


@dataclass(frozen=True)
class Taken:
    """One parameter taken from the calibration, in the next spec's own key and unit."""

    parameter: str  # PARAMETERS name
    key: str  # the spec key it is written to
    value: float
    std: float | None  # 1 sigma, same unit
    unit: str


@dataclass
class PrinterCalibration:
    """The parameters of one calibration.json as a next spec uses them."""

    path: str
    calibrated_design: str
    taken: list[Taken] = field(default_factory=list)
    not_used: dict[str, str] = field(default_factory=dict)  # parameter -> why
    mechanics: str | None = None  # the rung of the fit (models.mechanics), when the record names one
    calibrated_to_N: float | None = None  # the load test's largest force, when the record holds one

    def lines(self) -> list[str]:
        """What was taken, with what uncertainty, and what was not: as ``mst design`` prints it."""

        def one(t: Taken) -> str:
            value = f"{t.value:+.4f}" if t.unit == "mm" else f"{t.value:.4f}"
            std = f" ± {t.std:.4f}" if t.std is not None else ""
            return f"{t.key} {value}{std}{' ' + t.unit if t.unit else ''}"

        out = [
            f"calibration {self.path} (a print of {self.calibrated_design}): "
            + ("; ".join(one(t) for t in self.taken) if self.taken else "nothing identifiable to take")
        ]
        out += [f"calibration: {name} not used: {why}" for name, why in self.not_used.items()]
        return out

    def report(self) -> dict:
        """report.json's ``calibration`` block."""
        return {
            "file": self.path,
            "calibrated_design": self.calibrated_design,
            "taken": {
                t.key: {"parameter": t.parameter, "value": t.value, "std": t.std, "unit": t.unit} for t in self.taken
            },
            "not_used": dict(self.not_used),
        }


def _refuse(path: str | Path, why: str) -> NoReturn:
    raise InputError(OPTION, str(path), why)


def _number(path: str | Path, where: str, value: Any, *, positive: bool = False) -> float:
    """``value`` as a (``positive``) finite number, else InputError naming ``where``."""
    if (
        isinstance(value, bool)
        or not isinstance(value, (int, float))
        or not math.isfinite(value)
        or (positive and value <= 0)
    ):
        _refuse(
            path,
            f"{where} = {value!r} is not a {'positive ' if positive else ''}finite number: "
            "give the calibration.json mst calibrate wrote",
        )
    return float(value)


def read_calibration(path: str | Path, doc: Document) -> PrinterCalibration:
    """Read calibration.json at ``path`` for the spec ``doc``: the values in ``doc``'s terms.

    The wall and gap offsets are the print's own (mm beyond the drawing); the modulus factor
    is converted to ``doc``'s modulus (E_calibrated x factor / E_doc) and the remanence factor
    to a remanence (Br_calibrated x factor). InputError (``--calibration``) when the file is
    missing or unreadable, not JSON, not a calibration record, or fitted on another material.
    """

    text = read_input_text(
        path, MAX_INPUT_BYTES, field=OPTION, what="calibration.json", too_large=": a calibration.json is a few kB"
    )
    try:
        record = json.loads(text)
    except (ValueError, RecursionError):  # RecursionError: brackets nested too deep
        _refuse(path, "is not JSON: give the calibration.json mst calibrate wrote")
    if not isinstance(record, dict) or not isinstance(record.get("parameters"), dict):
        _refuse(path, "has no 'parameters' mapping: give the calibration.json mst calibrate wrote")
    constants = record.get(CONSTANTS_KEY)
    if not isinstance(constants, dict):
        _refuse(
            path,
            f"has no '{CONSTANTS_KEY}' (written by an mst calibrate before 0.7): run mst calibrate on that print again",
        )
    material = constants.get("material_name")
    if not isinstance(material, str):
        _refuse(path, f"{CONSTANTS_KEY}.material_name is missing: give the calibration.json mst calibrate wrote")
    if material != doc.material.name:
        _refuse(
            path,
            f"was fitted on a print of material '{material}', this spec prints '{doc.material.name}' "
            "(material.name): calibrate a print of the same printer and filament",
        )
    E_cal = _number(path, f"{CONSTANTS_KEY}.youngs_modulus_MPa", constants.get("youngs_modulus_MPa"), positive=True)
    Br_cal = _number(path, f"{CONSTANTS_KEY}.remanence_T", constants.get("remanence_T"), positive=True)

    out = _fit_context(record, PrinterCalibration(path=str(path), calibrated_design=str(record.get("design", "?"))))
    for name, par in PARAMETERS.items():
        entry = record["parameters"].get(name)
        if not isinstance(entry, dict) or not isinstance(entry.get("fitted"), bool):
            _refuse(
                path, f"parameters.{name} is missing or has no 'fitted': give the calibration.json mst calibrate wrote"
            )
        if not entry["fitted"]:
            why = entry.get("held_because")
            out.not_used[name] = "held by the calibration" + (f" ({why})" if isinstance(why, str) else "")
            continue
        value = _number(path, f"parameters.{name}.value", entry.get("value"))
        std_given = entry.get("std")
        std = None if std_given is None else _number(path, f"parameters.{name}.std", std_given)
        scale = {"modulus_factor": E_cal / doc.material.youngs_modulus_MPa, "remanence_factor": Br_cal}.get(name, 1.0)
        unit = "T" if name == "remanence_factor" else par.unit
        out.taken.append(Taken(name, TARGET_KEY[name], value * scale, None if std is None else std * scale, unit))
    return out


def _fit_context(record: dict, out: PrinterCalibration) -> PrinterCalibration:
    """``out`` with the record's rung and calibrated range, where it names usable ones."""
    models = record.get("models")
    rung = models.get("mechanics") if isinstance(models, dict) else None
    out.mechanics = rung if isinstance(rung, str) else None
    top = record.get("calibrated_to_N")
    if isinstance(top, (int, float)) and not isinstance(top, bool) and math.isfinite(top) and top > 0:
        out.calibrated_to_N = float(top)
    return out


def apply_calibration(doc: Document, cal: PrinterCalibration) -> Document:
    """``doc`` with the taken values in its ``printer`` section and magnet (each checked against
    its key's declared bounds: InputError naming the key and ``--calibration``)."""
    printer: dict[str, Any] = {}
    magnet: dict[str, Any] = {}
    for t in cal.taken:
        section, key = t.key.split(".")
        rule = SECTIONS[section][key]
        try:
            rule.check(t.key, t.value)
        except InputError as exc:
            raise InputError(f"{t.key} (from {OPTION} {cal.path})", t.value, exc.allowed) from None
        (printer if section == "printer" else magnet)[key] = t.value
    out = replace(doc, printer=replace(doc.printer, **printer), magnet=replace(doc.magnet, **magnet))
    for v in printer_violations(out.printer, out.housing, out.family.contact_allowance_mm):
        raise InputError(f"{v.field} (from {OPTION} {cal.path})", v.value, v.allowed)
    return out


def load_with_calibration(
    spec_file: str | Path, calibration: str | Path | None
) -> tuple[Document, PrinterCalibration | None]:
    """A spec or design file with an earlier print's calibration applied (``mst design
    --calibration``), and that calibration (None without one: the file as it is)."""
    doc = load_document(spec_file)
    if calibration is None:
        return doc, None
    cal = read_calibration(calibration, doc)
    return apply_calibration(doc, cal), cal


__all__ = [
    "read_calibration",
    "apply_calibration",
    "design_constants",
    "PrinterCalibration",
    "Taken",
    "load_with_calibration",
]
