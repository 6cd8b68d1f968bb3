"""mst design --refine (output space mapping onto a dearer rung) and model.accuracy_rel.

The refined design is judged independently: the test re-simulates the written design.yaml with
the frame model itself. The rung picked for an accuracy follows the measured ladder errors
stored with the package (read here, so the expectation moves with the data).
"""

from __future__ import annotations

import json
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest
import yaml
from click.testing import CliRunner

from mst_cli.cli.app import main
from mst_cli.model.ladder import ERRORS_FILE, choose_mechanics
from mst_cli.model.response import simulate
from mst_cli.sensor.document import load_document

ROOT = Path(__file__).resolve().parents[1]
SPEC = ROOT / "configs" / "fingertip.yaml"  # met by the printable cell
PAPER = ROOT / "configs" / "mohammadi2021.yaml"  # the paper's own targets
USER_LADDER = ("spring", "frame", "continuum")  # cheapest first; continuum is the reference


def _run(args):
    return CliRunner().invoke(main, [str(a) for a in args], catch_exceptions=False)


def _achieved(path, mechanics):
    """(S per regime, R per layer, targets) of a written design, simulated here."""
    doc = load_document(path)
    resp = simulate(doc.geometry(), doc.material, mechanics=mechanics)
    S = np.array([r.sensitivity_secant_per_N for r in resp.regimes])
    R = np.zeros(len(doc.layers))
    for r in resp.regimes:
        R[r.layer - 1] = r.force_to_N
    S_t = np.array([la.target_sensitivity_per_N for la in doc.layers])
    R_t = np.array([la.target_range_N for la in doc.layers])
    return S, R, S_t, R_t, doc


def _stored_err(errors, m):
    """Stored median |error| of user rung m: the worse of stiffness and lock force."""
    if m == "continuum":
        return 0.0
    entry = errors["models"][m]
    return max(entry["median_abs_err_k"], entry["median_abs_err_lock_force"])


def _expected_rung(accuracy_rel, errors):
    """The cheapest user rung whose stored median errors are <= accuracy_rel."""
    for m in USER_LADDER:
        err = _stored_err(errors, m)
        if err <= accuracy_rel:
            return m, err
    raise AssertionError("continuum always qualifies")


def _with_model(raw: dict, tmp_path: Path, name: str, **model) -> Path:
    raw = dict(raw)
    raw["model"] = {**(raw.get("model") or {}), **model}
    path = tmp_path / name
    path.write_text(yaml.safe_dump(raw, sort_keys=False))
    return path


ONE_LAYER = {"name": "one", "layers": [{"theta_deg": 40.0, "t_mm": 1.0, "h_mm": 3.0}]}


# --------------------------------------------------------------------------- refinement
def test_refine_continuum_meets_every_target_by_the_continuum_model(tmp_path):
    # the printable web's soft layers sit at shallow walls, where the frame rung's beam contact
    # closes early (README, Models): refinement is checked on the reference rung
    out = tmp_path / "out"
    res = _run(["design", SPEC, "--refine", "continuum", "--out", out])
    assert res.exit_code == 0, res.output
    S, R, S_t, R_t, doc = _achieved(out / "design.yaml", "continuum")
    tol = doc.design["tolerance_rel"]
    assert np.all(np.abs(S / S_t - 1.0) <= tol), S / S_t - 1.0
    assert np.all(np.abs(R / R_t - 1.0) <= tol), R / R_t - 1.0
    assert doc.mechanics == "continuum"  # mst simulate design.yaml reproduces these numbers

    report = json.loads((out / "report.json").read_text())
    assert report["models"]["mechanics"] == "continuum"
    ref = report["refinement"]
    assert ref["inner_model"] == "spring" and ref["model"] == "continuum"
    errs = [it["max_abs_error_rel"] for it in ref["iterations"]]
    assert 1 <= len(errs) <= ref["max_iterations"]
    assert errs[-1] <= tol
    # the reported achieved numbers are the continuum model's on the written design
    got_S = [row["achieved_sensitivity_per_N"] for row in report["design"]["targets"]]
    np.testing.assert_allclose(got_S, S, rtol=1e-9)
    # the first iterate is the plain L0 design: its frame error is what refinement removed
    if errs[0] > tol:
        assert len(errs) > 1


