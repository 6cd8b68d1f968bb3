"""Readings to forces with a calibrated model (what ``mst read`` does): a :class:`ForceReader`
is one model's inverse map, told whether a matching calibration.json stands beside the model
file; :meth:`~ForceReader.read` is the one pipeline of a readings file and of a live stream's
batches (:mod:`mst_cli.readout.live`). Flagged readings have no force: never extrapolated."""

from __future__ import annotations

from dataclasses import dataclass, field, fields
from pathlib import Path

import numpy as np

from mst_cli.calibration.accuracy import ERROR_FROM_RANGE, force_errors, force_errors_by_regime, regime_error_lines
from mst_cli.calibration.calibration_json import CalibrationRecord, record_beside
from mst_cli.calibration.loadtest import Readings, rig_column, unknown_columns
from mst_cli.calibration.rung_check import read_rung_warning
from mst_cli.calibration.tables import forces_csv
from mst_cli.calibration.temperature_fit import reading_scales
from mst_cli.estimation.inverse_map import FLAGS, InverseMap, inverse_map, reading_resolution_T
from mst_cli.estimation.load_readings import LOAD_COLUMNS, LoadReadings
from mst_cli.estimation.offset_reading import OFFSET_COLUMNS, OffsetEstimator, OffsetReadings
from mst_cli.estimation.table_reader import OffsetTableReader, ShearTableReader, TwoChipLoadReader
from mst_cli.model.chip import ChipSetting
from mst_cli.model.offcentre import section_members_pose
from mst_cli.readout.rig_reading import (
    BranchForces,
    follow_branches,
    no_load_rows,
    tare_shift_T,
    unloading_model_of,
    zero_shift_T,
)
from mst_cli.sensor.document import Document

FORCES_FILE = "forces.csv"
BRANCH_COLUMNS = ("branch", "force_uncertainty_N")
WRITTEN = (*BRANCH_COLUMNS, *OFFSET_COLUMNS, *LOAD_COLUMNS)  # columns forces.csv may add after FORCES_COLUMNS


@dataclass
class ForceReadings:
    """The forces of a readings file: force_N (NaN where flagged), regime (0 where flagged),
    flag (:data:`~mst_cli.estimation.inverse_map.FLAGS`) and force_resolution_N, one per reading."""

    name: str
    readings: Readings
    force_N: np.ndarray
    regime: np.ndarray
    flag: np.ndarray
    force_resolution_N: np.ndarray
    offset: OffsetReadings | LoadReadings | None = None  # with --estimate: force_N is the estimate's ...
    force_centred_N: np.ndarray | None = None  # ... and this the centred model's
    edges_N: np.ndarray = field(default_factory=lambda: np.zeros(1))  # the model's regime edges (errors per regime)
    branches: BranchForces | None = None  # the branch of each reading and its force's uncertainty
    tare_shift_uT: float | None = None  # --tare: |B| shift that re-zeroed the unloaded field (--track-zero: mean)
    zero_tracked: bool = False  # --track-zero: re-zeroed at every rest

    def csv(self) -> str:
        """forces.csv: the input columns and the force, regime, flag and resolution of each row
        (with an estimate: force_N the estimate's, then the centred force and the estimate's columns)."""
        text = forces_csv(self.readings, self.force_N, self.regime, self.flag, self.force_resolution_N, WRITTEN)
        if self.branches is not None and self.branches.model_used:  # a calibration with an unloading model
            text = _branch_columns(text, self.branches)
        if self.offset is None or self.force_centred_N is None:
            return text
        return self.offset.append_columns(text, self.force_centred_N)

    def errors(self) -> dict | None:
        """Force errors against the file's own force_N column (None without one)."""
        ref = self.readings.force_N
        if ref is None or not len(ref) or float(np.max(ref)) <= 0:
            return None
        err = force_errors(self.force_N, ref, float(np.max(ref)), self.flag)  # the same readings for any model
        err["by_regime"] = force_errors_by_regime(self.force_N, ref, self.edges_N, self.flag)
        return err

    def summary(self) -> str:
        F, flag = self.force_N, self.flag
        counts = {k: int(np.sum(flag == k)) for k in FLAGS}
        ok = np.isfinite(F)
        lines = [
            f"{self.name}: {len(self.readings)} readings: {counts['ok']} in range"
            + "".join(
                f", {counts[k]} {k.replace('_', ' ')}"
                for k in ("above_calibrated", "below_range", "above_range", "saturated")
                if counts[k]
            )
            + (f"; forces {np.nanmin(F):.4g}-{np.nanmax(F):.4g} N" if ok.any() else "")
        ]
        if self.offset is not None:
            lines.append(self.offset.summary())
        if self.tare_shift_uT is not None:
            what, how = ("zero", "at every rest, by a mean of") if self.zero_tracked else ("tare", "by")
            lines.append(f"{what}: no load re-zeroed {how} {self.tare_shift_uT:+.3g} uT of |B|")
        if self.branches is not None and np.any(self.branches.branch == "unloading"):
            n = {k: int(np.sum(self.branches.branch == k)) for k in ("loading", "unloading", "hold")}
            lines.append(
                f"branches: {n['loading']} loading, {n['unloading']} unloading, {n['hold']} hold readings"
                + ("" if self.branches.model_used else " (no unloading model in the calibration: read as loading)")
            )
        unknown = unknown_columns(self.readings)
        if unknown:
            lines.append(f"note: column(s) {', '.join(unknown)} not read by mst (copied into {FORCES_FILE} as written)")
        err = self.errors()
        if err is not None and "median_rel" in err:
            lines.append(
                f"against force_N_reference (readings >= {err['from_force_N']:.3g} N): median error "
                f"{100 * err['median_rel']:.3g} %, 95th percentile {100 * err['p95_rel']:.3g} %, "
                f"max {100 * err['max_rel']:.3g} %, RMS {err['rms_N']:.4g} N"
                + (f"; {err['flagged']} flagged" if err["flagged"] else "")
            )
        elif err is not None and err["readings"]:
            lines.append(
                f"against force_N_reference: all {err['readings']} readings >= {ERROR_FROM_RANGE:g} x range are flagged"
            )
        if err is not None:
            lines += regime_error_lines(err["by_regime"])
        return "\n".join(lines)


