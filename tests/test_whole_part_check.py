"""``mst check --whole-part`` (mst_cli/cad/whole_part_check.py): the exported part's section on the
whole-part rung against the field change per newton its design states, per regime, within the
issue's 5 / 8 / 20 % budget, naming the member the closed form misses.

The truth here is not mst's closed form: the rung is checked on its own in
tests/test_whole_part_rung.py (its members rigid it is L2, its cap alone the beam closed form,
and it converges with the mesh). What these tests assert is physics the two must share: members
only add compliance, they nearly add in series, and the bundled forward design, whose cover stays
off the board, is within budget, while the same part with 0.1 mm of air, whose cover lands on
the board in mst's model (a contact the printed body does not have), is not."""

import json
import math
from pathlib import Path

import pytest
import yaml
from click.testing import CliRunner

import mst_cli as mst
from mst_cli import api
from mst_cli.cad.whole_part_check import SHEAR_FIGURES
from mst_cli.cli.app import main
from mst_cli.model.cover_air import air_keeping_cover_off_mm
from mst_cli.model.load_path import ACCURACY_BUDGET_REL

ROOT = Path(__file__).resolve().parents[1]
FORWARD = ROOT / "configs" / "mohammadi2021-forward.yaml"
LANDING_AIR_MM = 0.1  # the forward part's cover lands on the board inside its range (25 N) with this air


@pytest.fixture(scope="module")
def exports(tmp_path_factory) -> dict[str, Path]:
    """The bundled forward design, and the same part with 0.1 mm of air over the board."""
    folder = tmp_path_factory.mktemp("whole_part_check")
    raw = yaml.safe_load(FORWARD.read_text())
    raw["housing"] = {**raw.get("housing", {}), "chip_clearance_mm": LANDING_AIR_MM}
    landing = folder / "landing.yaml"
    landing.write_text(yaml.safe_dump(raw, sort_keys=False))
    out = {}
    for name, design in (("forward", FORWARD), ("landing", landing)):
        mst.export(design, folder / name, stl=True)
        out[name] = folder / name
    return out


@pytest.fixture(scope="module")
def forward_checked(exports) -> tuple:
    """(the forward export's checks with --whole-part, the progress lines they said)."""
    lines = []
    return mst.check(exports["forward"], whole_part=True, progress=lines.append), lines


def whole_part(results, name: str = "whole_part"):
    (check,) = [c for c in results if c.name == name]
    return check


def test_the_bundled_forward_part_gives_what_its_closed_form_states_like_for_like(forward_checked):
    """The bundled forward design (the closed form, with the walls' joints with the plates of
    model.plate_joint): like for like, the design's linear figure against the rung's, every regime
    is within its budget (docs/design.md 4.7: -0.1 / -0.4 / -7.8 %; -7.7 / -8.0 / -10.2 % before
    the joints). The members as printed only add compliance, in the rung as in the design, and
    the secant S sits above the linear figure in every regime: the layers' softening before
    their lock, which no linear model has."""
    results, lines = forward_checked
    check = whole_part(results)
    assert lines and "whole-part rung" in lines[0]
    regimes = check.values["regimes"]
    assert [r["regime"] for r in regimes] == [1, 2, 3]
    assert [r["locked_layers"] for r in regimes] == [[], [1], [1, 2]]  # layer 1 locks first on this design
    for r, budget in zip(regimes, ACCURACY_BUDGET_REL):
        assert r["budget_rel"] == budget
        assert abs(r["error_rel"]) <= budget and r["secant_error_rel"] > r["error_rel"]
        assert r["rung_outside_layers_mm_per_N"] > 0.0 and r["stated_outside_layers_mm_per_N"] > 0.0
    assert check.passed and "whole_part" not in results.failed
    # every layer that locks stiffens the part, in the rung as in the design
    rung = [r["rung_uT_per_N"] for r in regimes]
    assert rung[0] > rung[1] > rung[2]


