"""One calibration, from a design and its printed sensor's load test to every file
``mst calibrate`` writes: :func:`calibrate` runs the fit (:mod:`~mst_cli.calibration.fit`) and
builds the record, the tables and the C header; :class:`Calibration` holds them and writes
them atomically (all or none)."""

from __future__ import annotations

import math
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import yaml

from mst_cli.calibration import fit as cal
from mst_cli.calibration.accuracy import force_errors, force_errors_by_regime, regime_error_lines
from mst_cli.calibration.calibration_json import (
    CALIBRATED_YAML,
    CALIBRATION_JSON,
    SCHEMA_VERSION,
    CalibrationRecord,
    design_constants,
    sha256_text,
)
from mst_cli.calibration.chip_choice import ChipChoice, choose_setting_for
from mst_cli.calibration.fit_quality import fit_quality
from mst_cli.calibration.force_unit import check_force_unit
from mst_cli.calibration.loadtest import (
    FORCE_COLUMN,
    MAX_ROWS,
    Readings,
    check_field_unit,
    check_load_test,
    parse_readings,
    read_text,
    unknown_columns,
)
from mst_cli.calibration.missing_force import check_force_sentinel
from mst_cli.calibration.plot import plot_calibration
from mst_cli.calibration.rig_calibration import RigAnalysis, analyse, describe
from mst_cli.calibration.tables import lookup_csv, residuals_csv
from mst_cli.calibration.temperature_fit import (
    TemperatureCalibration,
    calibrate_temperature,
    referred,
    remanence_coeff_of,
)
from mst_cli.calibration.tilt_fit import fit_lever_factor
from mst_cli.calibration.time_alignment import align
from mst_cli.errors import CalibrationFailed, InputError
from mst_cli.estimation.inverse_map import InverseMap, field_sigma_T, inverse_map, reading_resolution_T
from mst_cli.firmware.header import HEADER_FILE, c_header
from mst_cli.io.outputs import staged
from mst_cli.model.chip import ChipSetting, field_resolution_T
from mst_cli.model.response import Response, simulate
from mst_cli.sensor.as_printed import PARAMETERS, apply_parameters
from mst_cli.sensor.document import Document, document_to_dict, parse_document
from mst_cli.version import package_version

PLOT_FILE = "calibration.png"
TEMPERATURE_ROUNDS = 4  # modulus coefficient and elastic fit in turn (the two correlate through the modulus)
MIN_CENTRED_ROWS = 8  # a load test with presses off the axis still needs this many on it
PROGRESS_FROM_SAMPLES = 10_000  # a load test this long gets a progress line (40 000 samples: 2-3 s)
YAML_PREAMBLE = (
    "# The design as printed: mst calibrate fitted it to a load test (calibration.json beside it).\n"
    "# It models the printed sensor for mst simulate and mst read; it is not a file to print.\n"
)


def parse_params(text: str) -> tuple[str, ...]:
    """The parameter names of ``--params`` ("a,b"): InputError for none, an unknown or a repeated one."""
    names = [n.strip() for n in text.split(",") if n.strip()]
    if not names:
        raise InputError("--params", text, "one or more of " + ", ".join(PARAMETERS))
    for n in names:
        if n not in PARAMETERS:
            raise InputError("--params", n, "unknown parameter; allowed: " + ", ".join(PARAMETERS))
    if len(set(names)) != len(names):
        raise InputError("--params", text, "a parameter is named twice")
    return tuple(names)


def regime_rows(resp: Response) -> list[dict]:
    """Each regime's band, sensitivity, stiffness and force resolution (None when unresolved)."""
    return [
        {
            "regime": r.index,
            "locking_layer": r.layer,
            "force_from_N": r.force_from_N,
            "force_to_N": r.force_to_N,
            "sensitivity_secant_per_N": r.sensitivity_secant_per_N,
            "k_effective_N_per_mm": r.k_effective_N_per_mm,
            "force_resolution_N": r.force_resolution_N if np.isfinite(r.force_resolution_N) else None,
        }
        for r in resp.regimes
    ]


