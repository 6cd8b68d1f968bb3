"""Calibrating from a real rig's log (issue 47): each effect of studies/rig_log.py alone, then all
together, the value recovered against the value put in."""

import json
import sys
from pathlib import Path

import numpy as np
import pytest
from click.testing import CliRunner

from mst_cli import api
from mst_cli.calibration import hysteresis as hy
from mst_cli.calibration.branches import find_branches
from mst_cli.cli.app import main

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "studies"))
from rig_loadtest import forward_curve, rig_design
from rig_log import SOFTENING_X, RigLog, all_off, loop_h, rig_log, stiffness, write_log

ROOT = Path(__file__).resolve().parents[1]
DESIGN = rig_design()  # the forward design with the default air (studies/rig_loadtest.py)
CURVE = forward_curve()
QUIET = {"noise_uT": (0.5, 0.5, 0.5), "force_noise_N": 0.005}  # a little noise: sigmas stay finite


def calibrated(tmp_path, rig, missing="-1", **options):
    rows, truth = rig_log(rig, CURVE)
    f = tmp_path / "lt.csv"
    write_log(f, rows, missing)
    cal = api.calibrate(DESIGN, f, out=tmp_path / "cal", missing_force=-1.0 if missing == "-1" else None, **options)
    return cal, json.loads((tmp_path / "cal" / "calibration.json").read_text()), truth


def test_the_lag_alone_is_found_and_removed(tmp_path):
    cal, rec, _ = calibrated(tmp_path, all_off(lag_s=0.2, cycles=4, **QUIET))
    a = rec["time_alignment"]
    assert a["applied"] and abs(a["lag_s"] - 0.2) < max(3 * a["lag_sigma_s"], 0.01), a
    assert abs(cal.fit.values["modulus_factor"] - 0.9) < 0.01 * 0.9


def test_no_lag_is_not_applied_and_without_time_the_cost_is_said(tmp_path):
    _, rec, _ = calibrated(tmp_path, all_off(cycles=4, **QUIET))
    assert abs(rec["time_alignment"]["lag_s"]) < 0.01
    rows, _ = rig_log(all_off(cycles=4, lag_s=0.2, **QUIET), CURVE)
    f = tmp_path / "no_time.csv"
    cols = ("force_N", "Bx_uT", "By_uT", "Bz_uT")
    f.write_text(
        "\n".join(
            [",".join(cols)] + [",".join(f"{rows[c][i]:.6g}" for c in cols) for i in range(0, len(rows["time_s"]), 10)]
        )
    )
    got = api.calibrate(DESIGN, f)
    assert "no time_s: the lag between the force and the field is neither measured nor removed" in got.summary()


def run(args):
    return CliRunner().invoke(main, [str(a) for a in args])


@pytest.mark.parametrize(
    "mark, said", [("-1", "--missing-force -1 skips them"), ("nan", "--missing-force"), ("", "--missing-force")]
)
def test_rows_without_a_force_are_refused_in_one_line(tmp_path, mark, said):
    rows, _ = rig_log(all_off(cycles=2, force_present=0.5, **QUIET), CURVE)
    f = tmp_path / "lt.csv"
    write_log(f, rows, mark)
    r = run(["calibrate", DESIGN, f, "--out", tmp_path / "o", "--no-plot"])
    assert r.exit_code == 2 and r.stderr.count("\n") == 1 and said in r.stderr and "force_N" in r.stderr, r.output
    assert not (tmp_path / "o").exists()


@pytest.mark.parametrize("mark, option", [("-1", "-1"), ("nan", "nan"), ("", "nan")])
def test_rows_without_a_force_are_skipped_counted_and_never_fitted(tmp_path, mark, option):
    rows, _ = rig_log(all_off(cycles=4, force_present=0.5, **QUIET), CURVE)
    f = tmp_path / "lt.csv"
    write_log(f, rows, mark)
    r = run(["calibrate", DESIGN, f, "--out", tmp_path / "o", "--no-plot", "--missing-force", option])
    assert r.exit_code == 0, r.output
    missing = int(np.sum(~np.isfinite(rows["force_N"])))
    assert f"{missing} of {len(rows['force_N'])} rows without a force skipped, never fitted" in r.stdout
    rec = json.loads((tmp_path / "o" / "calibration.json").read_text())
    assert rec["time_alignment"]["rows_without_force"] == missing
    assert rec["hysteresis"]["rows_in_fit"] <= len(rows["force_N"]) - missing


