"""The housing's cover stays off the board's parts within the designed range (issue 44, docs/design.md
4.6): the cover bends over the board slot until it closes its air onto the chip and connectors; past
that the press bears on the board, a support of the assembly that the printed body (export's STL) lacks.
``mst design`` keeps that landing past the range's end; a spec whose targets need it is not met, and the
one line names the cover and what to do. Checked on ``mst simulate``'s report of the written design,
the forward model's code path, not the design loop's vectorised one."""

import json
import re
from pathlib import Path

import pytest
import yaml
from click.testing import CliRunner

import mst_cli as mst
from mst_cli.cli.app import main
from mst_cli.design.problem import COVER_LANDING_RULE, DesignProblem

ROOT = Path(__file__).resolve().parents[1]


def _design_and_simulate(spec: Path, tmp_path: Path):
    """(mst design's result, simulate's report.json and terminal output on the written design)."""
    runner = CliRunner()
    designed = runner.invoke(main, ["design", str(spec), "--out", str(tmp_path / "d"), "--no-plot"])
    written = str(tmp_path / "d" / "design.yaml")
    sim = runner.invoke(main, ["simulate", written, "--out", str(tmp_path / "s"), "--no-plot"])
    assert sim.exit_code == 0, sim.output
    return designed, json.loads((tmp_path / "s" / "report.json").read_text()), sim.output


@pytest.mark.slow
@pytest.mark.parametrize("config", ["mohammadi2021", "fingertip"])
def test_the_designed_cover_lands_past_the_range(tmp_path, config):
    """The bundled specs with 2.5 mm covers (whose designs leaned on the landing at 6.7 and 12.2 N
    before the constraint) are met, and simulate's report puts the landing (or none: layer 1 off
    the slot) past the range's end; the design loop's constraint is R_3 (1 + tolerance) / landing - 1."""
    designed, report, output = _design_and_simulate(ROOT / "configs" / f"{config}.yaml", tmp_path)
    assert designed.exit_code == 0, designed.output
    end_N = report["load_path"]["regimes"][-1]["force_N"][1]
    assert end_N == pytest.approx(16.2, rel=0.02)  # the target R_3 within the tolerance
    lands_N = report["load_path"]["cover_lands_N"]
    assert "inside the range" not in output
    if lands_N is None:  # layer 1's feet on the slot walls: no bending over the slot
        return
    assert lands_N > end_N
    doc = mst.load(tmp_path / "d" / "design.yaml")
    problem = DesignProblem(doc)
    cells = doc.layers
    ev = problem.evaluate_physical(*([getattr(c, k) for c in cells] for k in ("theta_deg", "t_mm", "h_mm")))
    g = ev.constraints[problem.constraint_names().index(COVER_LANDING_RULE)]
    assert g == pytest.approx(16.2 * 1.02 / lands_N - 1.0, abs=1e-6)


@pytest.mark.slow
def test_targets_that_need_the_landing_are_not_met_naming_the_cover(tmp_path):
    """The paper's targets with a 0.3 mm cover and layer 1 held at 10-20 deg (its feet over the
    slot): without the constraint mst design met them with the cover on the board from 0.43 N
    (measured on the base commit). Now the nearest design holds the cover off to R_3, its bending
    over the slot at the bound (air / (R_3 + 2 %) = 0.3 / 16.524 mm/N), misses, and the one line names the
    housing's cover and a thicker housing.cover_mm."""
    spec = yaml.safe_load((ROOT / "configs" / "mohammadi2021.yaml").read_text())
    spec["housing"]["cover_mm"] = 0.3
    spec["design"]["theta_deg_bounds"] = [10, 20]
    (tmp_path / "thin.yaml").write_text(yaml.safe_dump(spec))
    designed, report, _ = _design_and_simulate(tmp_path / "thin.yaml", tmp_path)
    assert designed.exit_code == 1, designed.output
    line = designed.output.strip().splitlines()[-1]
    assert line.startswith("mst design: targets not met: the housing's cover: "), line
    assert "a thicker housing.cover_mm" in line
    bending = float(re.search(r"its bending over the slot \(([0-9.]+) mm/N, 0.3 mm of air\)", line).group(1))
    bound = 0.3 / (16.2 * 1.02)  # the air over the range's end: the constraint's edge, where it binds
    assert bound * (1 - 0.02) * 0.995 <= bending <= bound * 1.005  # binding (ACTIVE_TOL), 3 digits
    assert report["load_path"]["cover_lands_N"] >= 16.2  # the written design holds it off too
