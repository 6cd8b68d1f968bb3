"""Issue 38, wired in: load tests as rigs write them (time_s, cycle, branch, T_C), and the
defects the issue lists. The synthetic rig is studies/rig_loadtest.py (spring rung)."""

import json
import re
import sys
from pathlib import Path

import numpy as np
import pytest
from click.testing import CliRunner

from mst_cli.cli.app import main

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "studies"))
from rig_loadtest import Rig, forward_curve, rig_design, rig_loadtest

ROOT = Path(__file__).resolve().parents[1]
DESIGN = rig_design()  # the forward design with the default air (studies/rig_loadtest.py)
CURVE = forward_curve()
RIG_COLUMNS = ("force_N", "Bx_uT", "By_uT", "Bz_uT", "time_s", "cycle", "branch", "T_C")


def run(args):
    return CliRunner().invoke(main, [str(a) for a in args])


def write_csv(path, rows, cols=RIG_COLUMNS, edit=None):
    lines = [",".join(cols)]
    for i in range(len(rows["force_N"])):
        cells = {c: str(rows[c][i]) for c in cols if c in rows}
        if edit is not None:
            edit(i, cells)
        lines.append(",".join(cells.get(c, "") for c in cols))
    path.write_text("\n".join(lines) + "\n")
    return path


@pytest.fixture(scope="module")
def rig_rows():
    return rig_loadtest(Rig(cycles=3, hysteresis_pct=0.0, seed=1), CURVE)[0]


def one_line_exit_2(r, *parts):
    assert r.exit_code == 2, r.output
    assert r.stderr.count("\n") == 1, r.stderr
    for p in parts:
        assert p in r.stderr, r.stderr


@pytest.mark.parametrize(
    "column, row, value, said",
    [
        ("branch", 5, "rising", "one of loading, unloading, hold"),
        ("T_C", 7, "130", "-40..125"),
        ("T_C", 7, "-41", "-40..125"),
        ("time_s", 9, "3.5", "never decrease"),
        ("cycle", 4, "1.5", "whole number"),
    ],
)
@pytest.mark.parametrize("command", ["calibrate", "read"])
def test_rig_columns_refuse_bad_values_in_one_line(tmp_path, rig_rows, column, row, value, said, command):
    def edit(i, cells):
        if i == row:
            cells[column] = value

    f = write_csv(tmp_path / "lt.csv", rig_rows, edit=edit)
    r = run([command, DESIGN, f, "--out", tmp_path / "o"] + (["--no-plot"] if command == "calibrate" else []))
    one_line_exit_2(r, f"line {row + 2} {column}", said)
    assert not (tmp_path / "o").exists()


def test_unknown_columns_are_named_in_one_note(tmp_path, rig_rows):
    rows = dict(rig_rows, operator=["ann"] * len(rig_rows["force_N"]), humidity=["40"] * len(rig_rows["force_N"]))
    f = write_csv(tmp_path / "lt.csv", rows, cols=(*RIG_COLUMNS, "operator", "humidity"))
    r = run(["calibrate", DESIGN, f, "--out", tmp_path / "o", "--no-plot"])
    assert r.exit_code == 0, r.output
    notes = [line for line in r.stdout.splitlines() if line.startswith("note:")]
    assert notes == ["note: column(s) operator, humidity of lt.csv not used by the calibration"]
    r = run(["read", DESIGN, f, "--out", tmp_path / "r"])
    assert "note: column(s) operator, humidity not read by mst" in r.stdout


@pytest.mark.parametrize("command", ["calibrate", "read"])
def test_millitesla_under_microtesla_columns_gets_a_unit_hint(tmp_path, rig_rows, command):
    rows = {**rig_rows, **{c: np.asarray(rig_rows[c]) / 1000 for c in ("Bx_uT", "By_uT", "Bz_uT")}}
    f = write_csv(tmp_path / "lt.csv", rows)
    r = run([command, DESIGN, f, "--out", tmp_path / "o"] + (["--no-plot"] if command == "calibrate" else []))
    one_line_exit_2(r, "Bx_uT,By_uT,Bz_uT", "in mT?", "x 1000")


