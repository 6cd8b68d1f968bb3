"""``mst calibrate`` (fit a printed sensor to its load test) and ``mst read`` (readings -> forces).

The physics lives in :mod:`mst_cli.calibrate.fit` (fit, calibrated design, inverse map), the
input files in :mod:`mst_cli.calibrate.loadtest` and the serial lines in :mod:`mst_cli.io.serial_lines`;
this module parses options, calls them and writes the files (atomically: all or none).
"""

from __future__ import annotations

import hashlib
import io
import json
import math
import sys
import time
from pathlib import Path
from typing import TYPE_CHECKING

import click

from mst_cli import __version__
from mst_cli.cli.common import EXIT_TARGETS, default_out_dir, handles_input_errors, no_plot_option

if TYPE_CHECKING:
    import numpy as np

MECHANICS = ["spring", "frame", "continuum"]
BAUD_RATES = (1200, 2400, 4800, 9600, 19200, 38400, 57600, 115200, 230400, 460800, 921600)
CALIBRATION_JSON = "calibration.json"
CALIBRATED_YAML = "calibrated.yaml"
HEADER_FILE = "force_table.h"
SCHEMA_VERSION = 1
ERROR_FROM_RANGE = 0.1     # force errors are quoted on readings above this fraction of the range
PROGRESS_FROM_SAMPLES = 10_000   # a load test this long gets a progress line (40 000 samples: 2-3 s)


def _fail_fit(reason: str, what: str = "calibration failed"):
    from mst_cli.cli.common import one_line
    click.echo(one_line(f"mst: {what}: {reason}; nothing was written"), err=True)
    sys.exit(EXIT_TARGETS)


def _parse_params(text: str) -> tuple[str, ...]:
    from mst_cli.calibrate.fit import PARAMETERS
    from mst_cli.errors import InputError

    names = [n.strip() for n in text.split(",") if n.strip()]
    if not names:
        raise InputError("--params", text, "one or more of " + ", ".join(PARAMETERS))
    for n in names:
        if n not in PARAMETERS:
            raise InputError("--params", n, "unknown parameter; allowed: " + ", ".join(PARAMETERS))
    if len(set(names)) != len(names):
        raise InputError("--params", text, "a parameter is named twice")
    return tuple(names)


def force_errors(F_model, F_true, range_N: float) -> dict:
    """Relative force errors on readings above ERROR_FROM_RANGE of the range (NaN = flagged)."""
    import numpy as np

    F_model, F_true = np.asarray(F_model, dtype=float), np.asarray(F_true, dtype=float)
    use = (F_true >= ERROR_FROM_RANGE * range_N) & (F_true > 0)
    flagged = int(np.sum(use & ~np.isfinite(F_model)))
    ok = use & np.isfinite(F_model)
    if not ok.any():
        return {"readings": int(use.sum()), "flagged": flagged}
    rel = np.abs(F_model[ok] - F_true[ok]) / F_true[ok]
    return {"readings": int(use.sum()), "flagged": flagged,
            "from_force_N": ERROR_FROM_RANGE * range_N,
            "median_rel": float(np.median(rel)), "p95_rel": float(np.percentile(rel, 95)),
            "max_rel": float(rel.max()),
            "rms_N": float(np.sqrt(np.mean((F_model[ok] - F_true[ok]) ** 2)))}


def _regime_rows(resp):
    import math as _m
    return [{"regime": r.index, "locking_layer": r.layer, "force_from_N": r.force_from_N,
             "force_to_N": r.force_to_N, "sensitivity_secant_per_N": r.sensitivity_secant_per_N,
             "k_effective_N_per_mm": r.k_effective_N_per_mm,
             "force_resolution_N": r.force_resolution_N if _m.isfinite(r.force_resolution_N) else None}
            for r in resp.regimes]


# --------------------------------------------------------------------------- output writers
def lookup_csv(imap, setting, n: int) -> str:
    from mst_cli.model.chip import quantise_lsb

    B, Bz, F, regime, res = imap.table(n)
    buf = io.StringIO()
    code_col = setting is not None
    top = imap.calibrated_to_N if imap.calibrated_to_N is not None else float("inf")
    buf.write("B_abs_uT,Bz_uT," + ("Bz_code_lsb," if code_col else "")
              + "force_N,force_mN,regime,force_resolution_N,calibrated\n")
    codes = quantise_lsb(Bz, setting.z_uT_per_lsb) if code_col else None
    for i in range(len(B)):
        buf.write(f"{B[i] * 1e6:.6f},{Bz[i] * 1e6:.6f}," + (f"{int(codes[i])}," if code_col else "")
                  + f"{F[i]:.9g},{F[i] * 1e3:.6g},{int(regime[i])},{res[i]:.6g},{int(F[i] <= top * (1 + 1e-9))}\n")
    return buf.getvalue()


def c_float(value: float, digits: int = 4) -> str:
    """A C float literal (always with a point or an exponent before the f suffix)."""
    text = f"{value:.{digits}g}"
    return text + ("f" if any(c in text for c in ".en") else ".0f")


