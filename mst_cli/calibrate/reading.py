"""Readings to forces with a calibrated model (what ``mst read`` does): a :class:`ForceReader`
is one model's inverse map, told whether a matching calibration.json stands beside the model
file; it reads a file of readings (:meth:`~ForceReader.read`) or a live serial stream
(:meth:`~ForceReader.stream`). Flagged readings have no force: never extrapolated."""

from __future__ import annotations

import io
import math
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from mst_cli.calibrate.accuracy import ERROR_FROM_RANGE, force_errors, force_errors_by_regime, regime_error_lines
from mst_cli.calibrate.calibration_json import CalibrationRecord, record_beside
from mst_cli.calibrate.inverse_map import FLAGS, InverseMap, inverse_map
from mst_cli.calibrate.load_readings import LoadReadings
from mst_cli.calibrate.loadtest import Readings, field_of, rig_column, unknown_columns
from mst_cli.calibrate.offset_reading import OffsetEstimator, OffsetReadings
from mst_cli.calibrate.rig_reading import BranchForces, follow_branches, no_load_rows, unloading_model_of, zero_shift_T
from mst_cli.calibrate.rung_check import read_rung_warning
from mst_cli.calibrate.table_reader import OffsetTableReader, ShearTableReader, TwoChipLoadReader
from mst_cli.calibrate.tables import FORCES_COLUMNS, cell, forces_csv
from mst_cli.calibrate.temperature_fit import field_at_reference
from mst_cli.io.serial_lines import LineSource, SampleParser
from mst_cli.model.chip import ChipSetting, field_resolution_T
from mst_cli.sensor.document import Document

FORCES_FILE = "forces.csv"


@dataclass
class ForceReadings:
    """The forces of a readings file: force_N (NaN where flagged), regime (0 where flagged),
    flag (:data:`~mst_cli.calibrate.inverse_map.FLAGS`) and force_resolution_N, one per reading."""

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
        text = forces_csv(self.readings, self.force_N, self.regime, self.flag, self.force_resolution_N)
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


def _branch_columns(forces_csv_text: str, bf: BranchForces) -> str:
    """forces.csv with the branch each reading was read on and its force's 1-sigma uncertainty
    (resolution, the unloading model's residual, the hysteresis a hold leaves open)."""
    lines = forces_csv_text.splitlines()
    out = [lines[0] + ",branch,force_uncertainty_N"]
    for i, line in enumerate(lines[1:]):
        u = bf.uncertainty_N[i]
        out.append(f"{line},{bf.branch[i]}," + (f"{u:.6g}" if np.isfinite(u) else ""))
    return "\n".join(out) + "\n"


