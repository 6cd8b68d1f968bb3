"""The printer in the spec (issue 21): walls designed as printed, the worst print deviation
reported and limited, and the loop from a first print's load test to a second print.

The synthetic printer prints every wall 0.06 mm thicker than drawn and the TPU 15 % softer than
its data sheet; the design never sees those numbers. A print of a written design.yaml is built
by editing the file's keys by hand (walls + 0.06 mm, modulus x 0.85, the grade's magnet, the
drawn housing) and simulating it with the forward model, not through the code under test
(studies/printer_loop.py holds that printer; its main prints the loop's figures).
"""

import json
import math
import sys
from pathlib import Path

import numpy as np
import pytest
import yaml
from click.testing import CliRunner

from mst_cli.cli.app import main
from mst_cli.model.assembly import Housing
from mst_cli.model.response import simulate
from mst_cli.sensor.document import load_document, parse_document

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "studies"))
from printer_loop import MODULUS, WALL_MM, print_of, write_load_test

ROOT = Path(__file__).resolve().parents[1]
SPEC = ROOT / "configs" / "mohammadi2021.yaml"


def run(args):
    return CliRunner().invoke(main, [str(a) for a in args])


def outputs(resp):
    """(S per regime, R per layer in file order) of a response."""
    S = np.array([r.sensitivity_secant_per_N for r in resp.regimes])
    R = np.zeros(len(S))
    for r in resp.regimes:
        R[r.layer - 1] = r.force_to_N
    return S, R


def targets(path=SPEC):
    doc = load_document(path)
    return (
        np.array([la.target_sensitivity_per_N for la in doc.layers]),
        np.array([la.target_range_N for la in doc.layers]),
    )


def as_the_file_says(design_yaml, extra_wall_mm=0.0, mechanics="spring"):
    """A written design as its own printer section says it prints, by hand."""
    raw = yaml.safe_load(Path(design_yaml).read_text())
    pr = raw["printer"]
    raw["material"]["youngs_modulus_MPa"] *= pr["modulus_factor"]
    for layer in raw["layers"]:
        layer["t_mm"] += pr["wall_offset_mm"] + extra_wall_mm
    raw["housing"]["chip_clearance_mm"] += pr["gap_offset_mm"]
    doc = parse_document(raw)
    return simulate(doc.geometry(), doc.material, mechanics=mechanics)


@pytest.fixture(scope="module")
def loop(tmp_path_factory):
    """Print 1 from the spec, its load test, mst calibrate, then design 2 with --calibration."""
    d = tmp_path_factory.mktemp("loop")
    first = run(["design", SPEC, "--out", d / "print1", "--no-plot", "-q"])
    assert first.exit_code == 0, first.output
    print1 = print_of(d / "print1" / "design.yaml")
    write_load_test(print1, d / "loadtest.csv", np.random.default_rng(11))
    cal = run(["calibrate", d / "print1" / "design.yaml", d / "loadtest.csv", "--out", d / "cal", "--no-plot"])
    assert cal.exit_code == 0, cal.output
    second = run(["design", SPEC, "--calibration", d / "cal" / "calibration.json", "--out", d / "print2", "--no-plot"])
    assert second.exit_code == 0, second.output
    return {"dir": d, "print1": print1, "second": second}


def test_the_first_print_misses_and_the_second_meets_every_target(loop):
    S_t, R_t = targets()
    S1, R1 = outputs(loop["print1"])
    miss1 = np.abs(np.concatenate([S1 / S_t, R1 / R_t]) - 1.0)
    assert miss1.max() > 0.2  # tens of percent: the printer is not the drawing
    S2, R2 = outputs(print_of(loop["dir"] / "print2" / "design.yaml"))
    miss2 = np.abs(np.concatenate([S2 / S_t, R2 / R_t]) - 1.0)
    assert miss2.max() < 0.05, miss2