def c_header(imap, setting, name: str, sources: str, limitations) -> str:
    """A C99 header: raw |Z| code -> force in mN, with the regime and resolution of each entry
    and a lookup function that flags out-of-range and saturated codes."""
    import numpy as np

    from mst_cli.model.chip import CODE_RANGE_LSB, SATURATION_T

    codes, F, regime, res = imap.z_code_table(setting)
    n = len(codes)
    tol = max(1, int(math.ceil(imap.tolerance_T / (setting.z_uT_per_lsb * 1e-6))))
    limit = min(CODE_RANGE_LSB[setting.res] - 1, int(SATURATION_T / (setting.z_uT_per_lsb * 1e-6)))
    top_N = imap.calibrated_to_N if imap.calibrated_to_N is not None else float(imap.force_N[-1])
    top_code = int(math.floor(abs(float(np.interp(top_N, imap.force_N, imap.Bz_T))) / (setting.z_uT_per_lsb * 1e-6)))
    guard = "MST_FORCE_TABLE_H"

    def arr(ctype, cname, values, fmt, per_line=10):
        lines = []
        for i in range(0, len(values), per_line):
            lines.append("    " + ", ".join(fmt(v) for v in values[i:i + per_line]))
        return f"static const {ctype} {cname}[MST_TABLE_LEN] = {{\n" + ",\n".join(lines) + "\n};\n"

    text_lim = "\n".join(f" *   - {line}" for line in limitations)
    return f"""/* {HEADER_FILE}: force from the MLX90393's raw Z code for ONE printed sensor ({name}).
 * Generated by mst calibrate from {sources}. Do not edit: re-run mst calibrate.
 *
 * Assumes the chip at GAIN_SEL = {setting.gain_sel}, RES = {setting.res} (HALLCONF 0xC, TCMP off):
 * {setting.z_uT_per_lsb} uT per LSB on Z. Codes read at any other GAIN_SEL/RES are NOT valid here.
 * Index: |Z code| (the magnet may face either way); the table runs from no load to the last
 * layer lock, strictly increasing in code and in force, linearly interpolated between entries.
 * Codes below/above the table by more than MST_Z_TOLERANCE_LSB (3 field resolutions) are out
 * of range and return a flag, never an extrapolated force. Codes above the load test's largest
 * force (MST_Z_CALIBRATED_LSB) return the model's force with the flag MST_ABOVE_CALIBRATED.
 *
 * What this table cannot know:
{text_lim}
 */
#ifndef {guard}
#define {guard}

#include <stdint.h>

#define MST_GAIN_SEL {setting.gain_sel}
#define MST_RES {setting.res}
#define MST_Z_UT_PER_LSB {c_float(setting.z_uT_per_lsb, 6)}
#define MST_TABLE_LEN {n}
#define MST_Z_TOLERANCE_LSB {tol}
#define MST_Z_SATURATED_LSB {limit}
#define MST_FORCE_FULL_MN {int(round(F[-1] * 1e3))}
#define MST_Z_CALIBRATED_LSB {top_code}
#define MST_FORCE_CALIBRATED_MN {int(round(top_N * 1e3))}
#define MST_N_REGIMES {imap.n_regimes}

enum mst_flag {{ MST_OK = 0, MST_BELOW_RANGE = 1, MST_ABOVE_RANGE = 2, MST_SATURATED = 3,
                MST_ABOVE_CALIBRATED = 4 }};

/* |Z| code of each entry, strictly increasing */
{arr("int32_t", "mst_z_code", codes, lambda v: str(int(v)))}
/* force at each entry, mN (non-decreasing) */
{arr("int32_t", "mst_force_mN", F, lambda v: str(int(round(v * 1e3))))}
/* regime (1 = softest band) of each entry */
{arr("uint8_t", "mst_regime", regime, lambda v: str(int(v)), per_line=20)}
/* force resolution at each entry, mN (chip noise or LSB over the local slope) */
{arr("float", "mst_resolution_mN", res, lambda v: c_float(v * 1e3), per_line=8)}
/* Force in mN from a raw Z code. Returns MST_OK (or MST_ABOVE_CALIBRATED) and sets *force_mN
 * and *regime, or another flag (then the outputs are left untouched). */
static inline int mst_force_from_z(int32_t z_code, int32_t *force_mN, uint8_t *regime)
{{
    int32_t z = z_code < 0 ? -z_code : z_code;
    int32_t lo = 0, hi = MST_TABLE_LEN - 1;
    if (z >= MST_Z_SATURATED_LSB) return MST_SATURATED;
    if (z < mst_z_code[0] - MST_Z_TOLERANCE_LSB) return MST_BELOW_RANGE;
    if (z > mst_z_code[MST_TABLE_LEN - 1] + MST_Z_TOLERANCE_LSB) return MST_ABOVE_RANGE;
    if (z <= mst_z_code[0]) {{ *force_mN = mst_force_mN[0]; *regime = mst_regime[0]; return MST_OK; }}
    if (z >= mst_z_code[hi]) {{
        *force_mN = mst_force_mN[hi]; *regime = mst_regime[hi];
        return z > MST_Z_CALIBRATED_LSB + MST_Z_TOLERANCE_LSB ? MST_ABOVE_CALIBRATED : MST_OK;
    }}
    while (hi - lo > 1) {{
        int32_t mid = lo + (hi - lo) / 2;
        if (mst_z_code[mid] <= z) lo = mid; else hi = mid;
    }}
    *force_mN = mst_force_mN[lo] + (int32_t)(((int64_t)(mst_force_mN[hi] - mst_force_mN[lo])
                 * (z - mst_z_code[lo])) / (mst_z_code[hi] - mst_z_code[lo]));
    *regime = mst_regime[lo];
    return z > MST_Z_CALIBRATED_LSB + MST_Z_TOLERANCE_LSB ? MST_ABOVE_CALIBRATED : MST_OK;
}}

#endif /* {guard} */
"""