@pytest.fixture(scope="module")
def partial_calibration(tmp_path_factory):
    """A calibration from cycles to 60 % of full scale (no hysteresis), and a stream to full scale."""
    d = tmp_path_factory.mktemp("partial")
    rows, _ = rig_loadtest(Rig(cycles=3, turn_fraction=(0.6, 0.6, 0.6), hysteresis_pct=0.0, seed=3), CURVE)
    r = run(["calibrate", DESIGN, write_csv(d / "lt.csv", rows), "--out", d / "cal", "--no-plot"])
    assert r.exit_code == 0, r.output
    stream, _ = rig_loadtest(Rig(cycles=1, hysteresis_pct=0.0, seed=4), CURVE)
    return d, r.stdout, write_csv(d / "stream.csv", stream), stream


def test_regime_1_appears_in_every_summary(partial_calibration):
    d, calibrate_out, stream_csv, _ = partial_calibration
    r = run(["read", d / "cal" / "calibrated.yaml", stream_csv, "--out", d / "r"])
    for out in (calibrate_out, r.stdout):
        line = next(x for x in out.splitlines() if x.strip().startswith("regime 1 ("))
        assert "median" in line, out  # the light-touch band is quoted, from a tenth of its own top
        lo = float(line.split("F >= ")[1].split(" N")[0])
        assert lo == pytest.approx(0.1 * CURVE.lock_forces_N[0], rel=0.06)


def test_every_flag_is_counted_in_the_errors(partial_calibration):
    from mst_cli import api

    d, _, stream_csv, stream = partial_calibration
    got = api.read(d / "cal" / "calibrated.yaml", stream_csv)
    err = got.errors()
    used = stream["force_N"] >= 0.1 * stream["force_N"].max()
    assert (got.flag[used] == "above_calibrated").sum() > 10  # read past the load test's largest force
    assert err["flagged"] == int(np.sum(used & (got.flag != "ok")))


@pytest.mark.parametrize("command, first", [("calibrate", "DESIGN_FILE"), ("read", "MODEL_FILE")])
def test_swapped_arguments_are_named_in_one_line(tmp_path, rig_rows, command, first):
    f = write_csv(tmp_path / "lt.csv", rig_rows)
    r = run([command, f, DESIGN, "--out", tmp_path / "o"])
    one_line_exit_2(r, f"{first} = ", "the arguments are swapped", f"mst {command} ")
    assert not (tmp_path / "o").exists()


# ----------------------------------------------------------------- calibrating a rig's load test
TRUTH = {"modulus_factor": 0.9, "wall_offset_mm": 0.04, "gap_offset_mm": 0.2}
WITHIN = {"modulus_factor": 0.02 * 0.9, "wall_offset_mm": 0.01, "gap_offset_mm": 0.05}


@pytest.fixture(scope="module")
def rig_calibration(tmp_path_factory):
    """The done-when rig: three cycles, hysteresis 6 % of the turning force, cycle 1 8 % stiffer,
    2 uT noise, LSB rounding (spring-rung truth)."""
    from mst_cli import api

    d = tmp_path_factory.mktemp("rig")
    rows, truth = rig_loadtest(Rig(cycles=3, hysteresis_pct=6.0, first_cycle_pct=8.0, seed=1), CURVE)
    f = write_csv(d / "lt.csv", rows)
    return api.calibrate(DESIGN, f, out=d / "cal", plot=True), truth, d


def test_a_rig_load_test_is_fitted_on_its_loading_branch_within_two_sigma(rig_calibration):
    """Each parameter within 2 of the fit's own sigma; the modulus and walls also within WITHIN.
    Not the gap: at one temperature the fit knows it only to ~0.047 mm (1 sigma; the
    remanence trades with it), and over noise seeds 1-5 it missed by up to 0.095 mm, within
    0.05 mm on seed 1 alone (studies/rig_seeds.py; the three-temperature rig fixes it to ~2 um,
    test_the_modulus_temperature_coefficient_is_fitted_from_T_C). The 2-sigma claims: one of
    the three just past 2 sigma (1.03-1.06 x) on 2 of those 5 seeds, as three 2-sigma claims
    should (~1 seed in 8); all within 3 sigma."""
    result, _, _ = rig_calibration
    for name, value in TRUTH.items():
        got, sd = result.fit.values[name], result.fit.std[name]
        assert abs(got - value) < 2 * sd, (name, got, sd)
        assert name == "gap_offset_mm" or abs(got - value) < WITHIN[name], (name, got, sd)
    assert len(result.load_test) == 80  # loading rows of cycles 2 and 3 (cycle 1 is 8 % stiffer)


