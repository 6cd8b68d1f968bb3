"""Calibrating from the load test a rig really produces (issue 38): the kernels on a synthetic
rig with known truth (studies/rig_loadtest.py: hysteresis h, a stiffer first cycle, creep under
a hold, drift, temperature; 2 uT noise and the chip's LSB)."""

import sys
from pathlib import Path

import numpy as np
import pytest

from mst_cli.calibration import hysteresis as hy
from mst_cli.calibration.branches import find_branches
from mst_cli.calibration.fit_quality import fit_quality, runs_test
from mst_cli.calibration.temperature import fit_modulus_coeff, modulus_coeff_sigma
from mst_cli.errors import InputError
from mst_cli.model.components import remanence_at_T
from mst_cli.model.temperature import force_at_T

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "studies"))
from rig_loadtest import Rig, forward_curve, hysteresis_peak_tolerance_N, rig_loadtest, truth_hysteresis_pct

CURVE = forward_curve()  # spring rung, 3 ms
EDGES = (0.0, *CURVE.lock_forces_N)


def field_abs_T(rows):
    return 1e-6 * np.linalg.norm(np.stack([rows[k] for k in ("Bx_uT", "By_uT", "Bz_uT")], -1), axis=-1)


def force_noise_N(F_load):
    """2 uT of |B| as force on the curve's loading branch at F_load."""
    slope = np.gradient(CURVE.field_abs_T(CURVE.force_N), CURVE.force_N)
    return 2e-6 / np.interp(F_load, CURVE.force_N, slope)


def test_branches_turning_points_cycles_and_holds_are_found_to_the_row():
    rows, truth = rig_loadtest(Rig(turn_fraction=(1, 0.5, 0.75, 1), hold_cycles=(2,), creep_pct_per_decade=1), CURVE)
    b = find_branches(rows["force_N"], rows["time_s"])
    assert list(b.peak_rows) == truth.peak_rows and list(b.valley_rows) == truth.valley_rows
    assert list(b.holds) == truth.holds
    assert np.all(b.label == rows["branch"]) and np.all(b.cycle == rows["cycle"])
    unloading = b.label == "unloading"
    turn = np.repeat(truth.turn_forces_N, np.bincount(rows["cycle"])[1:])
    assert np.allclose(b.turn_force_N[unloading], turn[unloading], atol=4 * 0.01)  # the load cell's noise


def test_user_hints_are_checked_against_the_force():
    rows, _ = rig_loadtest(Rig(cycles=3), CURVE)
    F = rows["force_N"]
    assert np.all(find_branches(F, branch=rows["branch"], cycle=rows["cycle"]).label == rows["branch"])
    branch = rows["branch"].copy()
    branch[55] = "loading"  # an unloading row
    with pytest.raises(InputError) as err:
        find_branches(F, branch=branch, first_row=2)
    assert err.value.field == "branch[57]"
    cycle = rows["cycle"].copy()
    cycle[20:] += 1  # a new cycle in the middle of a loading
    with pytest.raises(InputError) as err:
        find_branches(F, cycle=cycle)
    assert err.value.field == "cycle[20]"


def test_hysteresis_is_measured_within_a_point_of_full_scale_per_regime():
    """Each regime's peak within 3 standard errors of the noise (hysteresis_peak_tolerance_N):
    over the three regimes, 198 of 200 noise seeds hold (studies/rig_seeds.py; the worst
    1.4 x the bound), as 3-sigma claims on three bands should (~1 % fail)."""
    # 240 rows a branch: the whole part's last regime (the cap closing the top layer's cavity
    # a few newtons before layer 2 locks) is a tenth of the full scale, ~20 rows a cycle
    rows, truth = rig_loadtest(Rig(cycles=6, points_per_branch=240, seed=2), CURVE)
    b = find_branches(rows["force_N"], rows["time_s"])
    got = hy.measure_hysteresis(field_abs_T(rows), rows["force_N"], b.label, EDGES)
    for r in got:
        pct, _ = truth_hysteresis_pct(truth, r.lo_N, r.hi_N)
        tol_N = hysteresis_peak_tolerance_N(truth, r.lo_N, r.hi_N, r.samples)  # what the noise allows
        assert abs(r.max_pct - pct) / 100 * (r.hi_N - r.lo_N) < tol_N < 0.01 * CURVE.full_scale_N, (r, pct, tol_N)