def test_force_clipped_at_zero_is_rest_not_a_hold_and_a_short_pause_is_no_hold(tmp_path):
    _, rec, _ = calibrated(tmp_path, all_off(cycles=4, clip_force=True, force_noise_N=0.01, noise_uT=(0.5,) * 3))
    h = rec["hysteresis"]
    assert h["rows"]["hold"] == 0 and h["rows"]["rest"] > 4 * 140 and h["creep"] == []  # 3 s rests at 50 Hz
    F = np.r_[np.linspace(0, 10, 50), np.full(5, 10.0), np.linspace(10, 20, 50)]  # a 0.1 s pause at 50 Hz
    assert find_branches(F, np.arange(len(F)) * 0.02).holds == ()
    F = np.r_[np.linspace(0, 10, 50), np.full(60, 10.0), np.linspace(10, 0, 50)]  # 1.2 s at the turn
    assert len(find_branches(F, np.arange(len(F)) * 0.02).holds) == 1


def test_the_zero_its_drift_and_recovery_are_recovered(tmp_path):
    rig = all_off(cycles=6, drift_uT_per_s=0.25, zero_off_pct=1.6, first_zero_off_pct=3.2,
                  zero_recovery_pct_per_decade=1.5, noise_uT=(3.0, 3.0, 4.5))  # fmt: skip
    cal, rec, truth = calibrated(tmp_path, rig)
    z, span = rec["zero"], truth.span_uT
    for key, want in (
        ("drift_uT_per_min", 15.0),
        ("offset_after_unloading_uT", -0.016 * span),
        ("offset_after_first_press_uT", -0.032 * span),
        ("recovery_uT_per_decade", 0.015 * span),
    ):
        sigma = z[key.replace("_uT", "_sigma_uT")] if "drift" not in key else z["drift_sigma_uT_per_min"]
        assert abs(z[key] - want) < 4 * sigma + 0.05 * abs(want), (key, z[key], want, sigma)
    assert abs(cal.fit.values["modulus_factor"] - 0.9) < 0.01 * 0.9
    assert abs(cal.fit.values["wall_offset_mm"] - 0.04) < 0.005


def fitted_loop(seed: int = 0):
    """(the rig, its unloading model, x, the model's loop at x) of a loop alone, as pressed
    (studies/rig_seeds.py sweeps it over seeds)."""
    rig = all_off(cycles=6, hold_cycles=(3, 5), noise_uT=(1.0,) * 3,
                  loop_pct=(-3.0, -0.4, 2.0, 1.5, 0.0), open_after_hold_pct=2.5, seed=seed)  # fmt: skip
    rows, _ = rig_log(rig, CURVE)
    B = 1e-6 * np.linalg.norm(np.stack([rows[c] for c in ("Bx_uT", "By_uT", "Bz_uT")], -1), axis=1)
    b = find_branches(rows["force_N"], rows["time_s"])
    after = hy.rows_after_holds(b.label, b.holds)
    u = hy.fit_unloading(B, rows["force_N"], b.label, b.turn_force_N, rows["force_N"] > 0.01, after)
    x = np.linspace(0.05, 0.95, 19)
    return rig, u, x, np.polynomial.polynomial.polyval(x, u.coefficients)


def test_a_loop_of_either_sign_open_after_a_hold_is_fitted():
    """The unloading model on the loop alone (the rows as the rig pressed them: the lag's own
    estimate is tested above)."""
    rig, u, x, got = fitted_loop()
    assert np.max(np.abs(got - loop_h(rig, x, False))) < 0.005  # of the turning force
    held = got + u.after_hold * x**4
    assert np.max(np.abs(held - loop_h(rig, x, True))[x > 0.5]) < 0.01
    assert u.residual_rms_N < 0.005 * CURVE.full_scale_N and all(np.isfinite(u.sigma))


def test_softening_is_fitted_against_load_and_press_and_unsettled_presses_left_out(tmp_path):
    rig = all_off(cycles=10, softening_pct=(68.0, 20.0, 8.0), softening_decay=1.5, noise_uT=(1.0,) * 3)
    cal, rec, _ = calibrated(tmp_path, rig)
    s = rec["softening"]
    for x, want in zip(SOFTENING_X, (68.0, 20.0, 8.0)):
        key = f"{round(100 * x)}_pct_fs"
        assert abs(s["first_press_stiffer_pct"][key] - want) < 0.15 * want, (x, s)  # a smooth law on a kinked truth
    assert abs(s["decay_q"] - 1.5) < 0.2
    x = np.linspace(0.1, 0.9, 17)
    over_last = [np.max(stiffness(rig, x, k) / stiffness(rig, x, 10)) - 1 for k in range(1, 11)]
    assert s["presses_left_out"] + 1 == next(k for k in range(1, 11) if 100 * over_last[k - 1] <= 2.0)
    assert abs(cal.fit.values["modulus_factor"] - 0.9) < 0.02 * 0.9


def test_creep_on_a_hold_and_none_on_a_rest(tmp_path):
    rig = all_off(cycles=5, hold_cycles=(2, 4), hold_s=8.0, creep_pct_per_decade=1.0, clip_force=True,
                  noise_uT=(1.0,) * 3, force_noise_N=0.005)  # fmt: skip
    _, rec, _ = calibrated(tmp_path, rig)
    creep = rec["hysteresis"]["creep"]
    assert len(creep) == 2
    for c in creep:
        assert abs(c["pct_per_decade"] - 1.0) < 3 * c["sigma_pct"] + 0.1, c