def flag_impossible(F: np.ndarray, flag: np.ndarray, top_N: np.ndarray | float) -> None:
    """No force a sensor cannot give is ``ok`` (issue 46): an ok force below 0 N is flagged
    below_range, one above ``top_N`` (the last lock's) or not finite above_range, its force
    emptied (in place)."""
    ok = flag == "ok"
    low = ok & (F < 0.0)
    high = ok & ~(F <= top_N * (1.0 + 1e-9)) & ~low  # NaN and inf too
    flag[low], flag[high] = "below_range", "above_range"
    F[low | high] = np.nan


def estimates_impossible(est: OffsetReadings | LoadReadings, centred_N: np.ndarray, top_N: np.ndarray) -> None:
    """An ``ok`` estimate whose force lies outside [0, ``top_N``] or whose values are not finite
    is no_fit (in place): it keeps the centred force and has no values."""
    names = [f.name for f in fields(est) if f.name not in ("flag", "assumption") and not f.name.startswith("sigma")]
    values = np.column_stack([getattr(est, n) for n in names])
    F = est.force_N
    bad = (est.flag == "ok") & ~(np.all(np.isfinite(values), axis=1) & (F >= 0.0) & (F <= top_N * (1.0 + 1e-9)))
    if not bad.any():
        return
    est.flag[bad] = "no_fit"
    for f in fields(est):
        a = getattr(est, f.name)
        if isinstance(a, np.ndarray) and a.dtype.kind == "f":
            a[bad] = np.nan
    F[bad] = centred_N[bad]


def _branch_columns(forces_csv_text: str, bf: BranchForces) -> str:
    """forces.csv with the branch each reading was read on and its force's 1-sigma uncertainty
    (resolution, the unloading model's residual, the hysteresis a hold leaves open)."""
    lines = forces_csv_text.splitlines()
    out = [lines[0] + "," + ",".join(BRANCH_COLUMNS)]
    for i, line in enumerate(lines[1:]):
        u = bf.uncertainty_N[i]
        out.append(f"{line},{bf.branch[i]}," + (f"{u:.6g}" if np.isfinite(u) else ""))
    return "\n".join(out) + "\n"