def plot_calibration(path: Path, F: np.ndarray, B_meas_T: np.ndarray, design_model: tuple[np.ndarray, np.ndarray],
                     cal_model: tuple[np.ndarray, np.ndarray], residual_T: np.ndarray, sigma_T: float,
                     title: str) -> None:
    """Measured |B| against force with the design's and the calibrated curves; residuals."""
    from matplotlib.figure import Figure

    fig = Figure(figsize=(10, 4.2))
    ax1, ax2 = fig.subplots(1, 2)
    fig.subplots_adjust(left=0.08, right=0.98, bottom=0.12, top=0.9, wspace=0.25)
    ax1.plot(F, B_meas_T * 1e3, ".", color="k", ms=4, label="load test")
    for (Fm, Bm), label, style in ((design_model, "design", "C3--"), (cal_model, "calibrated", "C0-")):
        ax1.plot(Fm, Bm * 1e3, style, label=label)
    ax1.set_xlabel("force F [N]")
    ax1.set_ylabel("|B| at the chip [mT]")
    ax1.legend(loc="upper left")
    ax1.grid(alpha=0.3)
    ax2.axhspan(-2 * sigma_T * 1e6, 2 * sigma_T * 1e6, color="C0", alpha=0.12, label="+-2 sigma noise")
    ax2.plot(F, residual_T * 1e6, ".", color="C0", label="measured - calibrated")
    ax2.set_xlabel("force F [N]")
    ax2.set_ylabel("residual |B| [uT]")
    ax2.legend(loc="upper left", fontsize=8)
    ax2.grid(alpha=0.3)
    fig.suptitle(title)
    fig.savefig(path, dpi=110, format="png")


# --------------------------------------------------------------------------- calibrate
@click.command()
@click.argument("design_file", type=click.Path(dir_okay=False, path_type=Path))
@click.argument("load_test", type=click.Path(dir_okay=False, path_type=Path))
@click.option("--out", "out_dir", type=click.Path(file_okay=False, path_type=Path), default=None,
              help="Output folder [default: ./mst-out/<name>-calibration/].")
@click.option("--mechanics", type=click.Choice(MECHANICS), default="spring", show_default=True,
              help="Layer mechanics of the fit: spring is milliseconds per evaluation; frame and "
                   "continuum are fitted by space mapping on spring (a few dear evaluations).")
@click.option("--params", "params", default="modulus_factor,wall_offset_mm,gap_offset_mm,remanence_factor",
              show_default=True, help="Parameters to fit (comma separated).")
@click.option("--gain-sel", type=click.IntRange(0, 7), default=None,
              help="GAIN_SEL the load test was read at (needed for raw codes; the C header's setting).")
@click.option("--res", type=click.IntRange(0, 3), default=None, help="RES the load test was read at.")
@click.option("--table-size", type=click.IntRange(16, 4096), default=256, show_default=True,
              help="Entries of the lookup table (CSV and C header).")