# ----------------------------------------------------------------- every effect at once (the done-when rig)
@pytest.fixture(scope="module")
def real_rig(tmp_path_factory):
    d = tmp_path_factory.mktemp("real")
    rows, truth = rig_log(RigLog(seed=1), CURVE)
    write_log(d / "lt.csv", rows)
    r = run(["calibrate", DESIGN, d / "lt.csv", "--out", d / "cal", "--no-plot", "--missing-force", -1])
    assert r.exit_code == 0, r.output
    return d, r.stdout, json.loads((d / "cal" / "calibration.json").read_text()), truth


def test_the_real_rig_gets_the_modulus_within_3_percent_and_the_walls_within_15_um(real_rig):
    _, _, rec, _ = real_rig
    p = rec["parameters"]
    assert abs(p["modulus_factor"]["value"] / 0.9 - 1) < 0.03
    assert abs(p["wall_offset_mm"]["value"] - 0.04) < 0.015


def test_the_real_rig_reports_lag_zero_and_softening_with_sigma_in_one_line_each(real_rig):
    """The lag holds on seed 1 only by luck: over noise seeds 1-5 (studies/rig_seeds.py) the lag
    read 214, 225, 234, 229, 215 ms (+-8..18 ms from the blocks): a bias of about +23 ms, past
    the loop's +15 and the zero's -6 the estimator's doc names, and past max(3 sigma, 15 ms) on
    seeds 2 and 3. A known failure of mst_cli/calibration/time_alignment.py, reported, not
    hidden by a wider bound."""
    _, out, rec, truth = real_rig
    a, z, s = rec["time_alignment"], rec["zero"], rec["softening"]
    assert abs(a["lag_s"] - 0.2) < max(3 * a["lag_sigma_s"], 0.015)
    assert abs(z["drift_uT_per_min"] - 15) < 4 * z["drift_sigma_uT_per_min"] + 1.5
    assert abs(z["offset_after_unloading_uT"] + 0.016 * truth.span_uT) < 4 * z["offset_after_unloading_sigma_uT"] + 2
    assert s["first_press_sigma_pct"]["10_pct_fs"] > 0 and s["decay_q_sigma"] > 0
    for start in ("force lag: the force is", "zero: drift", "softening: press 1 stiffer"):
        assert sum(line.startswith(start) for line in out.splitlines()) == 1, out


@pytest.mark.parametrize("branch", ["loading", "unloading"])
def test_a_held_out_stream_reads_within_2_percent_median_and_5_at_p95(real_rig, branch):
    """Holds on calibration seeds 1 and 5, not on 2, 3, 4 (studies/rig_seeds.py: unloading p95
    5.6-7.2 %, seed 3's loading median 2.1 %; the stream's own seed moves them by 0.3 %). The
    cause is the lag's bias (the test above): seed 2 calibrated with the true 0.2 s reads
    0.4 / 1.6 % and 0.7 / 2.7 %. The done-when holds for this seed, not yet for the rig."""
    d, _, _, _ = real_rig
    stream, truth = rig_log(RigLog(cycles=4, first_cycle=11, zero_shift_uT=117.0, hold_cycles=(13,), seed=7), CURVE)
    cols = ("time_s", "Bx_uT", "By_uT", "Bz_uT")
    lines = [",".join(cols)] + [",".join(f"{stream[c][i]:.6g}" for c in cols) for i in range(len(stream["time_s"]))]
    (d / "stream.csv").write_text("\n".join(lines) + "\n")
    got = api.read(d / "cal" / "calibrated.yaml", d / "stream.csv", track_zero=True)
    use = (truth.branch == branch) & (truth.force_N >= 0.1 * CURVE.full_scale_N)
    rel = np.abs(got.force_N[use] - truth.force_N[use]) / truth.force_N[use]
    assert np.median(rel) <= 0.02 and np.percentile(rel, 95) <= 0.05, (np.median(rel), np.percentile(rel, 95))
    plain = api.read(d / "cal" / "calibrated.yaml", d / "stream.csv")  # the zero moved 117 uT: far off
    assert np.nanmedian(np.abs(plain.force_N[use] - truth.force_N[use]) / truth.force_N[use]) > 0.1
    r = run(["read", d / "cal" / "calibrated.yaml", d / "stream.csv", "--track-zero", "--out", d / f"r_{branch}"])
    assert r.exit_code == 0, r.output
    cli = np.genfromtxt(d / f"r_{branch}" / "forces.csv", delimiter=",", names=True)["force_N"]
    assert np.allclose(cli[use], got.force_N[use], rtol=1e-4, atol=1e-4)