@dataclass
class Calibration:
    """A finished calibration: the fit, the calibrated design and every output's content."""

    design: Document
    calibrated: Document
    mechanics: str
    load_test: Readings
    load_test_name: str
    fit: cal.FitResult
    inverse_map: InverseMap  # the calibrated model's reading -> force map
    record: CalibrationRecord  # calibration.json
    calibrated_yaml: str
    lookup_csv: str
    residuals_csv: str
    header: str | None  # force_table.h (None: see header_reason)
    header_reason: str | None
    header_setting: ChipSetting | None
    design_curve: tuple[np.ndarray, np.ndarray]  # (force N, |B| T) of the design
    calibrated_curve: tuple[np.ndarray, np.ndarray]
    rig: RigAnalysis | None = None  # the branches of every centred row (load_test: the rows fitted)
    chip: ChipChoice | None = None  # the one chip setting (header_setting) and why
    temperature: TemperatureCalibration | None = None  # a load test with T_C: the modulus coefficient

    @property
    def warnings(self) -> list[str]:
        """Sentences for the terminal: the fit misses the load test beyond its noise."""
        q = self.record.fit_quality
        return [q["warning"]] if q and q.get("warning") else []

    @property
    def file_names(self) -> list[str]:
        return [CALIBRATED_YAML, CALIBRATION_JSON, "residuals.csv", "lookup.csv"] + (
            [HEADER_FILE] if self.header else []
        )

    def write(self, out: Path, plot: bool = True) -> None:
        """Every file into ``out``, atomically; ``plot=False`` draws no calibration.png (and
        removes an old one) without importing matplotlib."""
        with staged(out) as st:
            st.write_text(CALIBRATED_YAML, self.calibrated_yaml)
            st.write_json(CALIBRATION_JSON, self.record.to_json())
            st.write_text("residuals.csv", self.residuals_csv)
            st.write_text("lookup.csv", self.lookup_csv)
            if self.header:
                st.write_text(HEADER_FILE, self.header)
            if not plot:
                st.remove(PLOT_FILE)
            else:
                rows = self.rig.readings if self.rig is not None else self.load_test
                plot_calibration(
                    st.path(PLOT_FILE),
                    rows.load_N,
                    rows.B_abs_T,
                    self.design_curve,
                    self.calibrated_curve,
                    rows.B_abs_T - self.fit.model.field_abs_T(rows.load_N, self.fit.values),
                    self.fit.sigma_T,
                    f"{self.design.name}: load test against the design and the calibrated model",
                    None if self.rig is None else self.rig.branches.label,
                )

    def summary(self) -> str:
        """The table ``mst calibrate`` prints: parameters, residual, S and R, force errors."""
        r, fit, lt = self.record, self.fit, self.load_test
        lines = [
            f"{self.design.name}: calibrated from {self.load_test_name} ({len(lt)} samples, "
            f"{lt.load_N.min():.3g}-{lt.load_N.max():.4g} N), mechanics={self.mechanics}",
            f"{'parameter':<18} {'design':>8} {'fitted':>10} {'+-1 sigma':>10}  identifiable",
        ]
        for n, p in PARAMETERS.items():
            unit = f" {p.unit}" if p.unit else ""
            if n in fit.names:
                ident = "yes" if fit.identifiable[n] else "NO: the data barely fix it (the last one left)"
                lines.append(f"{n:<18} {p.nominal:>8g} {fit.values[n]:>10.4f} {fit.std[n]:>10.2g}{unit:<3} {ident}")
            elif n in fit.held:
                lines.append(f"{n:<18} {p.nominal:>8g} {'(held)':>10} {'':>10}{'':<3} NO: held at the design's value")
            else:
                lines.append(f"{n:<18} {p.nominal:>8g} {'(held)':>10} {'':>10}{'':<3} not requested")
        lines.append(
            f"residual |B| {fit.residual_rms_T * 1e6:.3g} uT RMS (noise {fit.sigma_T * 1e6:.3g} uT, "
            f"chi2/dof {fit.chi2_reduced:.3g})"
        )
        lines.append(f"{'regime':>6} {'R design':>9} {'R calib.':>9} {'S design':>9} {'S calib.':>9} {'dF calib.':>9}")
        lines.append(f"{'':>6} {'[N]':>9} {'[N]':>9} {'[1/N]':>9} {'[1/N]':>9} {'[mN]':>9}")
        for row in r.regimes:
            d, c = row["design"], row["calibrated"]
            dF = f"{c['force_resolution_N'] * 1e3:9.2f}" if c["force_resolution_N"] is not None else f"{'-':>9}"
            lines.append(
                f"{d['regime']:>6} {d['force_to_N']:>9.3f} {c['force_to_N']:>9.3f} "
                f"{d['sensitivity_secant_per_N']:>9.4f} {c['sensitivity_secant_per_N']:>9.4f} {dF}"
            )
        lines += _error_lines(r.force_errors_in_sample)
        s = self.header_setting
        if s is not None:
            lines.append(f"table for GAIN_SEL {s.gain_sel}, RES {s.res} ({s.z_uT_per_lsb} uT/LSB on Z)")
        if self.chip is not None:
            lines.append(self.chip.line())
        if self.temperature is not None:
            lines.append(self.temperature.line())
        if r.tilt is not None:
            t = r.tilt
            lines.append(
                f"tilt, from {t['rows']} rows at {len(t['presses_mm'])} presses off the axis: lever factor "
                f"{t['lever_factor']:.4f} +- {t['std']:.2g}"
                + (" (AT ITS BOUND)" if t["at_bound"] else "")
                + f"; field residual {t['rms_residual_uT']:.3g} uT RMS ({t['rms_residual_at_factor_1_uT']:.3g} at 1)"
            )
        if self.rig is not None and (len(self.rig.readings) > len(lt) or not self.rig.use_branches):
            lines += self.rig.summary_lines()
        if self.rig is not None:
            lines += self.rig.rig_lines()
        lines += [f"warning: {w}" for w in self.warnings]
        unknown = unknown_columns(self.load_test)
        if unknown:
            lines.append(f"note: column(s) {', '.join(unknown)} of {self.load_test_name} not used by the calibration")
        return "\n".join(lines)