def test_refine_not_met_exits_1_naming_the_worst_target(tmp_path):
    # one iteration only: the plain L0 design judged by frame; exit 1 unless it already meets
    from mst_cli.design.refine import refine_document

    doc = load_document(SPEC)
    result = refine_document(doc, "frame", max_iterations=1)
    assert result.response.mechanics == "frame"
    worst = max(max(abs(r["sensitivity_error_rel"]), abs(r["range_error_rel"])) for r in result.targets)
    if worst > doc.design["tolerance_rel"]:
        assert result.exit_code == 1
        assert "frame model" in result.binding and result.binding.startswith("layer ")
    else:
        assert result.exit_code == 0


def test_refine_reports_the_rung_that_measured_the_print_error(tmp_path):
    # no model.accuracy_rel: the cheap corrected rung L0 measures the print sensitivity, and the
    # report and the terminal say so; the numbers are L0's own ratios at t +- 0.05 mm
    from mst_cli.model.printer import Printer

    PRINT_ERROR_T_MM = Printer().wall_tolerance_mm  # the default printer's
    out = tmp_path / "out"
    res = _run(["design", SPEC, "--refine", "frame", "--out", out])
    assert res.exit_code in (0, 1), res.output
    assert "print error (t+-0.05 mm columns) measured with mechanics=spring" in res.output
    pe = json.loads((out / "report.json").read_text())["design"]["print_error_sensitivity"]
    assert pe["mechanics"] == "spring" and "accuracy_rel" in pe["mechanics_rule"]
    doc = load_document(out / "design.yaml")
    g = doc.geometry()
    nominal = simulate(g, doc.material, mechanics="spring")
    thick = [doc.family.cell(c.theta_deg, c.t_mm + PRINT_ERROR_T_MM, c.h_mm) for c in g.layers]
    plus = simulate(doc.geometry(thick), doc.material, mechanics="spring")
    for row, r0, r1 in zip(pe["layers"], nominal.regimes, plus.regimes):
        assert row["dS_rel_t_plus"] == pytest.approx(
            r1.sensitivity_secant_per_N / r0.sensitivity_secant_per_N - 1, rel=1e-9
        )


def test_print_error_rung_follows_accuracy_rel():
    from mst_cli.design.refine import print_error_rung

    errors = {
        "models": {
            "spring": {"median_abs_err_k": 0.01, "median_abs_err_lock_force": 0.015},
            "frame": {"median_abs_err_k": 0.01, "median_abs_err_lock_force": 0.09},
        }
    }
    doc = load_document(SPEC)
    assert print_error_rung(doc, "continuum", errors)[0] == "spring"  # nothing asked
    assert print_error_rung(replace(doc, accuracy_rel=0.05), "continuum", errors)[0] == "spring"
    assert print_error_rung(replace(doc, accuracy_rel=0.01), "continuum", errors)[0] == "continuum"
    rung, rule = print_error_rung(replace(doc, accuracy_rel=0.01), "frame", errors)
    assert rung == "frame" and "capped" in rule  # never dearer than the refining rung


def test_print_error_on_the_dear_rung_when_asked():
    from mst_cli.model.printer import Printer

    PRINT_ERROR_T_MM = Printer().wall_tolerance_mm  # the default printer's
    from mst_cli.design.refine import refine_document

    result = refine_document(load_document(SPEC), "frame", max_iterations=1, print_error_mechanics="frame")
    assert result.print_error["mechanics"] == "frame"
    g, doc = result.geometry, result.document
    nominal = simulate(g, doc.material, mechanics="frame")
    thin = [doc.family.cell(c.theta_deg, c.t_mm - PRINT_ERROR_T_MM, c.h_mm) for c in g.layers]
    minus = simulate(doc.geometry(thin), doc.material, mechanics="frame")
    for row, r0, r1 in zip(result.print_error["layers"], nominal.regimes, minus.regimes):
        assert row["dR_rel_t_minus"] == pytest.approx(r1.force_to_N / r0.force_to_N - 1, rel=1e-9)