def test_the_second_design_says_what_it_took_and_draws_thinner_walls(loop):
    out = loop["second"].output
    rec = json.loads((loop["dir"] / "cal" / "calibration.json").read_text())["parameters"]
    for key in ("printer.wall_offset_mm", "printer.modulus_factor", "printer.gap_offset_mm", "magnet.remanence_T"):
        assert key in out
    assert f"± {rec['wall_offset_mm']['std']:.4f} mm" in out  # with its uncertainty
    doc2 = load_document(loop["dir"] / "print2" / "design.yaml")
    assert doc2.printer.wall_offset_mm == pytest.approx(rec["wall_offset_mm"]["value"], abs=1e-12)
    assert doc2.printer.wall_offset_mm == pytest.approx(WALL_MM, abs=0.005)
    assert doc2.printer.modulus_factor == pytest.approx(MODULUS, abs=0.02)
    report = json.loads((loop["dir"] / "print2" / "report.json").read_text())["design"]
    assert set(report["calibration"]["taken"]) == {
        "printer.wall_offset_mm",
        "printer.modulus_factor",
        "printer.gap_offset_mm",
        "magnet.remanence_T",
    }


def test_export_draws_the_walls_as_drawn(loop, tmp_path):
    design = loop["dir"] / "print2" / "design.yaml"
    r = run(["export", design, "--stl", "--out", tmp_path])
    assert r.exit_code == 0, r.output
    drawn = [la.t_mm for la in load_document(design).layers]
    exported = [la["t_mm"] for la in json.loads((tmp_path / "export.json").read_text())["layers"]]
    assert exported == pytest.approx(drawn, abs=1e-9)


def test_simulate_models_a_design_as_its_printer_section_says(loop, tmp_path):
    design = loop["dir"] / "print2" / "design.yaml"
    r = run(["simulate", design, "--out", tmp_path, "--no-plot"])
    assert r.exit_code == 0, r.output
    assert "as printed: printer.wall_offset_mm" in r.output
    rep = json.loads((tmp_path / "report.json").read_text())
    S, R = outputs(as_the_file_says(design))
    got = [row["sensitivity_secant_per_N"] for row in rep["regimes"]]
    assert got == pytest.approx(list(S), rel=1e-7)  # the model file keeps t to 1e-9 mm


def test_a_parameter_the_calibration_held_is_not_used_and_named(loop, tmp_path):
    d = loop["dir"]
    cal = run(
        [
            "calibrate",
            d / "print1" / "design.yaml",
            d / "loadtest.csv",
            "--out",
            tmp_path / "cal",
            "--params",
            "modulus_factor,wall_offset_mm",
            "--no-plot",
        ]
    )
    assert cal.exit_code == 0, cal.output
    r = run(
        ["design", SPEC, "--calibration", tmp_path / "cal" / "calibration.json", "--out", tmp_path / "d", "--no-plot"]
    )
    assert r.exit_code == 0, r.output
    for name in ("gap_offset_mm", "remanence_factor"):
        assert f"calibration: {name} not used: held by the calibration" in r.output
    doc = load_document(tmp_path / "d" / "design.yaml")
    spec = load_document(SPEC)
    assert doc.printer.gap_offset_mm == 0.0 and doc.magnet.remanence_T == spec.magnet.remanence_T
    assert doc.printer.wall_offset_mm != 0.0


def _calibration_cases(loop):
    good = json.loads((loop["dir"] / "cal" / "calibration.json").read_text())
    other = json.loads(json.dumps(good))
    other["design_constants"]["material_name"] = "PLA"
    old = {k: v for k, v in good.items() if k != "design_constants"}
    broken = json.loads(json.dumps(good))
    broken["parameters"]["wall_offset_mm"]["value"] = "thick"
    closing = json.loads(json.dumps(good))
    closing["parameters"]["wall_offset_mm"]["value"] = 0.2  # would print the narrowest cavity shut
    return {
        "missing": None,
        "not json": "{not json",
        "other material": json.dumps(other),
        "older calibrate": json.dumps(old),
        "bad value": json.dumps(broken),
        "a list": "[1, 2]",
        "closes the cavity": json.dumps(closing),
    }