def test_a_cover_that_lands_on_the_board_fails_and_names_the_air_that_keeps_it_off(exports, tmp_path):
    """The forward part with 0.1 mm of air: mst's cover lands on the board at 15.3 N, inside
    regime 2, and is held there in regime 3, a contact the printed body does not have; like for
    like regime 3 is then past its budget (-29 %; the bundled part, 0.65 mm of air: -15 %), and the
    check names the air that keeps the cover off, whatever member it names first."""
    check = whole_part(mst.check(exports["landing"], whole_part=True))
    assert not check.passed
    regimes = check.values["regimes"]
    assert regimes[2]["error_rel"] < -regimes[2]["budget_rel"]  # -29 %
    members = check.values["regime_members_mm_per_N"]
    worst = regimes[members["regime"] - 1]
    # the members nearly add in series (docs/design.md 4.7: within a few per cent of the part's drop)
    outside = worst["rung_outside_layers_mm_per_N"]
    total = worst["rung_uT_per_N"] / check.values["field_per_drop_uT_per_mm"]
    assert abs(sum(v["rung"] for k, v in members.items() if k != "regime") - outside) < 0.05 * total
    # the remedy is the air that keeps the cover off past 1.25 x the range's end, rounded up
    doc = mst.load(exports["landing"].parent / "landing.yaml")
    air = air_keeping_cover_off_mm(doc.geometry(), doc.material, regimes[2]["force_N"][1])
    assert LANDING_AIR_MM < air < 0.65  # the bundled config's 0.65 mm is past it
    assert f"housing.chip_clearance_mm >= {math.ceil(air * 100) / 100:.2f} mm" in check.note


def test_the_command_fails_naming_the_check_and_writes_its_figures(exports):
    res = CliRunner().invoke(main, ["check", str(exports["landing"]), "--whole-part", "--json"])
    assert res.exit_code == 1
    assert "mst check: failed: whole_part" in res.stderr
    assert "whole-part rung:" in res.stderr  # progress before the solves
    doc = json.loads(res.stdout)
    (row,) = [c for c in doc["checks"] if c["name"] == "whole_part"]
    assert len(row["values"]["regimes"]) == 3 and not row["passed"]


def test_without_the_flag_no_rung_is_solved(exports):
    assert "whole_part" not in {c.name for c in mst.check(exports["forward"])}


@pytest.mark.slow
@pytest.mark.parametrize("name", ["mohammadi2021", "fingertip"])
def test_the_specs_as_bundled_give_what_their_design_states_like_for_like(name, tmp_path):
    """The specs as bundled (closed form, 1.6 mm plates, the cover held 1.5 mm off the board),
    designed and exported as `mst export SPEC` does: like for like, the whole-part rung's linear
    field change per newton is the design's within the 5 / 8 / 20 % budget in every regime
    (docs/design.md 4.7: -1.7 / +6.2 / +8.8 % and -1.3 / +6.5 / +4.2 %)."""
    mst.export(ROOT / "configs" / f"{name}.yaml", tmp_path / "part", stl=True)
    check = whole_part(mst.check(tmp_path / "part", whole_part=True))
    assert check.passed, check.note
    regimes = check.values["regimes"]
    assert [abs(x["error_rel"]) <= x["budget_rel"] for x in regimes] == [True, True, True]


@pytest.mark.slow
def test_a_spec_that_lets_the_cover_land_fails_and_names_the_air_that_keeps_it_off(tmp_path):
    """The paper's targets with the housing's defaults (a 0.8 mm cover, 0.3 mm over the board):
    the design leans on the cover landing on the connectors inside the range (at 0.8 N), a support
    the printed body has not, so the rung's part is far softer after the lock (-55 and -82 %
    measured on 2026-12-02); the check fails and says what air keeps the cover off. (With the
    bundled 3.0 mm cover and only the air at its default, the closed form of 2026-12-02 designs
    a part whose cover does not land, and the check passes.)"""
    raw = yaml.safe_load((ROOT / "configs" / "mohammadi2021.yaml").read_text())
    del raw["housing"]["chip_clearance_mm"], raw["housing"]["cover_mm"]
    spec = tmp_path / "landing.yaml"
    spec.write_text(yaml.safe_dump(raw, sort_keys=False))
    mst.export(spec, tmp_path / "part", stl=True)
    check = whole_part(mst.check(tmp_path / "part", whole_part=True))
    assert not check.passed
    assert check.values["regimes"][-1]["error_rel"] < -0.20
    assert "chip_clearance_mm >=" in check.note and "lands on the board" in check.note


