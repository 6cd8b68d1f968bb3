"""mst bench: the measurement library, the model choice by accuracy, and the command."""

import json

import numpy as np
import pytest
from click.testing import CliRunner

from mst_cli.bench import (cheapest_model_for, field_errors, load_ladder_errors, sample_cells,
                           summarise)
from mst_cli.cli import main

ERRORS = {"models": {"spring-textbook": {"median_abs_err_k": 0.16}, "spring": {"median_abs_err_k": 0.02},
                     "frame": {"median_abs_err_k": 0.015}, "continuum": {"median_abs_err_k": 0.0}}}


@pytest.mark.parametrize("acc, model", [(0.5, "spring"), (0.1, "spring"),
                                        (0.016, "frame"), (0.001, "continuum")])
def test_cheapest_model_meets_the_accuracy(acc, model):
    chosen, err = cheapest_model_for(acc, ERRORS)
    assert chosen == model and err <= acc


def test_cheapest_model_reads_the_stored_measurement():
    stored = load_ladder_errors()
    chosen, err = cheapest_model_for(0.10)
    assert err == pytest.approx(0.0 if chosen == "continuum" else stored["models"][chosen]["median_abs_err_k"])
    assert err <= 0.10


@pytest.mark.parametrize("bad", [0.0, -0.1, float("nan")])
def test_cheapest_model_rejects_nonsense(bad):
    with pytest.raises(ValueError, match="accuracy_rel"):
        cheapest_model_for(bad, ERRORS)


def test_sample_is_valid_seeded_and_inside_the_bounds():
    a, b = sample_cells(20, seed=3), sample_cells(20, seed=3)
    assert a == b
    for c in a:
        assert not c.violations() and 15 <= c.theta_deg <= 60 and 0.4 <= c.t_mm <= 2 and 1.2 <= c.h_mm <= 6


def test_field_errors_axial_is_exact_and_dipole_overestimates():
    err = field_errors(np.array([5.0, 10.0, 15.0]))
    assert np.max(np.abs(err["axial"])) < 1e-9
    # DESIGN.md: dipole about +10 % at 10 mm, +5 % at 15 mm from the face
    assert err["dipole"][1] == pytest.approx(0.10, abs=0.02)
    assert err["dipole"][2] == pytest.approx(0.05, abs=0.015)


def test_summarise_counts_failures():
    rows = [{"m": {"err_k": 0.1, "err_d_lock": 0, "err_lock_force": 0.2}}, {"m": {"error": "x"}}]
    s = summarise(rows, "m")
    assert s["failures"] == 1 and s["err_k"]["median"] == pytest.approx(0.1)


def test_bench_command_writes_three_files(tmp_path):
    out = tmp_path / "b"
    r = CliRunner().invoke(main, ["bench", "--samples", "2", "--seed", "1", "--quick", "--out", str(out)])
    assert r.exit_code == 0, r.output
    assert {p.name for p in out.iterdir()} == {"bench.md", "bench.json", "bench.png"}
    data = json.loads((out / "bench.json").read_text())
    assert set(data["models"]) == {"spring-textbook", "spring", "frame", "continuum"}


def test_bench_rejects_bad_samples(tmp_path):
    r = CliRunner().invoke(main, ["bench", "--samples", "0", "--out", str(tmp_path / "x")])
    assert r.exit_code == 2 and not (tmp_path / "x").exists()