def test_the_unloading_model_leaves_less_than_the_noise():
    """Half the noise is a stated multiple, not a derived bound: it held on 198 of 200 noise
    seeds (studies/rig_seeds.py; worst 1.12 x), the residual's 1.5 x on all 200."""
    rows, truth = rig_loadtest(Rig(cycles=6, turn_fraction=(1, 0.5, 0.75, 1, 0.6, 0.9), seed=4), CURVE)
    b = find_branches(rows["force_N"], rows["time_s"])
    model = hy.fit_unloading(field_abs_T(rows), rows["force_N"], b.label, b.turn_force_N)
    un = b.label == "unloading"
    noise = force_noise_N(truth.force_load_N[un])
    miss = model.h_N(truth.force_load_N[un], b.turn_force_N[un]) - truth.h_N[un]
    assert np.sqrt(np.mean(miss**2)) < 0.5 * np.sqrt(np.mean(noise**2))
    assert model.residual_rms_N < 1.5 * np.sqrt(np.mean(noise**2))


def test_no_turn_means_no_loop_and_never_nan():
    """h = F_turn p(F / F_turn) with p bounded on [0, 1]: it goes to 0 with F_turn, so a reading
    before any turn (F_turn = 0) has no loop, not 0/0."""
    model = hy.UnloadingModel(coefficients=(0.02, 0.1, -0.3, 0.18), residual_rms_N=0.0, samples=10)
    F = np.array([0.0, 0.5, 3.0])
    assert np.array_equal(model.h_N(F, np.zeros(3)), np.zeros(3))
    assert np.array_equal(model.unloading_force_N(F, 0.0), F)
    tiny = model.h_N(F, np.full(3, 1e-9))
    assert np.all(np.isfinite(tiny)) and np.max(np.abs(tiny)) < 1e-9


@pytest.mark.parametrize("pct", [0.0, 8.0])
def test_a_stiffer_first_cycle_is_detected_when_8_percent_and_not_when_0(pct):
    rows, _ = rig_loadtest(Rig(first_cycle_pct=pct, seed=3), CURVE)
    b = find_branches(rows["force_N"], rows["time_s"])
    got = hy.first_cycle(field_abs_T(rows), rows["force_N"], b.label, b.cycle)
    assert got.differs == (pct > 0)
    assert abs(got.difference_pct - pct) < 4 * got.sigma_pct + 0.3
    assert hy.rows_without_first_cycle(b.cycle, got).sum() == len(b.cycle) - (pct > 0) * np.sum(b.cycle == 1)


def test_creep_per_decade_is_recovered_within_two_sigma():
    """A 2-sigma claim on the fit's own sigma: it held on 198 of 200 noise seeds
    (studies/rig_seeds.py; 3 sigma on all 200), so the sigma is honest or a little wide."""
    rows, _ = rig_loadtest(Rig(turn_fraction=(1, 0.6, 1), cycles=3, hold_cycles=(2,), creep_pct_per_decade=1.0), CURVE)
    b = find_branches(rows["force_N"], rows["time_s"])
    B = field_abs_T(rows)
    load = b.label == "loading"
    reading_N = hy.force_at_field_N(B[load], rows["force_N"][load], B, edges_N=EDGES)
    got = hy.creep(rows["time_s"], reading_N, b.holds[0], held_force_N=0.6 * CURVE.full_scale_N)
    assert abs(got.pct_per_decade - 1.0) < 2 * got.sigma_pct and got.sigma_pct < 0.3


def test_white_noise_gives_no_warning_and_chi2_near_one():
    """4 sd of chi2_nu and 3 of the runs z: over 200 draws (studies/rig_seeds.py) chi2_nu held on
    all, the runs z on 197 (it is a count, normal only roughly), the warning never came."""
    r = np.random.default_rng(7).standard_normal(400)
    q = fit_quality(r, 3, time_s=np.arange(400.0), sigma={"modulus_factor": 0.02})
    assert abs(q.chi2_nu - 1) < 4 * np.sqrt(2 / 397) and abs(q.runs_z) < 3 and q.warning is None
    assert q.sigma["modulus_factor"] == pytest.approx(0.02 * max(1, np.sqrt(q.chi2_nu)))


def test_runs_test_counts_runs():
    runs, mu, _ = runs_test(np.array([1, 1, -1, -1, 1, -1.0]))
    assert runs == 4 and mu == pytest.approx(2 * 3 * 3 / 6 + 1)


def _residual_of_a_loading_fit(rows, truth_curve_values=None):
    """Normalised residuals of |B| against the drift-free, hysteresis-free forward curve."""
    return (field_abs_T(rows) - CURVE.field_abs_T(rows["force_N"])) / 2e-6