@dataclass
class ForceReader:
    """One model file's reading -> force map and the warning it comes with (None: calibrated,
    and the model still gives the recorded curve)."""

    document: Document
    inverse_map: InverseMap
    warning: str | None
    record: CalibrationRecord | None

    @classmethod
    def open(
        cls, doc: Document, model_file: str | Path, mechanics: str, setting: ChipSetting | None = None
    ) -> ForceReader:
        """The reader of ``doc`` (loaded from ``model_file``) with ``mechanics``; ``setting`` is
        the chip's (else the one the model chooses): its LSB bounds the field resolution.
        CalibrationFailed when the model has no monotone map."""
        imap, resp = inverse_map(doc, mechanics)
        note, record = record_beside(Path(model_file))
        measured_uT = record.rest_noise_uT() if record is not None else None
        chip = setting or resp.chip_setting
        imap.field_resolution_T = reading_resolution_T(imap.field_resolution_T, chip, doc.noise_uT_rms, measured_uT)
        top = record.calibrated_top_N() if record else None
        if top is not None:
            imap.calibrated_to_N = min(top, float(imap.force_N[-1]))
        if note is None and record is not None:  # no note: the record beside matches
            note = read_rung_warning(record, mechanics, doc) or record.curve_changed(imap)
        return cls(doc, imap, note, record)

    def read(
        self,
        rd: Readings,
        offsets: OffsetEstimator | OffsetTableReader | ShearTableReader | TwoChipLoadReader | None = None,
        tare: int = 0,
        track_zero: bool = False,
        tare_shift_uT: float | None = None,
        estimated: OffsetReadings | LoadReadings | None = None,
    ) -> ForceReadings:
        """The forces of ``rd``, the one pipeline of files and streams: the tare (``tare``: the
        first readings at no load, or the shift ``tare_shift_uT`` a stream found), the temperature
        law (a T_C column), the centred force and no load; with ``offsets``, each in-range
        reading's force corrected for where (and how) it was pressed
        (:mod:`~mst_cli.estimation.offset_reading`; ``estimated``: the estimates of these readings
        made already, as a stream's batches made them); then each on its branch, with its
        uncertainty (:mod:`~mst_cli.readout.rig_reading`)."""
        imap = self.inverse_map
        r, m = self.temperature_scales(rd)
        B_ref = rd.B_abs_T / r  # the field at 20 degC the inverse map looks up
        if tare_shift_uT is not None:
            shift: np.ndarray | float = 1e-6 * tare_shift_uT
        else:
            zero_record = self.record.zero if self.record is not None else None
            time_s = rig_column(rd, "time_s")
            shift = zero_shift_T(B_ref, time_s, imap.B_abs_T, tare, track_zero, zero_record, rd.source)
        B = B_ref - shift  # re-zeroed
        F_ref, regime, flag = imap.force(B, rd.saturated)
        zero = no_load_rows(B, flag, float(imap.B_abs_T[0]), imap.field_resolution_T)
        F_ref[zero], regime[zero], flag[zero] = 0.0, 1, "ok"
        F = F_ref * m
        # the last lock's force at each T: the stack locks at the same stroke, so at m(T) x its 20 degC force
        top = float(imap.force_N[-1]) * m
        flag_impossible(F, flag, top)
        F_ref = np.where(flag == "ok", F_ref, np.nan)
        res = imap.local_resolution_N(np.where(np.isfinite(F), F, 0.0))
        est, unc = None, res
        if offsets is not None:
            chips = getattr(offsets, "chips", 1)  # a two-chip reader takes every chip's field
            B_est = rd.B_T if chips == 1 or rd.B_chips_T is None else rd.B_chips_T
            r_est = np.asarray(r, dtype=float).reshape((-1,) + (1,) * (B_est.ndim - 1))
            if estimated is None:  # each reading's own: a batch's estimates are its readings' one by one
                estimated = offsets.estimate_all(B_est / r_est, F_ref).scaled(m)
            est = estimated
            estimates_impossible(est, F, top)
            ok = est.flag == "ok"
            F = np.where(ok, est.force_N, F)
            unc = np.where(ok & np.isfinite(est.force_sigma_N), est.force_sigma_N, res)
        model = unloading_model_of(self.record.hysteresis) if self.record is not None else None
        bf = follow_branches(F, unc, model, rig_column(rd, "time_s"))
        flag_impossible(bf.force_N, flag, top)
        bf.uncertainty_N[flag != "ok"] = np.nan
        regime = np.where(np.isfinite(bf.force_N), imap.regime_of(np.nan_to_num(bf.force_N)), regime)
        out = ForceReadings(self.document.name, rd, bf.force_N, regime, flag, res, edges_N=imap.edges_N)
        zeroed = tare or track_zero or tare_shift_uT is not None
        out.branches, out.tare_shift_uT = bf, (float(np.mean(shift)) * 1e6 if zeroed else None)
        out.zero_tracked = track_zero
        if est is not None:
            out.offset, out.force_centred_N = est, F_ref * m
        return out

    def temperature_scales(self, rd: Readings) -> tuple[np.ndarray | float, np.ndarray]:
        """(r(T), m(T)) of each reading of ``rd`` (1 without a T_C column): its field is divided
        by r, its forces multiplied by m (:mod:`~mst_cli.calibration.temperature_fit`)."""
        scales = reading_scales(rd, self.document, getattr(self.record, "temperature", None))
        return scales if scales is not None else (1.0, np.ones(len(rd)))

    def tare_shift_uT(self, rd: Readings, tare: int) -> float:
        """The |B| shift (uT, at 20 degC) that puts the mean of the first ``tare`` readings of
        ``rd`` on the unloaded field."""
        r, _ = self.temperature_scales(rd)
        B_ref = rd.B_abs_T / r
        return 1e6 * tare_shift_T(B_ref, tare, float(self.inverse_map.B_abs_T[0]), rd.source)

    def offset_estimator(self, mechanics: str, max_sigma_mm: float) -> OffsetEstimator:
        """The offset estimator of this model: its geometry and material, the reader's field
        resolution as the noise, up to the last lock, and the lever factor its calibration fitted
        from presses at known offsets (1 without one)."""
        doc = self.document
        return OffsetEstimator(
            doc.geometry(),
            doc.material,
            mechanics,
            self.inverse_map.field_resolution_T,
            float(self.inverse_map.force_N[-1]),
            max_sigma_mm,
            self.record.lever_factor() if self.record is not None else 1.0,
            doc.whole_part,
            section_members_pose(doc.geometry(), doc.material, mechanics, doc.section_rung),
        )