def test_hysteresis_first_cycle_and_unloading_model_are_reported(rig_calibration):
    import json

    from rig_loadtest import hysteresis_peak_tolerance_N, truth_hysteresis_pct

    from mst_cli import api

    result, truth, d = rig_calibration
    h = json.loads((d / "cal" / "calibration.json").read_text())["hysteresis"]
    assert h["rows"] == {"loading": 121, "unloading": 120, "hold": 0} and h["rows_in_fit"] == 80
    # each regime's peak within what the rig's noise allows, 3 standard errors (tests/test_rig.py: a
    # point of full scale), on the noise seeds 1-5: a 3-sigma bound 15 times, so at most one past it
    # (seed 1's last regime, a tenth of full scale and 11 rows, reads 1.3 times it; the others 0.1-0.45)
    misses = []
    for seed in range(1, 6):
        if seed == 1:
            by_regime, truth_s = h["by_regime"], truth
        else:
            rows, truth_s = rig_loadtest(Rig(cycles=3, hysteresis_pct=6.0, first_cycle_pct=8.0, seed=seed), CURVE)
            cal = d / f"cal{seed}"
            api.calibrate(DESIGN, write_csv(d / f"lt{seed}.csv", rows), out=cal, plot=False)
            by_regime = json.loads((cal / "calibration.json").read_text())["hysteresis"]["by_regime"]
        for r in by_regime:
            lo, hi = r["force_from_N"], r["force_to_N"]
            pct, _ = truth_hysteresis_pct(truth_s, lo, hi)
            tol_N = hysteresis_peak_tolerance_N(truth_s, lo, hi, r["unloading_rows"])
            misses += [(seed, r["regime"])] if abs(r["max_pct_of_band"] - pct) / 100 * (hi - lo) >= tol_N else []
    assert len(misses) <= 1, misses
    assert h["first_cycle"]["differs"] and h["first_cycle"]["left_out_of_fit"]
    assert abs(h["first_cycle"]["stiffer_pct"] - 8.0) < 1.0
    x = 1 / np.sqrt(3)  # the truth loop's widest point: 6 % of the turning force
    assert abs(np.polynomial.polynomial.polyval(x, h["unloading_model"]["coefficients"]) - 0.06) < 0.01
    assert (d / "cal" / "calibration.png").stat().st_size > 10_000
    assert "hysteresis regime 1" in result.summary()


def test_the_calibration_that_ignores_branches_is_worse(rig_calibration):
    from mst_cli import api

    result, _, d = rig_calibration
    before = api.calibrate(DESIGN, d / "lt.csv", use_branches=False)

    def worst(fit):  # the worst parameter's miss, in its WITHIN
        return max(abs(fit.values[k] - TRUTH[k]) / WITHIN[k] for k in TRUTH)

    # the unloading rows read up to 6 % of the turning force less at a field (3.9 % over a loop):
    # mixed in, half the rows, they pull a parameter outside what the branch-aware fit meets (the
    # modulus by 5.8 % before the feet's press went into the forward model; since, the gap by 0.41 mm)
    miss, aware = worst(before.fit), worst(result.fit)
    assert miss > max(1.0, 5 * aware), (miss, aware)
    assert before.record.fit_quality["warning"] is not None
    assert result.record.fit_quality["warning"] is None


# ----------------------------------------------------------------- reading a rig's stream
def held_out_stream(seed=11, **rig):
    return rig_loadtest(Rig(cycles=2, hysteresis_pct=6.0, seed=seed, **rig), CURVE)