def test_local_match_evaluates_each_point_once_in_batches():
    # the warm-started L0 match: objective and every constraint of a point come from one
    # evaluation, and gradients come in batches (it was ~7000 single-point calls per match)
    from mst_cli.design import design_document
    from mst_cli.design.problem import DesignProblem
    from mst_cli.design.refine import _local_match

    doc = replace(load_document(PAPER), mechanics="spring")
    res = design_document(doc)
    x0 = [np.array([getattr(la, k) for la in res.document.layers]) for k in ("theta_deg", "t_mm", "h_mm")]
    moved = [
        replace(
            la, target_sensitivity_per_N=1.03 * la.target_sensitivity_per_N, target_range_N=0.95 * la.target_range_N
        )
        for la in doc.layers
    ]
    problem = DesignProblem(doc.with_layers(moved))
    seen = []
    evaluate = problem.evaluate
    problem.evaluate = lambda u: seen.append(np.atleast_2d(u).copy()) or evaluate(u)
    theta, t, h, n_eval, met = _local_match(problem, *x0)
    assert met
    rows = np.concatenate(seen)
    assert len(seen) < 100 and len(rows) <= n_eval + 5
    assert len({r.tobytes() for r in rows}) >= 0.95 * len(rows)  # no point evaluated twice over
    ev = problem.evaluate_physical(theta, t, h)
    assert np.all(np.abs(ev.rel_err) <= problem.tolerance_rel)


def _mapping_errors(A, z_star, steps, secant=True):
    """Max |dear log error| per iteration on the linear map e(z) = A (z - z*)."""
    from mst_cli.design.refine import _SecantMapping

    z, m, errs = np.zeros(len(z_star)), _SecantMapping(len(z_star)), []
    for _ in range(steps):
        e = A @ (z - z_star)
        errs.append(np.abs(e).max())
        z = m.next_targets(z, e)[0] if secant else z - e
    return np.array(errs)


def test_secant_mapping_beats_plain_space_mapping_on_an_over_correcting_map():
    # the reference spec's dear/L0 map over-corrects by about a third, errors alternating in
    # sign (A ~ 1.35 I): the plain step shrinks the error 3x per dear solve, the secant step
    # learns the factor from two iterates and lands on the third
    rng = np.random.default_rng(0)
    z_star = rng.standard_normal(6)
    aligned = _mapping_errors(1.35 * np.eye(6), z_star, 3)
    assert aligned[2] < 1e-9 * aligned[0]
    assert _mapping_errors(1.35 * np.eye(6), z_star, 3, secant=False)[2] > 0.1 * aligned[0]
    # coupled outputs: rank-one updates need more steps, and still beat the plain step
    A = 1.35 * np.eye(6) + 0.05 * rng.standard_normal((6, 6))
    sec, plain = _mapping_errors(A, z_star, 5), _mapping_errors(A, z_star, 5, secant=False)
    assert np.all(sec[2:] < 0.5 * plain[2:])


# --------------------------------------------------------------------------- accuracy_rel
def _accuracies(errors):
    """Accuracies just above and below every stored nonzero error, inside (0, 1)."""
    vals = {0.9}
    for m in USER_LADDER[:-1]:
        e = _stored_err(errors, m)
        vals |= {e * 1.001, e * 0.999}
    return sorted(v for v in vals if 0.0 < v < 1.0)


def test_simulate_accuracy_rel_picks_the_rung_the_stored_errors_give(tmp_path):
    errors = json.loads(ERRORS_FILE.read_text())
    for i, acc in enumerate(_accuracies(errors)):
        expected, err = _expected_rung(acc, errors)
        path = _with_model(ONE_LAYER, tmp_path, f"d{i}.yaml", accuracy_rel=acc)
        res = _run(["simulate", path, "--out", tmp_path / f"o{i}"])
        assert res.exit_code == 0, res.output
        first = res.output.splitlines()[0]
        assert first.startswith(f"mechanics: {expected} (measured median error against continuum"), first
        assert "requested" in first
        report = json.loads((tmp_path / f"o{i}" / "report.json").read_text())
        assert report["models"]["mechanics"] == expected


