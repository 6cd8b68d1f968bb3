"""docs/examples run as a user runs them, and what they print is checked against what the
physics or an independent source fixes (the spec's targets, the known print errors, ...)."""

from __future__ import annotations

import re
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
import yaml
from test_calibrate import TRUTH

ROOT = Path(__file__).resolve().parents[1]
EXAMPLES = ROOT / "docs" / "examples"
sys.path.insert(0, str(ROOT / "studies"))
from printed_sensor import loadtest_csv  # noqa: E402  (studies/ is not a package)

NUMBER = r"[-+]?\d+(?:\.\d+)?"


def run_example(name: str, cwd: Path) -> str:
    r = subprocess.run([sys.executable, str(EXAMPLES / name)], cwd=cwd, capture_output=True, text=True, timeout=600)
    assert r.returncode == 0, r.stderr
    return r.stdout


def test_examples_are_short_scripts():
    scripts = sorted(EXAMPLES.glob("*.py"))
    assert 4 <= len(scripts) <= 6
    for path in scripts:
        assert len(path.read_text().splitlines()) <= 40, path.name


def test_design_meets_the_spec_targets(tmp_path):
    out = run_example("design_and_plot.py", tmp_path)
    spec = yaml.safe_load((ROOT / "configs" / "mohammadi2021.yaml").read_text())
    rows = re.findall(rf"\| S ({NUMBER}) 1/N .*?\| R ({NUMBER}) N", out)
    assert len(rows) == len(spec["layers"]) and "targets met" in out
    for (S, R), layer in zip(rows, spec["layers"]):
        assert float(S) == pytest.approx(layer["target_sensitivity_per_N"], rel=spec["design"]["tolerance_rel"])
        assert float(R) == pytest.approx(layer["target_range_N"], rel=spec["design"]["tolerance_rel"])
    assert (tmp_path / "mst-out" / "examples" / "design.png").stat().st_size > 0


def test_a_thicker_wall_locks_later_and_is_less_sensitive(tmp_path):
    out = run_example("sweep_wall.py", tmp_path)
    t, S, R = np.array(re.findall(rf"t = ({NUMBER}) mm: S_1 = ({NUMBER}) 1/N, R_1 = ({NUMBER}) N", out), float).T
    # bending stiffness grows as t^3 and outruns the shorter stroke: R rises, S falls
    assert len(t) == 7 and np.all(np.diff(t) > 0)
    assert np.all(np.diff(R) > 0) and np.all(np.diff(S) < 0)


def test_the_exported_body_passes_every_check(tmp_path):
    out = run_example("export_and_check.py", tmp_path)
    results = re.findall(r"^(\w+)\s+(PASS|FAIL)\s", out, re.M)
    assert len(results) >= 10 and all(r == "PASS" for _, r in results), out
    written = {p.name for p in (tmp_path / "mst-out" / "examples" / "print").iterdir()}
    assert {"sensor.stl", "sensor.3mf", "export.json"} <= written


def test_the_bundled_load_test_is_the_known_printed_sensor():
    # the known printed sensor of tests/test_calibrate.py (studies/printed_sensor.py) on the
    # current model: the truth the example recovers is TRUTH
    assert (EXAMPLES / "loadtest.csv").read_text() == loadtest_csv(), (
        "docs/examples/loadtest.csv is not the current model's: run python tools/make_examples.py"
    )


def test_calibration_recovers_the_print_errors(tmp_path):
    out = run_example("calibrate_and_read.py", tmp_path)
    fitted = {n: (float(v), float(sd)) for n, v, sd in re.findall(rf"^(\w+)\s+({NUMBER}) \+- ({NUMBER})$", out, re.M)}
    assert set(fitted) == set(TRUTH)
    for name, (value, std) in fitted.items():
        assert abs(value - TRUTH[name]) < 3 * std + 1e-3, name
    median = float(re.search(rf"median force error ({NUMBER}) %", out).group(1))
    assert median < 1.0  # noise of 2 uT on a field span of mT: well under a percent


@pytest.mark.slow
def test_the_ladder_rungs_agree_on_one_cell(tmp_path):
    out = run_example("ladder_rungs.py", tmp_path)
    laws = {
        r: (float(k), float(F), float(d))
        for r, k, F, d in re.findall(
            rf"^(\w+)\s+k ({NUMBER}) N/mm, locks at ({NUMBER}) N after ({NUMBER}) mm", out, re.M
        )
    }
    assert set(laws) == {"spring", "frame", "continuum"}
    k2, F2, d2 = laws["continuum"]
    for k, F, d in laws.values():
        # the cheap rungs are fitted to the continuum's stiffness and share the cell's lock stroke
        assert k == pytest.approx(k2, rel=0.02) and d == pytest.approx(d2, rel=0.02)
        assert F == pytest.approx(F2, rel=0.15)


def test_an_off_centre_press_mirrors_and_reads_back(tmp_path):
    out = run_example("offcentre_touch.py", tmp_path)
    presses = re.findall(rf"press \(({NUMBER}), ({NUMBER})\) mm at {NUMBER} N: Bx ({NUMBER}) uT, By ({NUMBER}) uT", out)
    (x1, _, bx1, by1), (x2, _, bx2, by2), (_, y3, bx3, by3) = [tuple(map(float, p)) for p in presses]
    # mirror symmetry: a press at -x turns Bx over and leaves By; a press along y has no Bx
    assert x2 == -x1 and bx2 == pytest.approx(-bx1, abs=0.01) and abs(by1) < 0.01 and abs(bx3) < 0.01 and by3 > 0
    line = rf"true\s+({NUMBER}) N: centred\s+({NUMBER}) N, corrected\s+({NUMBER}) N at \(({NUMBER}), ({NUMBER})\) mm ok"
    back = re.findall(line, out)
    assert len(back) >= 5
    for F_true, _, F, x, y in (tuple(map(float, b)) for b in back):
        # noise-free readings of the same model: the press and the force come back
        assert F == pytest.approx(F_true, rel=2e-3, abs=0.01) and (x, y) == pytest.approx((6.0, 3.0), abs=0.02)
    assert max(abs(float(c) / float(t) - 1) for t, c, *_ in back) > 0.2  # what a centred reading misses