def _error_lines(errors: dict) -> list[str]:
    """The summary's lines on the load test's forces read back: overall, then per regime."""
    in_sample, design_errors = errors["calibrated"], errors["design"]
    lines = []
    if "median_rel" in in_sample:
        design_part = (
            f"design {100 * design_errors['median_rel']:.3g} %"
            if "median_rel" in design_errors
            else "design: all flagged"
        )
        lines.append(
            f"forces of the load test from its own readings (F >= {in_sample['from_force_N']:.3g} N): "
            f"median error calibrated {100 * in_sample['median_rel']:.3g} % (95th pct "
            f"{100 * in_sample['p95_rel']:.3g} %), {design_part}"
            + (f", {design_errors['flagged']} out of the design's range" if design_errors.get("flagged") else "")
        )
    return lines + regime_error_lines(in_sample.get("by_regime", []))


def calibrate(
    doc: Document,
    design_file: str | Path,
    load_test_file: str | Path,
    *,
    mechanics: str = "spring",
    params: Sequence[str] = cal.DEFAULT_PARAMETERS,
    gain_sel: int | None = None,
    res: int | None = None,
    table_size: int = 256,
    progress: Callable[[str], None] | None = None,
    use_branches: bool = True,
    missing_force: float | None = None,
) -> Calibration:
    """Fit ``doc`` (loaded from ``design_file``, which the record names) to the load test in
    ``load_test_file``: to its loading rows (:mod:`~mst_cli.calibration.rig_calibration`;
    ``use_branches=False``: every row as loading). InputError for a bad load test;
    CalibrationFailed (with why) when the fit fails or its values would make a design that does
    not load. ``progress`` gets a line before a long fit; ``missing_force``: a logger's mark."""
    read = _read_load_test(load_test_file, gain_sel, res, missing_force)
    aligned, alignment = align(read, measure=use_branches)  # the calibration that ignores branches: no lag
    lt_all, presses = _split_presses(aligned, doc)
    rig = analyse(lt_all, max(cal.MIN_POINTS, cal.MIN_POINTS_PER_PARAMETER * len(params)), use_branches, alignment)
    fitted, temperature = _fit_in_temperature(doc, rig, Path(load_test_file).name, mechanics, tuple(params), progress)
    lt = fitted.lt  # the rows fitted (referred to 20 degC when the load test has T_C)
    imap, setting = fitted.imap, fitted.setting
    header, header_reason = _header(fitted, f"{Path(design_file).name} and {Path(load_test_file).name}")
    F_fit, flag_fit, errors = _in_sample_errors(fitted)
    yaml_text = YAML_PREAMBLE + yaml.safe_dump(fitted.calibrated_dict, sort_keys=False, default_flow_style=None)
    files = _RecordFiles(str(design_file), str(load_test_file), sha256_text(yaml_text), table_size, header_reason)
    record = _record(doc, fitted, files, errors, header is not None)
    if presses is not None:
        record.tilt = fit_lever_factor(fitted.calibrated, mechanics, presses, fitted.fit.sigma_T)
    _rig_sections(record, rig, fitted)
    record.temperature = temperature.record() if temperature is not None else None
    F_grid = np.linspace(0.0, max(float(lt.load_N.max()), fitted.cal_resp.max_force_N), 400)
    design_resp, fit = fitted.design_resp, fitted.fit
    return Calibration(
        design=doc,
        calibrated=fitted.calibrated,
        mechanics=mechanics,
        load_test=lt,
        load_test_name=Path(load_test_file).name,
        fit=fit,
        inverse_map=imap,
        record=record,
        calibrated_yaml=yaml_text,
        lookup_csv=lookup_csv(imap, setting, table_size),
        residuals_csv=residuals_csv(lt, fit, F_fit, flag_fit),
        header=header,
        header_reason=header_reason,
        header_setting=setting,
        design_curve=(design_resp.force_N[design_resp.in_range], design_resp.B_abs_T[design_resp.in_range]),
        calibrated_curve=(F_grid, fit.model.field_abs_T(F_grid, fit.values)),
        rig=rig,
        chip=fitted.chip,
        temperature=temperature,
    )


