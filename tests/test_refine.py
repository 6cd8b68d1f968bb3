"""mst design --refine (output space mapping onto a dearer rung) and model.accuracy_rel.

The refined design is judged independently: the test re-simulates the written design.yaml with
the frame model itself. The rung picked for an accuracy follows the measured ladder errors
stored with the package (read here, so the expectation moves with the data).
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
import yaml
from click.testing import CliRunner

from mst_cli.cli.app import main
from mst_cli.io.schema import load_document
from mst_cli.model.ladder import ERRORS_FILE, choose_mechanics
from mst_cli.model.response import simulate

ROOT = Path(__file__).resolve().parents[1]
SPEC = ROOT / "configs" / "fingertip.yaml"       # met by the printable cell
PAPER = ROOT / "configs" / "mohammadi2021.yaml"   # the paper's own targets
USER_LADDER = ("spring", "frame", "continuum")      # cheapest first; continuum is the reference


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
    assert doc.mechanics == "continuum"       # mst simulate design.yaml reproduces these numbers

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
    errors = {"models": {"spring-textbook": {"median_abs_err_k": 0.30, "median_abs_err_lock_force": 0.6},
                         "spring": {"median_abs_err_k": 0.10, "median_abs_err_lock_force": 0.15},
                         "frame": {"median_abs_err_k": 0.02, "median_abs_err_lock_force": 0.04}}}
    assert choose_mechanics(None, 0.2, "spring", errors).mechanics == "spring"
    assert choose_mechanics(None, 0.12, "spring", errors).mechanics == "frame"   # R decides
    c = choose_mechanics(None, 0.05, "spring", errors)
    assert (c.mechanics, c.measured_err_k_rel, c.measured_err_lock_force_rel) == ("frame", 0.02, 0.04)
    assert c.message() == ("mechanics: frame (measured median error against continuum: stiffness 2 %, "
                           "lock force 4 %; requested <= 5 %)")
    assert choose_mechanics(None, 0.01, "spring", errors).mechanics == "continuum"
    # an explicit flag wins; without accuracy_rel the file's mechanics is used
    assert choose_mechanics("spring", 0.01, "frame", errors).mechanics == "spring"
    assert choose_mechanics("spring", 0.01, "frame", errors).message() is None
    assert choose_mechanics(None, None, "frame", errors).mechanics == "frame"


def test_explicit_mechanics_flag_wins_over_accuracy_rel(tmp_path):
    path = _with_model(ONE_LAYER, tmp_path, "d.yaml", accuracy_rel=0.9)   # would pick spring
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