def branch_errors(got, rows, branch):
    """(median, p95) of |F - F_true| / F_true from a tenth of full scale. A turn at full scale
    can read past the calibrated map's end (the calibration seed 3, stream 13 of
    studies/rig_seeds.py: the peak row, 27.861 of 27.863 N): no force, flagged above_range, and
    left out, only within 1 % of full scale."""
    F_true = rows["force_N"]
    use = (rows["branch"] == branch) & (F_true >= 0.1 * CURVE.full_scale_N)
    past = use & ~np.isfinite(got.force_N)
    assert np.all(got.flag[past] == "above_range") and np.all(F_true[past] > 0.99 * CURVE.full_scale_N)
    use &= ~past
    rel = np.abs(got.force_N[use] - F_true[use]) / F_true[use]
    return float(np.median(rel)), float(np.percentile(rel, 95))


def test_read_follows_the_branch_within_1_percent_median_and_3_at_p95(rig_calibration, tmp_path):
    from mst_cli import api

    _, _, d = rig_calibration
    rows, _ = held_out_stream()
    got = api.read(d / "cal" / "calibrated.yaml", write_csv(tmp_path / "s.csv", rows), out=tmp_path / "r")
    assert np.mean(got.branches.branch == rows["branch"]) > 0.95
    for branch in ("loading", "unloading"):
        median, p95 = branch_errors(got, rows, branch)
        assert median <= 0.01 and p95 <= 0.03, (branch, median, p95)
    text = (tmp_path / "r" / "forces.csv").read_text().splitlines()
    assert text[0].endswith(",branch,force_uncertainty_N") and ",branch_reference," in text[0]


def test_a_no_load_reading_reads_zero(rig_calibration, tmp_path):
    from mst_cli import api

    result, _, d = rig_calibration
    B0_uT = result.inverse_map.B_abs_T[0] * 1e6
    res_uT = result.inverse_map.field_resolution_T * 1e6
    below = [B0_uT - 4 * res_uT, B0_uT - 2 * res_uT, B0_uT, B0_uT - 30 * res_uT]
    f = tmp_path / "r.csv"
    f.write_text("Bx_uT,By_uT,Bz_uT\n" + "".join(f"0,0,{b:.4f}\n" for b in below))
    got = api.read(d / "cal" / "calibrated.yaml", f)
    assert np.all(np.abs(got.force_N[:3]) < 1e-3) and list(got.flag) == ["ok", "ok", "ok", "below_range"]


def test_tare_re_zeroes_a_shifted_chip(rig_calibration, tmp_path):
    from mst_cli import api

    _, _, d = rig_calibration
    rows, _ = held_out_stream(seed=12)
    rows = {**rows, "Bz_uT": np.asarray(rows["Bz_uT"]) - 40.0}  # the chip 40 uT low on z
    rows = {k: np.concatenate([np.asarray(v)[:1].repeat(5), np.asarray(v)]) for k, v in rows.items()}
    f = write_csv(tmp_path / "s.csv", rows)
    plain = api.read(d / "cal" / "calibrated.yaml", f)
    assert np.all(plain.flag[:5] == "below_range")
    tared = api.read(d / "cal" / "calibrated.yaml", f, tare=5)
    assert np.all(np.abs(tared.force_N[:5]) < 0.05) and abs(tared.tare_shift_uT + 40.0) < 3.0
    median, _ = branch_errors(tared, rows, "loading")
    assert median < 0.01
    r = run(["read", d / "cal" / "calibrated.yaml", f, "--tare", "10000", "--out", tmp_path / "o"])
    one_line_exit_2(r, "--tare = 10000", "no load")


def test_a_drifting_chip_gets_the_warning_and_inflated_sigmas(tmp_path):
    from mst_cli import api

    rows, _ = rig_loadtest(Rig(cycles=3, hysteresis_pct=6.0, drift_uT_per_s=0.3, seed=6), CURVE)
    got = api.calibrate(DESIGN, write_csv(tmp_path / "lt.csv", rows))
    q = got.record.fit_quality
    assert q["warning"] is not None and q["cause"] == "drift" and q["sigma_inflation"] > 1.4
    assert got.fit.chi2_reduced == pytest.approx(q["chi2_nu"], rel=0.05)  # the fit's sigmas carry it, once