@pytest.mark.parametrize(
    "case", ["missing", "not json", "other material", "older calibrate", "bad value", "a list", "closes the cavity"]
)
def test_a_bad_calibration_exits_2_in_one_line_writing_nothing(loop, tmp_path, case):
    text = _calibration_cases(loop)[case]
    path = tmp_path / "calibration.json"
    if text is not None:
        path.write_text(text)
    r = run(["design", SPEC, "--calibration", path, "--out", tmp_path / "out", "--no-plot"])
    assert r.exit_code == 2, r.output
    lines = r.output.strip().splitlines()
    assert len(lines) == 1 and "--calibration" in lines[0], r.output
    if case == "other material":
        assert "'PLA'" in lines[0] and "material.name" in lines[0]
    if case == "closes the cavity":
        assert "printer.wall_offset_mm" in lines[0] and "0.15 mm" in lines[0]
    assert not (tmp_path / "out").exists()


# --------------------------------------------------------------------------- the worst deviation
def test_the_reported_worst_deviation_is_a_finite_difference_of_the_print(tmp_path):
    raw = yaml.safe_load(SPEC.read_text())
    raw["printer"] = {"wall_offset_mm": 0.03, "modulus_factor": 0.9, "wall_tolerance_mm": 0.04}
    spec = tmp_path / "spec.yaml"
    spec.write_text(yaml.safe_dump(raw))
    r = run(["design", spec, "--out", tmp_path / "out", "--no-plot"])
    assert r.exit_code == 0, r.output
    design = tmp_path / "out" / "design.yaml"
    base = np.concatenate(outputs(as_the_file_says(design)))
    changes = [np.concatenate(outputs(as_the_file_says(design, s * 0.04))) / base - 1.0 for s in (1, -1)]
    worst = float(np.max(np.abs(changes)))
    rms = math.sqrt(np.mean(np.log1p(np.array(changes)) ** 2))
    pe = json.loads((tmp_path / "out" / "report.json").read_text())["design"]["print_error_sensitivity"]
    assert pe["print_error_t_mm"] == 0.04
    assert pe["worst_change_rel"] == pytest.approx(worst, rel=1e-7)  # walls kept to 1e-9 mm
    assert pe["rms_log_change"] == pytest.approx(rms, rel=1e-7)
    assert f"walls +-0.04 mm change S_i, R_i by {100 * worst:.1f} % at worst" in r.output
    S_t, R_t = targets()
    assert np.abs(base / np.concatenate([S_t, R_t]) - 1.0).max() < 0.02  # met as printed


def test_a_default_design_past_25_percent_says_so_in_one_line(tmp_path):
    r = run(["design", SPEC, "--out", tmp_path, "--no-plot"])
    assert r.exit_code == 0, r.output
    worst = json.loads((tmp_path / "report.json").read_text())["design"]["print_error_sensitivity"]["worst_change_rel"]
    assert worst > 0.25
    warned = [line for line in r.output.splitlines() if "--pareto" in line and "--calibration" in line]
    assert len(warned) == 1 and f"{100 * worst:.0f} %" in warned[0]


def _spec_with(tmp_path, name, **design):
    raw = yaml.safe_load(SPEC.read_text())
    raw["design"] = {**(raw.get("design") or {}), **design}
    path = tmp_path / f"{name}.yaml"
    path.write_text(yaml.safe_dump(raw))
    return path


def _housing_height_mm() -> float:
    """The spec's part height less its layers' (the base, plates, cap and insert)."""
    from mst_cli.design.problem import DesignProblem

    return DesignProblem(load_document(SPEC)).height_offset_mm