def _fit_in_temperature(
    doc: Document,
    rig: RigAnalysis,
    load_test_name: str,
    mechanics: str,
    names: tuple[str, ...],
    progress: Callable[[str], None] | None,
) -> tuple[_Fitted, TemperatureCalibration | None]:
    """The fit on the rig's rows to fit, referred to 20 degC (:mod:`~mst_cli.calibration.temperature_fit`;
    as they are without T_C) and, when the load test's temperatures fix the modulus coefficient,
    the fit again with it; its inverse map's resolution at the noise the rig logged at rest, when it
    logged rests (the readers' noise, as mst read's: :func:`~mst_cli.estimation.inverse_map.reading_resolution_T`)."""
    lt = rig.readings.subset(rig.fit_rows)
    alpha = remanence_coeff_of(doc)
    fitted = _fit(doc, referred(lt, alpha, 0.0), load_test_name, mechanics, names, progress)
    temperature = None
    for _ in range(TEMPERATURE_ROUNDS):  # the coefficient and the elastic fit, in turn
        temperature = calibrate_temperature(doc, lt, fitted.fit.values, fitted.fit.model.field_abs_T, fitted.sigma_T)
        if temperature is None or not temperature.fitted:
            break
        beta = temperature.modulus_coeff_per_K
        fitted = _fit(doc, referred(lt, alpha, beta), load_test_name, mechanics, names, progress)
    if rig.zero is not None and rig.zero.noise_T:
        noise_uT = 1e6 * rig.zero.noise_T
        fitted.imap.field_resolution_T = reading_resolution_T(0.0, fitted.setting, doc.noise_uT_rms, noise_uT)
    return fitted, temperature


def _in_sample_errors(fitted: _Fitted) -> tuple[np.ndarray, np.ndarray, dict]:
    """(the calibrated model's force of each fitted row, its flag, the force errors of the
    calibrated and the design's model against the load cell: calibration.json's
    force_errors_in_sample)."""
    lt, imap = fitted.lt, fitted.imap
    F_fit, _, flag_fit = imap.force(lt.B_abs_T, lt.saturated)
    in_sample = force_errors(F_fit, lt.load_N, fitted.cal_resp.max_force_N, flag_fit)
    in_sample["by_regime"] = force_errors_by_regime(F_fit, lt.load_N, imap.edges_N, flag_fit)
    try:
        F_design, _, _ = InverseMap.from_response(fitted.design_resp).force(lt.B_abs_T)
        design_errors = force_errors(F_design, lt.load_N, fitted.cal_resp.max_force_N)
    except CalibrationFailed:
        design_errors = {}
    return F_fit, flag_fit, {"calibrated": in_sample, "design": design_errors}