@pytest.mark.parametrize("seed", range(10))  # a few ms a seed
def test_drift_gives_the_warning_names_drift_and_inflates_sigmas(seed):
    """A drift alone, on ten noise seeds: before the branch and trend t were fitted together
    (mst_cli/calibration/fit_quality.py), 5 of these 10 seeds (91 of 200) failed: the drift's
    residuals, mostly of one sign, left the runs z above -3 (no warning, 46), or offset the
    unloading rows (each follows its loading) to a Welch t past 4 (named hysteresis, 45).
    Now 200 of 200 hold (studies/rig_seeds.py)."""
    rows, _ = rig_loadtest(Rig(hysteresis_pct=0.0, drift_uT_per_s=0.05, seed=seed), CURVE)
    q = fit_quality(_residual_of_a_loading_fit(rows), 4, rows["branch"], rows["time_s"], {"modulus_factor": 0.02})
    assert q.warning and q.cause == "drift" and q.sigma["modulus_factor"] > 0.02 * 1.4
    assert q.identifiable["modulus_factor"] == (q.sigma["modulus_factor"] <= 0.1 / 3)


@pytest.mark.parametrize("seed", [6, 13])
def test_hysteresis_and_an_unmodelled_nonlinearity_are_told_apart(seed):
    """Seed 13 is one of the 5 of 200 on which the 3 % loop (chi2_nu 210, branch t -24) got no
    warning before the branch t counted as structure: its runs z was -2.5."""
    rows, _ = rig_loadtest(Rig(hysteresis_pct=3.0, seed=seed), CURVE)
    q = fit_quality(_residual_of_a_loading_fit(rows), 4, rows["branch"], rows["time_s"])
    assert q.warning and q.cause == "hysteresis"
    rows, _ = rig_loadtest(Rig(hysteresis_pct=0.0, seed=seed), CURVE)
    bend = 2e-6 * 6 * np.sin(2 * np.pi * rows["force_N"] / CURVE.full_scale_N)  # 6 sigma the model lacks
    q = fit_quality(_residual_of_a_loading_fit(rows) + bend / 2e-6, 4, rows["branch"], rows["time_s"])
    assert q.warning and q.cause == "model" and q.chi2_nu > 2


def test_remanence_at_T_follows_the_grade_coefficient():
    assert remanence_at_T("N42", 40.0) == pytest.approx(1.30 * (1 - 0.0012 * 20))
    assert remanence_at_T(1.3, 20.0) == pytest.approx(1.3)


def test_a_reading_at_30_and_40_degC_is_corrected_within_1_5_percent():
    rig = Rig(cycles=3, T_C=(20.0, 30.0, 40.0), hysteresis_pct=0.0, seed=8)
    rows, truth = rig_loadtest(rig, CURVE)
    load = (rows["branch"] == "loading") & (rows["force_N"] > 5)
    B, T, F = field_abs_T(rows)[load], rows["T_C"][load], rows["force_N"][load]
    ref = CURVE.field_abs_T(CURVE.force_N)
    keep = CURVE.force_N <= CURVE.full_scale_N

    def inverse(b):
        return np.interp(b, ref[keep], CURVE.force_N[keep])

    got = force_at_T(inverse, B, T, truth.remanence_coeff_pct_per_K, rig.modulus_coeff_per_K)
    for temp in (30.0, 40.0):
        at = T == temp
        assert np.median(np.abs(got[at] / F[at] - 1)) < 0.015
        # uncorrected: off. The softer TPU partly offsets the weaker magnet, by a share that
        # changes along the curve (the error changes sign across it), so the typical error, not
        # the signed median
        assert np.median(np.abs(inverse(B[at]) / F[at] - 1)) > 0.015


def test_the_modulus_coefficient_is_fitted_and_judged_identifiable_only_with_spread():
    """3 sigma of the fit's own sigma: each held on 199 of 200 noise seeds (studies/rig_seeds.py),
    as a 3-sigma claim should (0.3 % fail)."""
    rig = Rig(cycles=3, T_C=(20.0, 30.0, 40.0), hysteresis_pct=0.0, seed=9)
    rows, truth = rig_loadtest(rig, CURVE)
    load = rows["branch"] == "loading"

    def model(F, values):
        m = values["modulus_factor"]
        return values["remanence_factor"] * CURVE.field_abs_T(np.asarray(F) / m)

    F, T = rows["force_N"][load], rows["T_C"][load]
    got = fit_modulus_coeff(model, F, field_abs_T(rows)[load], T, {}, 2e-6, truth.remanence_coeff_pct_per_K)
    assert abs(got.modulus_coeff_per_K - rig.modulus_coeff_per_K) < 3 * got.sigma_per_K and got.identifiable
    assert abs(got.modulus_factor - 1.0) < 3 * got.modulus_factor_sigma
    flat = modulus_coeff_sigma(model, F, np.full(len(F), 20.0), {}, 2e-6, truth.remanence_coeff_pct_per_K)
    assert flat == np.inf or flat > 1