def test_max_print_deviation_is_met_or_names_the_lowest_height(tmp_path):
    limit = 0.5
    # 5.6 mm for three layers: above the spec's own design (5.37 mm of layers with its 1.6 mm
    # plates), below what the limit needs
    low = round(_housing_height_mm() + 5.6, 2)
    tight = run(
        [
            "design",
            _spec_with(tmp_path, "tight", max_print_deviation_rel=limit, max_height_mm=low),
            "--out",
            tmp_path / "tight",
            "--no-plot",
        ]
    )
    assert tight.exit_code == 1, tight.output
    said = [line for line in tight.output.splitlines() if line.startswith("mst design: targets not met")]
    assert len(said) == 1 and "design.max_print_deviation_rel" in said[0]
    height = float(said[0].split("total height of ")[1].split(" mm")[0])
    assert height > low
    # that height is enough: with it allowed the limit is met, re-simulated by hand
    enough = run(
        [
            "design",
            _spec_with(
                tmp_path, "enough", max_print_deviation_rel=limit, max_height_mm=math.ceil(height * 100) / 100 + 0.01
            ),
            "--out",
            tmp_path / "enough",
            "--no-plot",
        ]
    )
    assert enough.exit_code == 0, enough.output
    design = tmp_path / "enough" / "design.yaml"
    base = np.concatenate(outputs(as_the_file_says(design)))
    for s in (1, -1):
        change = np.concatenate(outputs(as_the_file_says(design, s * 0.05))) / base - 1.0
        assert np.abs(change).max() <= limit + 1e-6
    S_t, R_t = targets()
    assert np.abs(base / np.concatenate([S_t, R_t]) - 1.0).max() < 0.02
    assert "warning: a wall" not in enough.output  # a limit was given: no advice line


def test_max_print_deviation_no_height_can(tmp_path):
    r = run(
        ["design", _spec_with(tmp_path, "never", max_print_deviation_rel=0.2), "--out", tmp_path / "o", "--no-plot"]
    )
    assert r.exit_code == 1, r.output
    assert "mst design: targets not met: design.max_print_deviation_rel: no height meets" in r.output


def _gap_offset_bound_mm() -> float:
    """The most the gap can close under the default housing: its chip clearance, pocket floor and
    cover, less 0.01 mm each of the last two (what calibrate's apply_parameters can write into it)."""
    h = Housing()
    return -(h.chip_clearance_mm + h.pocket_floor_mm + h.cover_mm - 0.02)


@pytest.mark.parametrize(
    "key,value,allowed,more",
    [
        ("wall_offset_mm", 0.2, "0.15 mm", {}),  # (min gap 0.4 - allowance 0.1) / 2: the cavity would close
        ("wall_offset_mm", -0.25, "-0.2 mm", {"min_wall_mm": 0.2}),  # a one-line wall would print to nothing
        ("gap_offset_mm", None, None, {}),  # more than clearance + pocket floor + cover can close
    ],
)
def test_a_printer_that_would_print_a_broken_cell_exits_2(tmp_path, key, value, allowed, more):
    raw = yaml.safe_load(SPEC.read_text())
    if value is None:  # 0.12 mm beyond the default housing's bound (the spec's 2.5 mm cover puts
        # its own, -3.18 mm, past the key's -3 mm: that rule is the key's range, tested elsewhere)
        raw.pop("housing", None)
        value, allowed = round(_gap_offset_bound_mm() - 0.12, 2), f"{_gap_offset_bound_mm():g} mm"
    raw["printer"] = {key: value, **more}
    spec = tmp_path / "spec.yaml"
    spec.write_text(yaml.safe_dump(raw))
    r = run(["design", spec, "--out", tmp_path / "out", "--no-plot"])
    assert r.exit_code == 2, r.output
    lines = r.output.strip().splitlines()
    assert len(lines) == 1 and f"printer.{key} = {value}" in lines[0] and allowed in lines[0], r.output
    assert not (tmp_path / "out").exists()