def _rig_sections(record: CalibrationRecord, rig: RigAnalysis, fitted: _Fitted) -> None:
    """calibration.json's hysteresis and fit_quality sections: the branches after the fit, and
    the fit's normalised residuals judged (the sigmas are the fit's, already x sqrt(chi2_nu)
    when it exceeds 1: not inflated twice)."""
    imap, fit = fitted.imap, fitted.fit
    describe(rig, imap.edges_N, lambda B: np.interp(B, imap.B_abs_T, imap.force_N))
    record.hysteresis = rig.record()
    for key, value in rig.rig_records().items():
        setattr(record, key, value)
    rows = rig.fit_rows
    q = fit_quality(fit.residual_T / fit.sigma_T, len(fit.names), rig.branches.label[rows], rig.time_s[rows])
    record.fit_quality = {
        "chi2_nu": q.chi2_nu,
        "runs": q.runs,
        "runs_expected": q.runs_expected,
        "runs_z": q.runs_z,
        "lag1_autocorrelation": q.lag1,
        "branch_t": q.branch_t,
        "trend_t": q.trend_t,
        "structured": q.structured,
        "cause": q.cause,
        "warning": q.warning,
        "sigma_inflation": math.sqrt(q.chi2_nu) if q.chi2_nu > 1 else 1.0,
        "rule": "warning when chi2_nu > 2 and the runs test's z < -3 or the branch or trend t beyond 4; "
        "every parameter sigma is the fit's, "
        "x sqrt(chi2_nu) when chi2_nu > 1, and identifiability is judged on it",
    }


def _read_load_test(
    load_test_file: str | Path, gain_sel: int | None, res: int | None, missing_force: float | None = None
) -> Readings:
    """The load test's rows, every one from one chip setting (rows without a force: NaN; a
    sentinel given without ``missing_force`` refused)."""
    text = read_text(load_test_file)
    lt = parse_readings(
        text, str(load_test_file), need_force=True, gain_sel=gain_sel, res=res, one_setting=True,
        missing_force=missing_force,
    )  # fmt: skip
    check_force_sentinel(lt.source, lt.lines, lt.force_N, FORCE_COLUMN)
    return lt


def _split_presses(lt: Readings, doc: Document) -> tuple[Readings, Readings | None]:
    """(the centred rows, the rows pressed off the axis or None) of a load test; without x_mm,
    y_mm columns every row is centred. InputError for too few centred rows or a press off the
    top face."""
    if lt.offset_mm is None:
        return lt, None
    centred = np.all(lt.offset_mm == 0.0, axis=1)
    if centred.sum() < MIN_CENTRED_ROWS:
        raise InputError(
            f"{lt.source} x_mm, y_mm",
            f"{int(centred.sum())} rows at 0, 0",
            f"need at least {MIN_CENTRED_ROWS} rows pressed on the axis (x_mm = y_mm = 0): they calibrate the sensor, "
            "the others its tilt",
        )
    geometry = doc.geometry()
    half = np.array([0.5 * geometry.width_mm, 0.5 * geometry.depth_mm])
    outside = np.flatnonzero(np.any(np.abs(lt.offset_mm) > half, axis=1))
    if outside.size:
        i = int(outside[0])
        raise InputError(
            f"{lt.source} line {lt.lines[i]} x_mm, y_mm",
            f"{lt.offset_mm[i, 0]:g}, {lt.offset_mm[i, 1]:g}",
            f"must lie on the top face: |x| <= {half[0]:g} mm, |y| <= {half[1]:g} mm",
        )
    return lt.subset(centred), (lt.subset(~centred) if (~centred).any() else None)