@no_plot_option("calibration.png", "about 40 % of a run: 0.45 s of matplotlib import and render", has_json=False)
@handles_input_errors
def calibrate(design_file: Path, load_test: Path, out_dir: Path | None, mechanics: str, params: str,
              gain_sel: int | None, res: int | None, table_size: int, no_plot: bool) -> None:
    """Fit DESIGN_FILE's print parameters to a LOAD_TEST of the printed sensor.

    LOAD_TEST is a CSV with force_N,Bx_uT,By_uT,Bz_uT (or raw codes Bx_code_lsb,By_code_lsb,
    Bz_code_lsb with --gain-sel/--res). Fits the effective modulus, a wall-thickness offset,
    a magnet-chip gap offset and the remanence; reports which the data cannot identify and
    holds those at the design's values. Writes calibrated.yaml (loadable by mst simulate and
    mst read), calibration.json (values, uncertainties, residuals, S_i and R_i against the
    design's), residuals.csv, lookup.csv, force_table.h (raw Z code -> mN) and
    calibration.png (not with --no-plot). Exit 2 on bad input, 1 when the fit fails (with why); nothing is
    written then.
    """
    import numpy as np
    import yaml

    from mst_cli.calibrate import fit as cal
    from mst_cli.calibrate.loadtest import MAX_ROWS, check_load_test, parse_readings, read_text
    from mst_cli.calibrate.record import CONSTANTS_KEY as design_constants_key
    from mst_cli.calibrate.record import design_constants
    from mst_cli.errors import InputError
    from mst_cli.io.outputs import check_out_dir, finite_or_none, staged
    from mst_cli.io.schema import document_to_dict, parse_document
    from mst_cli.model.chip import field_resolution_T
    from mst_cli.model.response import simulate

    names = _parse_params(params)
    from mst_cli.io.schema import load_design_document
    doc, geometry = load_design_document(design_file)
    out = out_dir or default_out_dir(f"{doc.name}-calibration")
    check_out_dir(out)
    lt = parse_readings(read_text(load_test), str(load_test), need_force=True, gain_sel=gain_sel,
                        res=res, one_setting=True)
    design_resp = simulate(geometry, doc.material, mechanics=mechanics, noise_uT_rms=doc.noise_uT_rms)
    check_load_test(lt, len(names), design_resp.max_force_N, cal.MIN_POINTS_PER_PARAMETER, cal.MIN_POINTS)

    setting_for_noise = lt.setting or design_resp.chip_setting
    sigma = cal.field_sigma_T(doc.noise_uT_rms, setting_for_noise)
    t0 = time.monotonic()
    if len(lt) >= PROGRESS_FROM_SAMPLES:      # a long load test: say what the next seconds are
        click.echo(f"mst calibrate: fitting {len(lt)} samples of {Path(load_test).name} "
                   f"(seconds; a load test holds at most {MAX_ROWS} rows)", err=True)
    try:
        fit = cal.fit_parameters(doc, lt.force_N, lt.B_abs_T, sigma, names, mechanics)
        cal_doc, edits = cal.apply_parameters(doc, fit.values, name=f"{doc.name}-calibrated",
                                              mechanics=mechanics)
        cal_dict = document_to_dict(cal_doc)
        parse_document(cal_dict, source=CALIBRATED_YAML)          # it loads as written
        bad = cal_doc.geometry().violations(cal_doc.printer)
        if bad:
            raise cal.CalibrationFailed(f"the calibrated cell of layer {bad[0][0] + 1} breaks "
                                        f"{bad[0][1].rule}: {bad[0][1].message}")
        imap, cal_resp = cal.inverse_map(cal_doc, mechanics)
    except cal.CalibrationFailed as exc:
        _fail_fit(str(exc))
    except InputError as exc:                                    # the fitted values break a file rule
        _fail_fit(f"the calibrated design would not load ({exc})")
    fit_s = time.monotonic() - t0

    imap.calibrated_to_N = min(float(lt.force_N.max()), float(imap.force_N[-1]))
    header_setting = lt.setting or cal_resp.chip_setting
    if header_setting is not None:
        imap.field_resolution_T = max(imap.field_resolution_T,
                                      field_resolution_T(header_setting, doc.noise_uT_rms))
    header_text, header_reason = None, None
    if header_setting is None:
        header_reason = "the calibrated field saturates the MLX90393 at full load: no setting to tabulate"
    else:
        try:
            header_text = c_header(imap, header_setting, cal_doc.name,
                                   f"{Path(design_file).name} and {Path(load_test).name}", cal.LIMITATIONS)
        except cal.CalibrationFailed as exc:
            header_reason = str(exc)

    F_fit, _, flag_fit = imap.force(lt.B_abs_T, lt.saturated)
    in_sample = force_errors(F_fit, lt.force_N, cal_resp.max_force_N)
    try:
        F_design, _, _ = cal.InverseMap.from_response(design_resp).force(lt.B_abs_T)
        design_errors = force_errors(F_design, lt.force_N, cal_resp.max_force_N)
    except cal.CalibrationFailed:
        design_errors = {}

    yaml_text = ("# The design as printed: mst calibrate fitted it to a load test (calibration.json beside it).\n"
                 "# It models the printed sensor for mst simulate and mst read; it is not a file to print.\n"
                 + yaml.safe_dump(cal_dict, sort_keys=False, default_flow_style=None))
    std = fit.std
    parameters = {}
    for n, p in cal.PARAMETERS.items():
        entry = {"value": fit.values[n], "std": std.get(n), "design_value": p.nominal, "unit": p.unit,
                 "typical_deviation": p.scale, "description": p.description,
                 "requested": n in names, "fitted": n in fit.names,
                 "identifiable": fit.identifiable.get(n, False) if n in names else None}
        if n in fit.held:
            entry["held_because"] = fit.held[n]
        elif n not in names:
            entry["held_because"] = "not requested (--params): held at the design's value"
        parameters[n] = entry
    setting_record = None
    if header_setting is not None:
        setting_record = {"gain_sel": header_setting.gain_sel, "res": header_setting.res,
                          "z_uT_per_lsb": header_setting.z_uT_per_lsb,
                          "xy_uT_per_lsb": header_setting.xy_uT_per_lsb,
                          "source": "the load test" if lt.setting is not None else
                                    "the finest setting that holds the calibrated field (the load test gave uT)"}
    design_regimes, cal_regimes = _regime_rows(design_resp), _regime_rows(cal_resp)
    report = {
        "schema_version": SCHEMA_VERSION,
        "design": str(design_file), "load_test": str(load_test),
        # what the fitted factors multiply: mst design --calibration reads them (calibrate.record)
        design_constants_key: design_constants(doc),
        "calibrated_yaml": CALIBRATED_YAML,
        "calibrated_yaml_sha256": hashlib.sha256(yaml_text.encode()).hexdigest(),
        "models": {"mechanics": mechanics, "field": fit.model.field_model,
                   "space_mapping_iterations": fit.iterations},
        "samples": len(lt), "force_range_N": [float(lt.force_N.min()), float(lt.force_N.max())],
        "fitted_quantity": "|B| at the chip (sqrt(Bx^2 + By^2 + Bz^2))",
        "chip_setting": setting_record,
        "noise_sigma_uT": sigma * 1e6,
        "parameters": parameters,
        "identifiability": {
            "rule": f"a parameter is identifiable when the data fix it to within {cal.IDENTIFIABLE_STD:.3g} of "
                    "its typical deviation (1 sigma); the worst one that is not is held at the design's "
                    "value and the fit repeated",
            "fitted": list(fit.names),
            "held": fit.held,
            "singular_values": fit.singular_values,
            "correlation": {"parameters": list(fit.names), "matrix": fit.correlation},
            "first_pass": fit.first_pass,
        },
        "residuals": {"rms_uT": fit.residual_rms_T * 1e6, "max_abs_uT": float(np.abs(fit.residual_T).max() * 1e6),
                      "chi2_reduced": fit.chi2_reduced},
        "force_errors_in_sample": {"calibrated": in_sample, "design": design_errors},
        "regimes": [{"regime": d["regime"], "design": d, "calibrated": c}
                    for d, c in zip(design_regimes, cal_regimes)],
        "range_N": {"design": design_resp.max_force_N, "calibrated": cal_resp.max_force_N},
        "calibrated_to_N": imap.calibrated_to_N,
        "edits": edits,
        "lookup_table": {"csv": "lookup.csv", "entries": table_size,
                         "notes": "|B| -> force on the calibrated loading curve from no load to the last "
                                  "lock, strictly increasing; readings beyond its ends by more than "
                                  "out_of_range_tolerance_uT are out of range (never extrapolated); "
                                  "calibrated = 0 marks entries above the load test's largest force "
                                  "(the fitted model, unchecked by a sample); see limitations",
                         "c_header": HEADER_FILE if header_text else None,
                         **({"c_header_reason": header_reason} if header_reason else {}),
                         "out_of_range_tolerance_uT": imap.tolerance_T * 1e6},
        "limitations": list(cal.LIMITATIONS),
        "mst_version": __version__,
        # the calibrated curve at a few forces: mst read recomputes it and warns when the model
        # code has changed since (the file's keys alone would then mean another curve)
        "curve_check": {"force_N": [float(f) for f in np.linspace(0.0, imap.force_N[-1], 9)],
                        "B_abs_uT": [float(b) * 1e6 for b in np.interp(np.linspace(0.0, imap.force_N[-1], 9),
                                                                        imap.force_N, imap.B_abs_T)]},
        "fit": {"evaluations": fit.evaluations, "seconds": fit_s, "message": fit.message},
    }

    F_grid = np.linspace(0.0, max(float(lt.force_N.max()), cal_resp.max_force_N), 400)
    design_curve = (design_resp.force_N[design_resp.in_range], design_resp.B_abs_T[design_resp.in_range])
    cal_curve = (F_grid, fit.model.field_abs_T(F_grid, fit.values))
    res_buf = io.StringIO()
    res_buf.write("line,force_N,B_abs_measured_uT,B_abs_model_uT,residual_uT,force_model_N,flag\n")
    B_model = fit.model.field_abs_T(lt.force_N, fit.values)
    for i in range(len(lt)):
        f = "" if not math.isfinite(F_fit[i]) else f"{F_fit[i]:.9g}"
        res_buf.write(f"{lt.lines[i]},{lt.force_N[i]:.9g},{lt.B_abs_T[i] * 1e6:.6f},{B_model[i] * 1e6:.6f},"
                      f"{fit.residual_T[i] * 1e6:.6f},{f},{flag_fit[i]}\n")

    with staged(out) as st:
        st.write_text(CALIBRATED_YAML, yaml_text)
        st.write_json(CALIBRATION_JSON, finite_or_none(report))
        st.write_text("residuals.csv", res_buf.getvalue())
        st.write_text("lookup.csv", lookup_csv(imap, header_setting, table_size))
        if header_text:
            st.write_text(HEADER_FILE, header_text)
        if no_plot:
            st.remove("calibration.png")
        else:
            plot_calibration(st.path("calibration.png"), lt.force_N, lt.B_abs_T, design_curve, cal_curve,
                             fit.residual_T, sigma,
                             f"{doc.name}: load test against the design and the calibrated model")

    click.echo(_summary(doc, lt, load_test, mechanics, fit, names, design_regimes, cal_regimes, sigma,
                        in_sample, design_errors, header_setting))
    click.echo(f"wrote {out}/{CALIBRATED_YAML}, {CALIBRATION_JSON}, residuals.csv, lookup.csv"
               + (f", {HEADER_FILE}" if header_text else "") + ("" if no_plot else ", calibration.png")
               + (f" (no C header: {header_reason})" if header_reason else ""))