@dataclass
class SerialSamples:
    """Samples of a serial stream: (seconds since the start, the line's three values, force N,
    regime, flag) each, and how many lines were not a sample."""

    raw: bool
    samples: list[tuple[float, tuple[float, float, float], float, int, str]] = field(default_factory=list)
    skipped: int = 0
    offsets: list[tuple[float, OffsetReadings | LoadReadings]] = field(
        default_factory=list
    )  # (centred force, estimate) each

    def csv(self, imap: InverseMap) -> str:
        cols = ("Bx_code_lsb", "By_code_lsb", "Bz_code_lsb") if self.raw else ("Bx_uT", "By_uT", "Bz_uT")
        buf = io.StringIO()
        buf.write(",".join(("time_s",) + cols + FORCES_COLUMNS) + "\n")
        for t, values, f, r, fl in self.samples:
            res_N = float(imap.local_resolution_N(f)) if math.isfinite(f) else None
            buf.write(
                ",".join(
                    [f"{t:.4f}"]
                    + [f"{v:.9g}" for v in values]
                    + [cell(f), str(r) if math.isfinite(f) else "", fl, cell(res_N, ".6g")]
                )
                + "\n"
            )
        if not self.offsets:
            return buf.getvalue()
        parts = [o for _, o in self.offsets]
        est = (
            LoadReadings.concat([p for p in parts if isinstance(p, LoadReadings)])
            if isinstance(parts[0], LoadReadings)
            else OffsetReadings.concat([p for p in parts if isinstance(p, OffsetReadings)])
        )
        return est.append_columns(buf.getvalue(), np.array([f for f, _ in self.offsets]))


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
        chip = setting or resp.chip_setting
        if chip is not None:
            imap.field_resolution_T = max(imap.field_resolution_T, field_resolution_T(chip, doc.noise_uT_rms))
        note, record = record_beside(Path(model_file))
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
    ) -> ForceReadings:
        """The forces of ``rd``; with ``offsets``, each in-range reading's force corrected for
        where it was pressed (:mod:`~mst_cli.calibrate.offset_reading`); else each on its branch
        (:mod:`~mst_cli.calibrate.rig_reading`). ``tare``: the first readings at no load."""
        imap = self.inverse_map
        zero_record = self.record.zero if self.record is not None else None
        shift = zero_shift_T(
            rd.B_abs_T, rig_column(rd, "time_s"), imap.B_abs_T, tare, track_zero, zero_record, rd.source
        )
        B, m = field_at_reference(rd.B_abs_T - shift, rd, self.document, self.record)  # a T_C column: at 20 degC
        F, regime, flag = imap.force(B, rd.saturated)
        F = F * m
        zero = no_load_rows(B, flag, float(imap.B_abs_T[0]), imap.field_resolution_T)
        F[zero], regime[zero], flag[zero] = 0.0, 1, "ok"
        res = imap.local_resolution_N(np.where(np.isfinite(F), F, 0.0))
        if offsets is None:
            model = unloading_model_of(self.record.hysteresis) if self.record is not None else None
            bf = follow_branches(F, res, model, rig_column(rd, "time_s"))
            regime = np.where(np.isfinite(bf.force_N), imap.regime_of(np.nan_to_num(bf.force_N)), regime)
            out = ForceReadings(self.document.name, rd, bf.force_N, regime, flag, res, edges_N=imap.edges_N)
            out.branches, out.tare_shift_uT = bf, (float(np.mean(shift)) * 1e6 if tare or track_zero else None)
            out.zero_tracked = track_zero
            return out
        chips = getattr(offsets, "chips", 1)  # a two-chip reader takes every chip's field
        B_est = rd.B_T if chips == 1 or rd.B_chips_T is None else rd.B_chips_T
        est = offsets.estimate_all(B_est, np.where(flag == "ok", F, np.nan))
        corrected = np.where(est.flag == "ok", est.force_N, F)
        regime = np.where(np.isfinite(corrected), self.inverse_map.regime_of(corrected), regime)
        return ForceReadings(
            self.document.name, rd, corrected, regime, flag, res, est, F, edges_N=self.inverse_map.edges_N
        )

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
        )

    def stream(
        self,
        port: str,
        baud: int,
        count: int | None,
        timeout_s: float | None,
        raw: bool,
        setting: ChipSetting | None,
        show: Callable[[str], None],
        offsets: OffsetTableReader | ShearTableReader | None = None,
    ) -> SerialSamples:
        """Read ``port`` until it closes, ``count`` samples, ``timeout_s`` of silence or Ctrl-C,
        showing each sample's force through ``show`` (with ``offsets``: corrected, and where it
        was pressed)."""
        src = LineSource(port, baud, timeout_s)
        out = SerialSamples(raw)
        parser = SampleParser(raw)
        t0 = time.monotonic()
        try:
            for line in src:
                values = parser.feed(line)
                if values is None:
                    continue
                B, sat = field_of(values, raw, setting, f"{port} sample {len(out.samples) + 1}")
                Babs = float(np.linalg.norm(B))
                F, regime, flag = self.inverse_map.force(np.array([Babs]), np.array([sat]))
                f, r, fl = float(F[0]), int(regime[0]), str(flag[0])
                where = ""
                if offsets is not None:
                    f, r, where = self._offset_sample(offsets, out, B, f, r, fl)
                out.samples.append((time.monotonic() - t0, values, f, r, fl))
                shown = f"F = {f:8.3f} N  regime {r}" if math.isfinite(f) else f"F = {'-':>8}    "
                if fl != "ok":
                    shown += f"  {fl}"
                shown += where
                show(f"{len(out.samples):6d}  {shown}  |B| {Babs * 1e3:.4f} mT")
                if count is not None and len(out.samples) >= count:
                    break
        except KeyboardInterrupt:
            pass
        finally:
            src.close()
            out.skipped = parser.skipped
        return out

    def _offset_sample(
        self,
        offsets: OffsetTableReader | ShearTableReader,
        out: SerialSamples,
        B: np.ndarray,
        f: float,
        r: int,
        fl: str,
    ) -> tuple[float, int, str]:
        """One stream sample's estimate, kept in ``out``: (the force, its regime, what the terminal
        line adds)."""
        est = offsets.estimate_all(B[None, :], np.array([f if fl == "ok" else math.nan]))
        out.offsets.append((f, est))
        if est.flag[0] != "ok":
            return f, r, est.terminal(0)
        F = float(est.force_N[0])
        return F, int(self.inverse_map.regime_of(F)), est.terminal(0)