# ----------------------------------------------------------------- one chip setting (issue 38)
def test_a_load_test_at_another_chip_setting_says_so_in_every_output(tmp_path):
    """Codes read at GAIN_SEL 0 / RES 0 while mst simulate recommends GAIN_SEL 7 / RES 0: the
    tables are for 0/0, and the terminal, calibration.json and force_table.h say why."""
    import json

    from mst_cli.calibration.loadtest import setting_of
    from mst_cli.model import chip as mlx

    rows, _ = rig_loadtest(Rig(cycles=2, hysteresis_pct=0.0, seed=21), CURVE)
    s = setting_of(0, 0)
    codes = {
        f"{a}_code_lsb": mlx.quantise_lsb(1e-6 * np.asarray(rows[f"{a}_uT"]), lsb)
        for a, lsb in (("Bx", s.xy_uT_per_lsb), ("By", s.xy_uT_per_lsb), ("Bz", s.z_uT_per_lsb))
    }
    cols = ("force_N", "Bx_code_lsb", "By_code_lsb", "Bz_code_lsb")
    f = write_csv(tmp_path / "lt.csv", {**rows, **codes}, cols=cols)
    r = run(["calibrate", DESIGN, f, "--out", tmp_path / "o", "--no-plot", "--gain-sel", 0, "--res", 0])
    assert r.exit_code == 0, r.output
    r_sim = run(["simulate", DESIGN, "--out", tmp_path / "sim", "--no-plot"])
    assert "chip GAIN_SEL 7, RES 0" in r_sim.stdout  # what mst simulate recommends
    assert "chip setting GAIN_SEL 0, RES 0: the load test's" in r.stdout
    assert "not the GAIN_SEL 7, RES 0 mst simulate recommends" in r.stdout
    rec = json.loads((tmp_path / "o" / "calibration.json").read_text())["chip_setting"]
    assert (rec["gain_sel"], rec["res"], rec["source"]) == (0, 0, "the load test")
    assert rec["design_recommended"] == {"gain_sel": 7, "res": 0} and rec["same_as_recommended"] is False
    header = (tmp_path / "o" / "force_table.h").read_text()
    assert "#define MST_GAIN_SEL 0" in header and "GAIN_SEL 7, RES 0 mst simulate" in " ".join(
        line.strip(" *") for line in header.splitlines()
    )


def test_a_load_test_in_uT_gets_the_setting_mst_simulate_recommends(tmp_path, rig_rows):
    import json

    r = run(["calibrate", DESIGN, write_csv(tmp_path / "lt.csv", rig_rows), "--out", tmp_path / "o", "--no-plot"])
    assert r.exit_code == 0, r.output
    rec = json.loads((tmp_path / "o" / "calibration.json").read_text())["chip_setting"]
    assert (rec["gain_sel"], rec["res"]) == (7, 0) and rec["same_as_recommended"] is True
    assert "chip setting GAIN_SEL 7, RES 0: the one mst simulate recommends" in r.stdout


# ----------------------------------------------------------------- the rung of the calibration (issue 38)
SPEC = ROOT / "configs" / "mohammadi2021.yaml"


def percent_apart(line):
    return float(line.split("up to ")[1].split(" %")[0])


def test_read_warns_in_one_line_on_another_rung_than_the_calibration(rig_calibration, tmp_path):
    from mst_cli.calibration.rung_check import rung_difference
    from mst_cli.sensor.document import load_document

    _, _, d = rig_calibration
    rows, _ = held_out_stream(seed=13)
    f = write_csv(tmp_path / "s.csv", rows)
    same = run(["read", d / "cal" / "calibrated.yaml", f, "--out", tmp_path / "a"])
    assert same.exit_code == 0 and same.stderr == "", same.stderr
    other = run(["read", d / "cal" / "calibrated.yaml", f, "--out", tmp_path / "b", "--mechanics", "continuum"])
    assert other.exit_code == 0, other.output
    assert other.stderr.count("\n") == 1 and other.stderr.startswith("mst read: warning: "), other.stderr
    assert "fitted with the spring rung and mst read uses continuum" in other.stderr
    assert "model code changed" not in other.stderr  # the rung, not the code, moved the curve
    # the number quoted: the continuum law reads forces a few % from the spring law on this design
    rel, _ = rung_difference(load_document(d / "cal" / "calibrated.yaml"), "spring", "continuum", CURVE.full_scale_N)
    assert percent_apart(other.stderr) == pytest.approx(100 * rel, rel=0.05) and 1.0 < 100 * rel < 10.0