def _summary(doc, lt, load_test, mechanics, fit, names, design_regimes, cal_regimes, sigma,
             in_sample, design_errors, setting) -> str:
    from mst_cli.calibrate.fit import PARAMETERS

    lines = [f"{doc.name}: calibrated from {Path(load_test).name} ({len(lt)} samples, "
             f"{lt.force_N.min():.3g}-{lt.force_N.max():.4g} N), mechanics={mechanics}",
             f"{'parameter':<18} {'design':>8} {'fitted':>10} {'+-1 sigma':>10}  identifiable"]
    for n, p in PARAMETERS.items():
        unit = f" {p.unit}" if p.unit else ""
        if n in fit.names:
            ident = "yes" if fit.identifiable[n] else "NO: the data barely fix it (the last one left)"
            lines.append(f"{n:<18} {p.nominal:>8g} {fit.values[n]:>10.4f} {fit.std[n]:>10.2g}{unit:<3} {ident}")
        elif n in fit.held:
            lines.append(f"{n:<18} {p.nominal:>8g} {'(held)':>10} {'':>10}{'':<3} NO: held at the design's value")
        else:
            lines.append(f"{n:<18} {p.nominal:>8g} {'(held)':>10} {'':>10}{'':<3} not requested")
    lines.append(f"residual |B| {fit.residual_rms_T * 1e6:.3g} uT RMS (noise {sigma * 1e6:.3g} uT, "
                 f"chi2/dof {fit.chi2_reduced:.3g})")
    lines.append(f"{'regime':>6} {'R design':>9} {'R calib.':>9} {'S design':>9} {'S calib.':>9} {'dF calib.':>9}")
    lines.append(f"{'':>6} {'[N]':>9} {'[N]':>9} {'[1/N]':>9} {'[1/N]':>9} {'[mN]':>9}")
    for d, c in zip(design_regimes, cal_regimes):
        dF = f"{c['force_resolution_N'] * 1e3:9.2f}" if c["force_resolution_N"] is not None else f"{'-':>9}"
        lines.append(f"{d['regime']:>6} {d['force_to_N']:>9.3f} {c['force_to_N']:>9.3f} "
                     f"{d['sensitivity_secant_per_N']:>9.4f} {c['sensitivity_secant_per_N']:>9.4f} {dF}")
    if "median_rel" in in_sample:
        design_part = (f"design {100 * design_errors['median_rel']:.3g} %" if "median_rel" in design_errors
                       else "design: all flagged")
        lines.append(f"forces of the load test from its own readings (F >= {in_sample['from_force_N']:.3g} N): "
                     f"median error calibrated {100 * in_sample['median_rel']:.3g} % (95th pct "
                     f"{100 * in_sample['p95_rel']:.3g} %), {design_part}"
                     + (f", {design_errors['flagged']} out of the design's range"
                        if design_errors.get("flagged") else ""))
    if setting is not None:
        lines.append(f"table for GAIN_SEL {setting.gain_sel}, RES {setting.res} "
                     f"({setting.z_uT_per_lsb} uT/LSB on Z)")
    return "\n".join(lines)


