"""`mst simulate` end to end, and the table of malformed input files."""

import json
from pathlib import Path

import pytest
import yaml
from click.testing import CliRunner

from mst_cli.cli.app import main

ROOT = Path(__file__).resolve().parents[1]
FORWARD = ROOT / "configs" / "mohammadi2021-forward.yaml"
GOOD_LAYERS = [{"theta_deg": 25, "t_mm": 0.6, "h_mm": 2.0}, {"theta_deg": 33, "t_mm": 1.0, "h_mm": 2.8}]


def run(args):
    return CliRunner().invoke(main, [str(a) for a in args])


def test_simulate_writes_report_csv_and_png(tmp_path):
    out = tmp_path / "out"
    r = run(["simulate", FORWARD, "--out", out])
    assert r.exit_code == 0, r.output
    assert {p.name for p in out.iterdir()} == {"report.json", "response.csv", "response.png"}
    rep = json.loads((out / "report.json").read_text())
    assert rep["models"] == {"mechanics": "spring", "field": "axial"}
    assert len(rep["regimes"]) == 3 and rep["B0_mT"] > 0 and rep["gap_min_mm"] < rep["gap0_mm"]
    assert rep["magnetometer"]["gain_sel"] is not None
    lines = (out / "response.csv").read_text().splitlines()
    assert lines[0].startswith("force_N,displacement_mm,gap_mm")
    # the chip's z code is the field divided by the chosen LSB size, rounded
    last = dict(zip(lines[0].split(","), lines[-1].split(",")))
    lsb_uT = rep["magnetometer"]["z_uT_per_lsb"]
    assert int(last["Bz_code_lsb"]) == round(float(last["Bz_mT"]) * 1e3 / lsb_uT)
    assert (out / "response.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert "regime" in r.output and "S [1/N]" in r.output


def test_json_flag_and_field_model_override(tmp_path):
    r = run(["simulate", FORWARD, "--out", tmp_path / "a", "--json", "--field-model", "dipole"])
    assert r.exit_code == 0
    rep = json.loads(r.stdout)
    assert rep["models"]["field"] == "dipole"
    exact = json.loads(run(["simulate", FORWARD, "--out", tmp_path / "b", "--json"]).stdout)
    assert rep["B0_mT"] > exact["B0_mT"]


def test_default_output_folder_is_named_after_the_design(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    assert run(["simulate", FORWARD]).exit_code == 0
    assert (tmp_path / "mst-out" / "mohammadi2021-forward" / "report.json").exists()


def doc(**over):
    d = {"name": "x", "layers": GOOD_LAYERS}
    d.update(over)
    return yaml.safe_dump(d)


BAD_FILES = {
    "empty file": ("", "(file)"),
    "not yaml": ("layers: [1, 2\n  - :", "(file)"),
    "not a mapping": ("- 1\n- 2\n", "(file)"),
    "missing layers": (yaml.safe_dump({"name": "x"}), "layers"),
    "no layers": (doc(layers=[]), "layers"),
    "thirteen layers": (doc(layers=GOOD_LAYERS * 6 + GOOD_LAYERS[:1]), "layers"),
    "missing key": (doc(layers=[{"theta_deg": 25, "t_mm": 0.6}]), "layers[0]"),
    "wrong type": (doc(layers=[{"theta_deg": [25], "t_mm": 0.6, "h_mm": 2}]), "layers[0].theta_deg"),
    "string number": (doc(layers=[{"theta_deg": "twenty", "t_mm": 0.6, "h_mm": 2}]), "layers[0].theta_deg"),
    "negative size": (doc(layers=[{"theta_deg": 25, "t_mm": -0.6, "h_mm": 2}]), "layers[0].t_mm"),
    "zero size": (doc(layers=[{"theta_deg": 25, "t_mm": 0.6, "h_mm": 0}]), "layers[0].h_mm"),
    "angle out of range": (doc(layers=[{"theta_deg": 95, "t_mm": 0.6, "h_mm": 2}]), "layers[0].theta_deg"),
    "unknown layer key": (doc(layers=[{"theta_deg": 25, "t_mm": 0.6, "h_mm": 2, "colour": 1}]), "layers[0].colour"),
    "unknown top key": (doc(magnett={}), "magnett"),
    "unknown section key": (doc(magnet={"diameter": 6}), "magnet.diameter"),
    "bad grade": (doc(magnet={"grade": "N99"}), "magnet.grade"),
    "negative modulus": (doc(material={"youngs_modulus_MPa": -3}), "material.youngs_modulus_MPa"),
    "poisson 0.5": (doc(material={"poisson_ratio": 0.5}), "material.poisson_ratio"),
    "bool as number": (doc(family={"width_mm": True}), "family.width_mm"),
    "removed struts key": (doc(family={"struts_per_chevron": 4}), "family.struts_per_chevron"),
    "depth off the layer grid": (doc(family={"depth_mm": 20.1}), "family.depth_mm"),
    "board too long for the depth": (doc(magnetometer={"board": "sparkfun-14571"}), "family.depth_mm"),
    "bad board": (doc(magnetometer={"board": "arduino"}), "magnetometer.board"),
    "bad offset": (doc(magnetometer={"chip_offset_mm": [1]}), "magnetometer.chip_offset_mm"),
    "section not mapping": (doc(housing=[1, 2]), "housing"),
    "nan": ("name: x\nlayers:\n  - {theta_deg: .nan, t_mm: 0.6, h_mm: 2}\n", "layers[0].theta_deg"),
    "spec given to simulate": (
        doc(layers=[{"target_sensitivity_per_N": 0.2, "target_range_N": 1}]),
        "layers[0].theta_deg",
    ),
    "invalid cell": (doc(layers=[{"theta_deg": 25, "t_mm": 1.0, "h_mm": 2.1}]), "layers[0]"),
    "bad name": (doc(name="../escape"), "name"),
}


@pytest.mark.parametrize("case", sorted(BAD_FILES))
def test_bad_input_gives_one_line_naming_the_field_and_exit_2(tmp_path, case):
    text, field = BAD_FILES[case]
    f = tmp_path / "in.yaml"
    f.write_text(text)
    out = tmp_path / "out"
    r = run(["simulate", f, "--out", out])
    assert r.exit_code == 2, (case, r.output)
    lines = r.stderr.strip().splitlines()
    assert len(lines) == 1, lines
    assert lines[0].startswith("mst: invalid input: " + field), lines[0]
    assert not out.exists()


def test_missing_file_exits_2(tmp_path):
    r = run(["simulate", tmp_path / "nope.yaml", "--out", tmp_path / "o"])
    assert r.exit_code == 2 and "file not found" in r.stderr


def test_staged_outputs_vanish_when_the_command_fails(tmp_path):
    from mst_cli.io.outputs import staged

    out = tmp_path / "new"
    with pytest.raises(RuntimeError), staged(out) as st:
        st.write_text("a.txt", "half")
        raise RuntimeError("plot failed")
    assert not out.exists()
    existing = tmp_path / "old"
    existing.mkdir()
    (existing / "keep.txt").write_text("x")
    with pytest.raises(RuntimeError), staged(existing) as st:
        st.write_text("a.txt", "half")
        raise RuntimeError
    assert [p.name for p in existing.iterdir()] == ["keep.txt"]