@dataclass
class _Fitted:
    """A fit and what it made: the models before and after it, the calibrated design and its
    inverse map, and the chip setting the tables are for (None: the field saturates)."""

    lt: Readings
    mechanics: str
    names: tuple[str, ...]
    sigma_T: float
    fit: cal.FitResult
    seconds: float
    design_resp: Response
    calibrated: Document
    calibrated_dict: dict
    edits: list[str]
    imap: InverseMap
    cal_resp: Response
    chip: ChipChoice

    @property
    def setting(self) -> ChipSetting | None:
        return self.chip.setting


def _fit(
    doc: Document,
    lt: Readings,
    load_test_name: str,
    mechanics: str,
    names: tuple[str, ...],
    progress: Callable[[str], None] | None,
) -> _Fitted:
    """The fit of ``names`` to the load test, its calibrated design (checked to load) and the
    calibrated inverse map; CalibrationFailed when the fitted values make a design that does not
    load."""
    design_resp = simulate(
        doc.geometry(), doc.material, mechanics, noise_uT_rms=doc.noise_uT_rms, whole_part=doc.whole_part,
        section=doc.section_rung,
    )  # fmt: skip
    check_field_unit(lt, float(design_resp.B_abs_T[0]), float(design_resp.B_abs_T[design_resp.in_range][-1]))
    check_force_unit(lt, design_resp.B_abs_T[design_resp.in_range], design_resp.force_N[design_resp.in_range])
    check_load_test(lt, len(names), design_resp.max_force_N, cal.MIN_POINTS_PER_PARAMETER, cal.MIN_POINTS)
    sigma = field_sigma_T(doc.noise_uT_rms, lt.setting or design_resp.chip_setting)
    t0 = time.monotonic()
    if progress is not None and len(lt) >= PROGRESS_FROM_SAMPLES:  # say what the next seconds are
        progress(f"fitting {len(lt)} samples of {load_test_name} (seconds; a load test holds at most {MAX_ROWS} rows)")
    fit = cal.fit_parameters(doc, lt.load_N, lt.B_abs_T, sigma, names, mechanics)
    try:
        cal_doc, edits = apply_parameters(doc, fit.values, name=f"{doc.name}-calibrated", mechanics=mechanics)
        cal_dict = document_to_dict(cal_doc)
        parse_document(cal_dict, source=CALIBRATED_YAML)  # it loads as written
        bad = cal_doc.geometry().violations(cal_doc.printer)
        if bad:
            raise CalibrationFailed(
                f"the calibrated cell of layer {(bad[0].layer or 0) + 1} breaks {bad[0].rule}: {bad[0].message}"
            )
        imap, cal_resp = inverse_map(cal_doc, mechanics)
    except InputError as exc:  # the fitted values break a file rule
        raise CalibrationFailed(f"the calibrated design would not load ({exc})") from None
    fit_s = time.monotonic() - t0
    imap.calibrated_to_N = min(float(lt.load_N.max()), float(imap.force_N[-1]))
    chip = choose_setting_for(design_resp, cal_resp, lt)
    setting = chip.setting
    if setting is not None:
        imap.field_resolution_T = max(imap.field_resolution_T, field_resolution_T(setting, doc.noise_uT_rms))
    return _Fitted(lt, mechanics, names, sigma, fit, fit_s, design_resp, cal_doc, cal_dict, edits, imap, cal_resp, chip)


def _header(fitted: _Fitted, source: str) -> tuple[str | None, str | None]:
    """(the C header, None) or (None, why there is none)."""
    if fitted.setting is None:
        return None, "the calibrated field saturates the MLX90393 at full load: no setting to tabulate"
    try:
        header = c_header(
            fitted.imap, fitted.setting, fitted.calibrated.name, source, cal.LIMITATIONS, fitted.chip.header_note()
        )
    except CalibrationFailed as exc:
        return None, str(exc)
    return header, None


@dataclass
class _RecordFiles:
    """The files a record names: the inputs, the calibrated YAML's hash and the tables written."""

    design_file: str
    load_test_file: str
    yaml_sha256: str
    table_size: int
    header_reason: str | None