# --------------------------------------------------------------------------- read
def _calibration_note(model_file: Path) -> tuple[str | None, dict | None]:
    """(None, the record) when MODEL has a matching calibration.json beside it, else (a warning
    sentence, None)."""
    from mst_cli.io.files import read_input_text
    from mst_cli.io.yaml_io import MAX_INPUT_BYTES
    sidecar = Path(model_file).with_name(CALIBRATION_JSON)
    try:               # regular files only: a FIFO in their place must not block
        record = json.loads(read_input_text(sidecar, MAX_INPUT_BYTES, field=CALIBRATION_JSON))
        text = read_input_text(model_file, MAX_INPUT_BYTES)
    except ValueError:                   # InputError (unreadable, not a file) and bad JSON
        return (f"{Path(model_file).name} has no {CALIBRATION_JSON} beside it: forces come from the "
                "design as drawn, not as printed (run mst calibrate; expect errors of tens of percent)"), None
    digest = hashlib.sha256(text.encode()).hexdigest()
    if not isinstance(record, dict) or record.get("calibrated_yaml_sha256") != digest:
        return (f"{CALIBRATION_JSON} beside {Path(model_file).name} belongs to another file: forces may "
                "not be calibrated"), None
    return None, record


@click.command("read")
@click.argument("model_file", type=click.Path(dir_okay=False, path_type=Path))
@click.argument("readings", required=False, type=click.Path(dir_okay=False, path_type=Path))
@click.option("--serial", "port", default=None, metavar="PORT",
              help="Read a live stream from this serial port (one sample per line) instead of a file.")
@click.option("--baud", type=click.Choice([str(b) for b in BAUD_RATES]), default="115200", show_default=True,
              help="Baud rate of --serial.")
@click.option("--count", type=click.IntRange(min=1), default=None,
              help="Stop --serial after this many samples [default: until the port closes or Ctrl-C].")