def test_design_warns_in_one_line_on_another_rung_than_the_calibration(rig_calibration, tmp_path):
    import json
    import shutil

    _, _, d = rig_calibration
    same = run(["design", SPEC, "--calibration", d / "cal" / "calibration.json", "--out", tmp_path / "p", "-q"])
    assert same.exit_code == 0 and "warning" not in same.stderr, same.output
    cal = tmp_path / "cal"
    shutil.copytree(d / "cal", cal)
    record = json.loads((cal / "calibration.json").read_text())
    record["models"]["mechanics"] = "continuum"  # as if calibrated with --mechanics continuum
    (cal / "calibration.json").write_text(json.dumps(record))
    other = run(["design", SPEC, "--calibration", cal / "calibration.json", "--out", tmp_path / "q", "-q"])
    lines = [line for line in other.stderr.splitlines() if "warning" in line]
    assert len(lines) == 1 and lines[0].startswith("mst design: warning: the calibration was fitted with the continuum")
    assert "mst design uses spring" in lines[0] and 1.0 < percent_apart(lines[0]) < 10.0


# ----------------------------------------------------------------- temperature (issue 38)
TEMPS = (20.0, 30.0, 40.0)
BETA = -0.008  # the rig's stated test coefficient of the TPU's modulus, 1/K


def temperature_errors(got, rows, T, use=None):
    """Median |F - F_true| / F_true at T of the readings from a tenth of full scale (``use``:
    of these; default those ``got`` gives a force: at 40 degC the softer sensor locks at m(T) x
    the 20 degC lock force, beyond is above_range)."""
    F = rows["force_N"]
    use = (rows["T_C"] == T) & (F >= 0.1 * CURVE.full_scale_N) & (np.isfinite(got.force_N) if use is None else use)
    return float(np.median(np.abs(got.force_N[use] - F[use]) / F[use])), int(use.sum())


@pytest.fixture(scope="module")
def warm_calibration(tmp_path_factory):
    from mst_cli import api

    d = tmp_path_factory.mktemp("warm")
    rows, _ = rig_loadtest(Rig(cycles=3, T_C=TEMPS, hysteresis_pct=6.0, seed=1), CURVE)
    return api.calibrate(DESIGN, write_csv(d / "lt.csv", rows), out=d / "cal"), d


def test_the_modulus_temperature_coefficient_is_fitted_from_T_C(warm_calibration):
    import json

    result, d = warm_calibration
    t = json.loads((d / "cal" / "calibration.json").read_text())["temperature"]
    assert t["fitted"] and t["load_test_T_C"] == [20.0, 40.0] and t["remanence_coeff_pct_per_K"] == -0.12
    assert abs(t["modulus_temp_coeff_per_K"] - BETA) < max(3 * t["sigma_per_K"], 2e-4), t
    for name, value in TRUTH.items():  # the print, referred to 20 degC
        assert abs(result.fit.values[name] - value) < WITHIN[name], (name, result.fit.values[name])
    assert "modulus_temp_coeff_per_K -0.8" in result.summary()


def test_one_temperature_holds_the_coefficient_at_0_and_says_so(rig_calibration):
    t = rig_calibration[0].record.temperature
    assert t["fitted"] is False and t["modulus_temp_coeff_per_K"] == 0.0 and "one temperature" in t["why"]