def _record(
    doc: Document, fitted: _Fitted, files: _RecordFiles, force_errors_in_sample: dict, has_header: bool
) -> CalibrationRecord:
    """calibration.json's content."""
    fit, lt, imap = fitted.fit, fitted.lt, fitted.imap
    design_resp, cal_resp = fitted.design_resp, fitted.cal_resp
    design_regimes, cal_regimes = regime_rows(design_resp), regime_rows(cal_resp)
    return CalibrationRecord(
        schema_version=SCHEMA_VERSION,
        design=files.design_file,
        load_test=files.load_test_file,
        design_constants=design_constants(doc),
        calibrated_yaml=CALIBRATED_YAML,
        calibrated_yaml_sha256=files.yaml_sha256,
        models={
            "mechanics": fitted.mechanics,
            "field": fit.model.field_model,
            "space_mapping_iterations": fit.iterations,
            "load_path": doc.load_path,  # the part's members in series with the layers, or the layers alone
        },
        samples=len(lt),
        force_range_N=[float(lt.load_N.min()), float(lt.load_N.max())],
        fitted_quantity="|B| at the chip (sqrt(Bx^2 + By^2 + Bz^2))",
        chip_setting=fitted.chip.record(),
        noise_sigma_uT=fitted.sigma_T * 1e6,
        parameters=_parameter_entries(fit, fitted.names),
        identifiability=_identifiability(fit),
        residuals={
            "rms_uT": fit.residual_rms_T * 1e6,
            "max_abs_uT": float(np.abs(fit.residual_T).max() * 1e6),
            "chi2_reduced": fit.chi2_reduced,
        },
        force_errors_in_sample=force_errors_in_sample,
        regimes=[{"regime": d["regime"], "design": d, "calibrated": c} for d, c in zip(design_regimes, cal_regimes)],
        range_N={"design": design_resp.max_force_N, "calibrated": cal_resp.max_force_N},
        calibrated_to_N=imap.calibrated_to_N,
        edits=fitted.edits,
        lookup_table=_lookup_table(imap, files, has_header),
        limitations=list(cal.LIMITATIONS),
        mst_version=package_version(),
        curve_check=CalibrationRecord.curve_points(imap),
        fit={"evaluations": fit.evaluations, "seconds": fitted.seconds, "message": fit.message},
    )


def _parameter_entries(fit: cal.FitResult, names: tuple[str, ...]) -> dict:
    """calibration.json's parameters: every parameter's value, uncertainty and why it was held."""
    parameters = {}
    for n, p in PARAMETERS.items():
        entry = {
            "value": fit.values[n],
            "std": fit.std.get(n),
            "design_value": p.nominal,
            "unit": p.unit,
            "typical_deviation": p.scale,
            "description": p.description,
            "requested": n in names,
            "fitted": n in fit.names,
            "identifiable": fit.identifiable.get(n, False) if n in names else None,
        }
        if n in fit.held:
            entry["held_because"] = fit.held[n]
        elif n not in names:
            entry["held_because"] = "not requested (--params): held at the design's value"
        parameters[n] = entry
    return parameters


def _identifiability(fit: cal.FitResult) -> dict:
    """calibration.json's identifiability: the rule, what was fitted and held, and why."""
    return {
        "rule": f"a parameter is identifiable when the data fix it to within {cal.IDENTIFIABLE_STD:.3g} of "
        "its typical deviation (1 sigma); the worst one that is not is held at the design's "
        "value and the fit repeated",
        "fitted": list(fit.names),
        "held": fit.held,
        "singular_values": fit.singular_values,
        "correlation": {"parameters": list(fit.names), "matrix": fit.correlation},
        "first_pass": fit.first_pass,
    }


def _lookup_table(imap: InverseMap, files: _RecordFiles, has_header: bool) -> dict:
    """calibration.json's lookup_table: what lookup.csv (and the C header) hold."""
    return {
        "csv": "lookup.csv",
        "entries": files.table_size,
        "notes": "|B| -> force on the calibrated loading curve from no load to the last "
        "lock, strictly increasing; readings beyond its ends by more than "
        "out_of_range_tolerance_uT are out of range (never extrapolated); "
        "calibrated = 0 marks entries above the load test's largest force "
        "(the fitted model, unchecked by a sample); see limitations",
        "c_header": HEADER_FILE if has_header else None,
        **({"c_header_reason": files.header_reason} if files.header_reason else {}),
        "out_of_range_tolerance_uT": imap.tolerance_T * 1e6,
    }