@click.option("--timeout", "timeout_s", type=click.FloatRange(min=0.0, min_open=True), default=None,
              help="Stop --serial after this many seconds without a byte.")
@click.option("--raw", is_flag=True, help="--serial lines carry raw codes (needs --gain-sel/--res).")
@click.option("--gain-sel", type=click.IntRange(0, 7), default=None, help="GAIN_SEL of raw codes.")
@click.option("--res", type=click.IntRange(0, 3), default=None, help="RES of raw codes.")
@click.option("--mechanics", type=click.Choice(MECHANICS), default=None,
              help="Layer mechanics [default: the model file's model.mechanics].")
@click.option("--out", "out_dir", type=click.Path(file_okay=False, path_type=Path), default=None,
              help="Output folder of forces.csv [default: ./mst-out/<name>-read/; with --serial "
                   "only when given].")
@handles_input_errors
def read(model_file: Path, readings: Path | None, port: str | None, baud: str, count: int | None,
         timeout_s: float | None, raw: bool, gain_sel: int | None, res: int | None, mechanics: str | None,
         out_dir: Path | None) -> None:
    """Turn MLX90393 readings into forces with MODEL_FILE (a calibrated.yaml).

    READINGS is a CSV with Bx_uT,By_uT,Bz_uT (or Bx_code_lsb,By_code_lsb,Bz_code_lsb with
    --gain-sel/--res); forces.csv gets the input columns plus force_N, regime, flag and
    force_resolution_N. With --serial PORT the lines of an Arduino MLX90393 sketch
    ("X: 12.3 \\tY: -4.5 \\tZ: 321.0 uTesla", "12.3,-4.5,321.0", ...) are shown live
    (and written to forces.csv with --out).

    Flags: above_calibrated (the model's force above the load test's largest force),
    below_range, above_range (past the last lock) and saturated (force left empty: never
    extrapolated).
    """
    from mst_cli.calibrate import fit as cal
    from mst_cli.calibrate.loadtest import parse_readings, read_text, setting_of
    from mst_cli.errors import InputError
    from mst_cli.io.outputs import check_out_dir
    from mst_cli.model.chip import field_resolution_T

    baud = int(baud)
    if (readings is None) == (port is None):
        raise click.UsageError("give READINGS.csv or --serial PORT (one of them)")
    if raw and port is None:
        raise click.UsageError("--raw is for --serial lines (a CSV says raw by its column names)")
    from mst_cli.io.schema import load_design_document
    doc, _ = load_design_document(model_file)
    if (gain_sel is None) != (res is None):
        raise InputError("--gain-sel/--res", f"{gain_sel}/{res}", "give both GAIN_SEL and RES, or neither")
    setting = setting_of(gain_sel, res) if gain_sel is not None else None
    if raw and setting is None:
        raise InputError("--gain-sel/--res", None, "--raw codes need the chip setting: give --gain-sel and --res")
    out = out_dir if (out_dir is not None or port is not None) else default_out_dir(f"{doc.name}-read")
    if out is not None:
        check_out_dir(out)
    from mst_cli.model.ladder import choose_mechanics
    choice = choose_mechanics(mechanics, doc.accuracy_rel, doc.mechanics)
    rd = None
    if readings is not None:
        rd = parse_readings(read_text(readings), str(readings), need_force=False, gain_sel=gain_sel, res=res)
        if len(rd) == 0:
            raise InputError(str(readings), "(no rows)", "has a header but no readings")
        setting = setting or rd.setting
    try:
        imap, resp = cal.inverse_map(doc, choice.mechanics)
    except cal.CalibrationFailed as exc:
        _fail_fit(str(exc), "no inverse map")
    chip = setting or resp.chip_setting
    if chip is not None:
        imap.field_resolution_T = max(imap.field_resolution_T, field_resolution_T(chip, doc.noise_uT_rms))
    note, record = _calibration_note(model_file)
    top = record.get("calibrated_to_N") if record else None
    if isinstance(top, (int, float)) and math.isfinite(top) and top > 0:
        imap.calibrated_to_N = min(float(top), float(imap.force_N[-1]))
    if note is None:
        note = _curve_changed(record, imap)
    if note:
        click.echo(f"mst read: warning: {note}", err=True)
    if rd is not None:
        _read_file(doc, imap, rd, out)
    else:
        _read_serial(doc, imap, port, baud, count, timeout_s, raw, setting, out)


def _curve_changed(record: dict, imap) -> str | None:
    """A warning when the model no longer gives the curve calibration.json recorded."""
    import numpy as np

    check = record.get("curve_check") if isinstance(record, dict) else None
    try:
        F = np.asarray(check["force_N"], dtype=float)
        B = np.asarray(check["B_abs_uT"], dtype=float) * 1e-6
    except (TypeError, KeyError, ValueError):
        return None
    now = np.interp(F, imap.force_N, imap.B_abs_T)
    worst = float(np.max(np.abs(now - B))) if len(F) else 0.0
    if worst > imap.field_resolution_T:
        return (f"the model now gives a calibrated curve up to {worst * 1e6:.3g} uT away from the one "
                f"recorded at calibration (mst {record.get('mst_version', '?')}; field resolution "
                f"{imap.field_resolution_T * 1e6:.3g} uT): the model code changed, re-run mst calibrate")
    return None


