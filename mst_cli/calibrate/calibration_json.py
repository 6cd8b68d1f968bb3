"""``calibration.json``: what ``mst calibrate`` fitted, how well, and what ``mst read`` needs to
trust a calibrated.yaml (its hash, the load test's largest force, a few points of the curve).
(``mst design --calibration`` reads the fitted printer back strictly: :mod:`.record`.)

:class:`CalibrationRecord` is the file, one field a key in the file's order (units in the
keys); the nested sections stay JSON mappings. :meth:`~CalibrationRecord.from_json` reads a
record back leniently: it sits beside a model file a user may have edited, so anything
missing or malformed is None and only costs ``mst read`` its warning, never the reading.
"""

from __future__ import annotations

import hashlib
import json
import math
from dataclasses import asdict, dataclass, fields
from pathlib import Path
from typing import Any

import numpy as np

from mst_cli.calibrate.fit import InverseMap
from mst_cli.io.files import read_input_text
from mst_cli.io.outputs import finite_or_none
from mst_cli.io.yaml_io import MAX_INPUT_BYTES

CALIBRATION_JSON = "calibration.json"
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
    # what the fitted factors multiply: mst design --calibration reads them (calibrate.record)
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
        value = self.tilt.get("lever_factor") if isinstance(self.tilt, dict) else self.tilt
        if isinstance(value, (int, float)) and not isinstance(value, bool) and math.isfinite(value) and value > 0:
            return float(value)
        from mst_cli.errors import InputError  # deferred: no error machinery for a well-formed file

        raise InputError(f"{CALIBRATION_JSON} tilt.lever_factor", value, "must be a positive number")

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
        except (TypeError, KeyError, ValueError):
            return None
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
    except ValueError:  # InputError (unreadable, not a file) and bad JSON
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