@pytest.mark.slow
def test_the_fingertip_spec_in_section_mode_gives_what_its_design_states(tmp_path):
    """The fingertip spec with ``model.load_path: section``: designed (the rung's correction held
    until the two agree), exported and checked, its linear figure is the rung's within budget in
    every regime; the section rounds' solves are the check's (kept in the rung store)."""
    raw = yaml.safe_load((ROOT / "configs" / "fingertip.yaml").read_text())
    raw["model"] = {**(raw.get("model") or {}), "load_path": "section"}
    spec = tmp_path / "fingertip-section.yaml"
    spec.write_text(yaml.safe_dump(raw, sort_keys=False))
    result = api.design(spec, out=tmp_path / "design", plot=False)
    assert result.status == "met", result.reasons
    mst.export(tmp_path / "design" / "design.yaml", tmp_path / "part", stl=True)
    check = whole_part(mst.check(tmp_path / "part", whole_part=True))
    assert check.passed, check.note


def test_the_shear_report_holds_the_layers_to_the_rung_and_never_fails_the_part(forward_checked):
    """Per regime, the rung with its members rigid and mst's general load of the layers alone are
    two independent models of the same layers (a plane-strain FE and L0's tilt and lateral laws),
    each read where its own regime starts: before the first lock the report's figures, each turned
    into the rung's sign, agree within 5 % (a sign or unit slip in either conversion is a factor
    of -1 or 1000), and past it every figure keeps its sign. The members as printed only add
    compliance: the part slides and turns more than its layers. The report is information: the
    bundled forward part's turn per tangential newton past a lock, which mst's closed form
    overstates several times (docs/design.md 4.7), fails nothing."""
    results, lines = forward_checked
    report = whole_part(results, "whole_part_shear")
    assert report.info and "whole_part_shear" not in results.failed
    assert any("pulled" in line for line in lines)
    regimes = report.values["regimes"]
    assert [r["locked_layers"] for r in regimes] == [[], [1], [1, 2]]  # as the centred check's
    assert regimes[0]["force_N"] < regimes[1]["force_N"] < regimes[2]["force_N"]
    for r in regimes:
        assert set(r["figures"]) == set(SHEAR_FIGURES)
        for key, row in r["figures"].items():
            if r["regime"] == 1:
                assert row["layers_stated"] == pytest.approx(row["layers_rung"], rel=0.05), key
            assert math.copysign(1.0, row["layers_stated"]) == math.copysign(1.0, row["layers_rung"]), key
        slide, per_moment = r["figures"]["slide_per_tangential_mm_per_N"], r["figures"]["turn_per_moment_mrad_per_Nmm"]
        assert slide["rung"] > slide["layers_rung"] > 0.0  # a pull along +x moves the magnet along +x
        assert per_moment["rung"] < per_moment["layers_rung"] < 0.0  # a press at +x turns the top toward +x
    # judged on the worst figure of any regime, which a failing report names with the layers' agreement
    errors = [(abs(row["error_rel"]), r["regime"], k) for r in regimes for k, row in r["figures"].items()]
    worst, regime, key = max(errors)
    assert report.passed == (worst <= report.values["budget_rel"])
    if not report.passed:
        assert SHEAR_FIGURES[key] in report.note and f"regime {regime}" in report.note
        assert "layers alone agree" in report.note