def test_read_corrects_with_T_C_within_1_5_percent_and_is_over_5_off_without(warm_calibration, tmp_path):
    from mst_cli import api

    _, d = warm_calibration
    rows, truth = rig_loadtest(Rig(cycles=3, T_C=TEMPS, hysteresis_pct=6.0, seed=11), CURVE)
    got = api.read(d / "cal" / "calibrated.yaml", write_csv(tmp_path / "s.csv", rows))
    plain_csv = write_csv(tmp_path / "p.csv", rows, cols=tuple(c for c in RIG_COLUMNS if c != "T_C"))
    plain = api.read(d / "cal" / "calibrated.yaml", plain_csv)
    for T in TEMPS:
        median, n = temperature_errors(got, rows, T)
        assert median < 0.015 and n > 40, (T, median, n)
    # uncorrected, on the loading readings the corrected reader reads at 40 degC: off by what the
    # rig's law gives a reader that ignores T, F_20(r B_20(F / m)) against F (the weaker magnet
    # partly offsets the softer TPU, by a share that changes along the curve)
    loading = np.isfinite(got.force_N) & (rows["branch"] == "loading")
    plain_error = temperature_errors(plain, rows, 40.0, loading)[0]
    use = loading & (rows["T_C"] == 40.0) & (rows["force_N"] >= 0.1 * CURVE.full_scale_N)
    r, m = 1 + 0.01 * truth.remanence_coeff_pct_per_K * 20.0, 1 + BETA * 20.0
    keep = CURVE.force_N <= CURVE.full_scale_N
    F_plain = np.interp(
        r * CURVE.field_abs_T(truth.force_load_N[use] / m), CURVE.field_abs_T(CURVE.force_N)[keep], CURVE.force_N[keep]
    )
    predicted = float(np.median(np.abs(F_plain / rows["force_N"][use] - 1)))
    assert abs(plain_error - predicted) < 0.01 and plain_error > 3 * temperature_errors(got, rows, 40.0)[0]


# ----------------------------------------------------------------- print 2 (issue 38)
def print2_errors(design_yaml):
    """(S, R) of print 2 as the truth's printer prints it, relative to the spec's targets - 1:
    print 2's design.yaml with the rig's walls +0.04 mm, modulus x0.9, gap +0.2 mm and the
    grade's magnet (the truth's; design.yaml holds the calibrated remanence)."""
    from rig_loadtest import PRINT

    from mst_cli.model.response import simulate
    from mst_cli.sensor.as_printed import apply_parameters
    from mst_cli.sensor.document import load_document

    doc = load_document(design_yaml)
    Br = load_document(DESIGN).magnet.remanence_T
    truth, _ = apply_parameters(doc, {**PRINT, "remanence_factor": Br / doc.magnet.remanence_T})
    resp = simulate(truth.geometry(), truth.material, mechanics="spring")
    spec = load_document(SPEC)
    S = np.array([r.sensitivity_secant_per_N for r in resp.regimes])
    R = np.zeros(len(S))
    for r in resp.regimes:
        R[r.layer - 1] = r.force_to_N
    tS = np.array([la.target_sensitivity_per_N for la in spec.layers])
    tR = np.array([la.target_range_N for la in spec.layers])
    return S / tS - 1, R / tR - 1


def test_print_2_designed_from_the_rig_meets_its_targets_within_2_percent(rig_calibration, tmp_path):
    """Print 2 of the paper's targets with a 5 mm cover: with the spec's 3 mm (1.5 mm over the
    board) the design from this calibration (modulus x0.9) lands its cover on the board's parts at
    8.7 N, inside its range, and its last regime then hangs on the cover's air, i.e. on the fitted
    gap (the rig's gap is fitted to +-0.05 mm, 1 sigma: S_3 3.1 % off at seed 1), which is the landing's
    sensitivity, not the calibration's. With 5 mm the cover bends too little to land inside the
    range, so what is tested is what calibration recovers (load_path.cover_lands_N)."""
    _, _, d = rig_calibration
    spec = tmp_path / "thick_cover.yaml"
    spec_text, swaps = re.subn(r"cover_mm: [0-9.]+", "cover_mm: 5.0", SPEC.read_text())
    assert swaps == 1, "the spec names its cover once"
    spec.write_text(spec_text)
    r = run(["design", spec, "--calibration", d / "cal" / "calibration.json", "--out", tmp_path / "p2", "--no-plot"])
    assert r.exit_code == 0, r.output
    report = json.loads((tmp_path / "p2" / "report.json").read_text())
    assert report["load_path"]["cover_lands_N"] > report["range_N"]  # the 5 mm cover stays off
    dS, dR = print2_errors(tmp_path / "p2" / "design.yaml")
    assert np.all(np.abs(dS) < 0.02) and np.all(np.abs(dR) < 0.02), (dS, dR)
    first, _ = print2_errors(SPEC.parent / "mohammadi2021-forward.yaml")  # the rig's print 1, printed the same way
    assert np.max(np.abs(first)) > 0.05  # without the calibration the same printer misses