def test_choice_walks_the_ladder_with_given_errors():
    errors = {
        "models": {
            "spring-textbook": {"median_abs_err_k": 0.30, "median_abs_err_lock_force": 0.6},
            "spring": {"median_abs_err_k": 0.10, "median_abs_err_lock_force": 0.15},
            "frame": {"median_abs_err_k": 0.02, "median_abs_err_lock_force": 0.04},
        }
    }
    assert choose_mechanics(None, 0.2, "spring", errors).mechanics == "spring"
    assert choose_mechanics(None, 0.12, "spring", errors).mechanics == "frame"  # R decides
    c = choose_mechanics(None, 0.05, "spring", errors)
    assert (c.mechanics, c.measured_err_k_rel, c.measured_err_lock_force_rel) == ("frame", 0.02, 0.04)
    assert c.message() == (
        "mechanics: frame (measured median error against continuum: stiffness 2 %, lock force 4 %; requested <= 5 %)"
    )
    assert choose_mechanics(None, 0.01, "spring", errors).mechanics == "continuum"
    # an explicit flag wins; without accuracy_rel the file's mechanics is used
    assert choose_mechanics("spring", 0.01, "frame", errors).mechanics == "spring"
    assert choose_mechanics("spring", 0.01, "frame", errors).message() is None
    assert choose_mechanics(None, None, "frame", errors).mechanics == "frame"


def test_explicit_mechanics_flag_wins_over_accuracy_rel(tmp_path):
    path = _with_model(ONE_LAYER, tmp_path, "d.yaml", accuracy_rel=0.9)  # would pick spring
    res = _run(["simulate", path, "--mechanics", "frame", "--out", tmp_path / "o"])
    assert res.exit_code == 0, res.output
    assert "measured median" not in res.output
    assert json.loads((tmp_path / "o" / "report.json").read_text())["models"]["mechanics"] == "frame"


def test_design_accuracy_rel_and_explicit_refine(tmp_path):
    raw = yaml.safe_load(SPEC.read_text())
    errors = json.loads(ERRORS_FILE.read_text())
    path = _with_model(raw, tmp_path, "s.yaml", accuracy_rel=0.9)
    expected, _ = _expected_rung(0.9, errors)
    res = _run(["design", path, "--out", tmp_path / "a"])
    assert res.exit_code in (0, 1), res.output
    assert res.output.splitlines()[0].startswith(f"mechanics: {expected} ")
    report = json.loads((tmp_path / "a" / "report.json").read_text())
    assert report["models"]["mechanics"] == expected
    assert ("refinement" in report) == (expected != "spring")
    # --refine wins over accuracy_rel's pick
    res = _run(["design", path, "--refine", "continuum", "--out", tmp_path / "b", "--quiet"])
    assert res.exit_code == 0, res.output
    report = json.loads((tmp_path / "b" / "report.json").read_text())
    assert report["models"]["mechanics"] == "continuum"
    assert report["refinement"]["inner_model"] == "spring"


@pytest.mark.parametrize("value", [0, 1.5, "high"])
@pytest.mark.parametrize("command", ["simulate", "design"])
def test_invalid_accuracy_rel_exits_2_naming_the_field(tmp_path, value, command):
    base = ONE_LAYER if command == "simulate" else yaml.safe_load(SPEC.read_text())
    path = _with_model(base, tmp_path, "bad.yaml", accuracy_rel=value)
    out = tmp_path / "o"
    res = CliRunner().invoke(main, [command, str(path), "--out", str(out)])
    assert res.exit_code == 2
    lines = [ln for ln in res.output.splitlines() if ln.strip()]
    assert len(lines) == 1 and "model.accuracy_rel" in lines[0], res.output
    assert not out.exists()