def _fmt(v, spec=".9g"):
    return "" if v is None or (isinstance(v, float) and not math.isfinite(v)) else format(v, spec)


def _read_file(doc, imap, rd, out):
    import numpy as np

    from mst_cli.io.outputs import staged

    F, regime, flag = imap.force(rd.B_abs_T, rd.saturated)
    res = imap.local_resolution_N(np.where(np.isfinite(F), F, 0.0))
    has_force = np.isfinite(F)
    header = ["force_N_reference" if h == "force_N" else h for h in rd.header]
    buf = io.StringIO()
    buf.write(",".join(header + ["force_N", "regime", "flag", "force_resolution_N"]) + "\n")
    for i, row in enumerate(rd.rows):
        ok = bool(has_force[i])
        cells = [c if "," not in c and '"' not in c else '"' + c.replace('"', '""') + '"' for c in row]
        buf.write(",".join(cells + [_fmt(float(F[i])), str(int(regime[i])) if ok else "", flag[i],
                                    _fmt(float(res[i]), ".6g") if ok else ""]) + "\n")
    with staged(out) as st:
        st.write_text("forces.csv", buf.getvalue())
    counts = {k: int(np.sum(flag == k)) for k in cal_flags()}
    ok = np.isfinite(F)
    lines = [f"{doc.name}: {len(rd)} readings: {counts['ok']} in range"
             + "".join(f", {counts[k]} {k.replace('_', ' ')}"
                       for k in ("above_calibrated", "below_range", "above_range", "saturated") if counts[k])
             + (f"; forces {np.nanmin(F):.4g}-{np.nanmax(F):.4g} N" if ok.any() else "")]
    if rd.force_N is not None and len(rd) and float(np.max(rd.force_N)) > 0:
        ref = rd.force_N
        err = force_errors(F, ref, float(np.max(ref)))      # the same readings for any model
        if "median_rel" in err:
            lines.append(f"against force_N_reference (readings >= {err['from_force_N']:.3g} N): median error "
                         f"{100 * err['median_rel']:.3g} %, 95th percentile {100 * err['p95_rel']:.3g} %, "
                         f"max {100 * err['max_rel']:.3g} %, RMS {err['rms_N']:.4g} N"
                         + (f"; {err['flagged']} flagged" if err["flagged"] else ""))
        elif err["readings"]:
            lines.append(f"against force_N_reference: all {err['readings']} readings >= "
                         f"{ERROR_FROM_RANGE:g} x range are flagged")
    click.echo("\n".join(lines))
    click.echo(f"wrote {out}/forces.csv")


def cal_flags() -> tuple[str, ...]:
    from mst_cli.calibrate.fit import FLAGS
    return FLAGS


def _read_serial(doc, imap, port, baud, count, timeout_s, raw, setting, out):
    import numpy as np

    from mst_cli.calibrate.loadtest import field_of
    from mst_cli.io.outputs import staged
    from mst_cli.io.serial_lines import LineSource, SampleParser

    src = LineSource(port, baud, timeout_s)
    samples = []
    parser = SampleParser(raw)
    t0 = time.monotonic()
    click.echo(f"{doc.name}: reading {port} at {baud} baud (Ctrl-C to stop)", err=True)
    try:
        for line in src:
            values = parser.feed(line)
            if values is None:
                continue
            B, sat = field_of(values, raw, setting, f"{port} sample {len(samples) + 1}")
            Babs = float(np.linalg.norm(B))
            F, regime, flag = imap.force(np.array([Babs]), np.array([sat]))
            f, r, fl = float(F[0]), int(regime[0]), str(flag[0])
            samples.append((time.monotonic() - t0, values, f, r, fl))
            shown = (f"F = {f:8.3f} N  regime {r}" if math.isfinite(f) else f"F = {'-':>8}    ")
            if fl != "ok":
                shown += f"  {fl}"
            click.echo(f"{len(samples):6d}  {shown}  |B| {Babs * 1e3:.4f} mT")
            if count is not None and len(samples) >= count:
                break
    except KeyboardInterrupt:
        pass
    finally:
        src.close()
    click.echo(f"{len(samples)} samples, {parser.skipped} lines skipped (not a sample)", err=True)
    if out is not None:
        cols = ("Bx_code_lsb", "By_code_lsb", "Bz_code_lsb") if raw else ("Bx_uT", "By_uT", "Bz_uT")
        buf = io.StringIO()
        buf.write(",".join(("time_s",) + cols + ("force_N", "regime", "flag", "force_resolution_N")) + "\n")
        for t, values, f, r, fl in samples:
            res_N = float(imap.local_resolution_N(f)) if math.isfinite(f) else None
            buf.write(",".join([f"{t:.4f}"] + [f"{v:.9g}" for v in values]
                               + [_fmt(f), str(r) if math.isfinite(f) else "", fl, _fmt(res_N, ".6g")]) + "\n")
        with staged(out) as st:
            st.write_text("forces.csv", buf.getvalue())
        click.echo(f"wrote {out}/forces.csv", err=True)
