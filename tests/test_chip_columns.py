"""A readings file of several chips (magnetometer.positions_mm): chip k's columns Bx{k}_uT,
By{k}_uT, Bz{k}_uT (or raw codes), read in chip order; a file whose chips do not match the
model's is refused in one line (exit 2, nothing written)."""

from pathlib import Path

import numpy as np
import pytest
from click.testing import CliRunner

from mst_cli.calibration.loadtest import parse_readings, unknown_columns
from mst_cli.cli.app import main
from mst_cli.errors import InputError
from mst_cli.io.cache import cache_dir

ROOT = Path(__file__).resolve().parents[1]
FORWARD = ROOT / "configs" / "mohammadi2021-forward.yaml"


def two_chip_model(tmp_path) -> Path:
    text = FORWARD.read_text().replace(
        "  noise_uT_rms: 2.0\n", "  noise_uT_rms: 2.0\n  positions_mm: [[0, 0], [10, 6]]\n"
    )
    path = tmp_path / "two.yaml"
    path.write_text(text)
    return path


def test_every_chips_columns_are_read_in_chip_order():
    text = "Bz2_uT,Bx_uT,By_uT,Bz_uT,Bx2_uT,By2_uT,note\n3900,1,2,4000,-5,6,a\n3800,0,0,4100,7,-8,b\n"
    rd = parse_readings(text, "r.csv", need_force=False)
    assert rd.chips == 2 and rd.B_chips_T.shape == (2, 2, 3)
    np.testing.assert_array_equal(rd.B_chips_T[0] * 1e6, [[1, 2, 4000], [-5, 6, 3900]])
    np.testing.assert_array_equal(rd.B_chips_T[:, 0], rd.B_T)
    assert unknown_columns(rd) == ["note"]
    assert rd.subset(np.array([False, True])).B_chips_T.shape == (1, 2, 3)
    assert parse_readings("Bx_uT,By_uT,Bz_uT\n1,2,3\n", "r.csv", need_force=False).chips == 1


@pytest.mark.parametrize(
    "header, says",
    [
        ("Bx_uT,By_uT,Bz_uT,Bx2_uT,By2_uT", "Bz2_uT"),
        ("Bx_uT,By_uT,Bz_uT,Bx3_uT,By3_uT,Bz3_uT", "Bx2_uT"),  # chip 2 skipped
        ("Bx_uT,By_uT,Bz_uT,Bx5_uT,By5_uT,Bz5_uT", "2 to 4"),
        ("Bx_uT,By_uT,Bz_uT,Bx2_code_lsb,By2_code_lsb,Bz2_code_lsb", "in uT"),
    ],
)
def test_a_broken_chip_header_is_refused_naming_it(header, says):
    n = header.count(",") + 1
    with pytest.raises(InputError) as e:
        parse_readings(header + "\n" + ",".join(["10"] * n) + "\n", "r.csv", need_force=False)
    assert says in str(e.value)


def test_a_nan_in_chip_2s_column_names_it():
    with pytest.raises(InputError) as e:
        parse_readings("Bx_uT,By_uT,Bz_uT,Bx2_uT,By2_uT,Bz2_uT\n1,2,3,4,nan,6\n", "r.csv", need_force=False)
    assert "By2_uT" in str(e.value) and "line 2" in str(e.value)


def run(args):
    return CliRunner().invoke(main, [str(a) for a in args])


@pytest.mark.parametrize(
    "two_chips, header, estimate, says",
    [
        (False, "Bx_uT,By_uT,Bz_uT,Bx2_uT,By2_uT,Bz2_uT", "none", "places 1 chip"),
        (True, "Bx_uT,By_uT,Bz_uT", "shear", "every chip's columns"),
    ],
)
def test_a_file_whose_chips_do_not_match_the_model_is_refused(tmp_path, two_chips, header, estimate, says):
    model = two_chip_model(tmp_path) if two_chips else FORWARD
    csv = tmp_path / "r.csv"
    csv.write_text(header + "\n" + ",".join(["0", "0", "4000"] * (header.count(",") // 3 + 1)) + "\n")
    res = run(["read", model, csv, "--estimate", estimate, "--out", tmp_path / "o"])
    assert res.exit_code == 2 and says in res.output, res.output
    errors = [line for line in res.output.splitlines() if not line.startswith("mst read: warning:")]
    assert len(errors) == 1
    assert not (tmp_path / "o").exists()


def test_a_two_chip_model_reads_its_first_chips_force_without_an_estimate(tmp_path):
    csv = tmp_path / "r.csv"
    csv.write_text("Bx_uT,By_uT,Bz_uT,Bx2_uT,By2_uT,Bz2_uT\n0,0,4000,100,50,3000\n")
    one = tmp_path / "one.csv"
    one.write_text("Bx_uT,By_uT,Bz_uT\n0,0,4000\n")
    model = two_chip_model(tmp_path)
    a, b = run(["read", model, csv, "--out", tmp_path / "a"]), run(["read", model, one, "--out", tmp_path / "b"])
    assert a.exit_code == 0 and b.exit_code == 0, a.output + b.output
    fa = (tmp_path / "a" / "forces.csv").read_text().splitlines()[1].split(",")
    fb = (tmp_path / "b" / "forces.csv").read_text().splitlines()[1].split(",")
    assert fa[6:] == fb[3:]  # the force, regime, flag, resolution: chip 1's


@pytest.mark.slow
def test_mst_read_estimates_all_five_from_two_chips(tmp_path):
    """Readings of the two-chip model's own general load (noise-free, written to 1e-4 uT): every
    unknown comes back, the assumption is none, and each carries its 1-sigma."""
    from mst_cli.model.general_load import field_T, loaded_stack
    from mst_cli.sensor.document import load_design_document

    model = two_chip_model(tmp_path)
    doc, geo = load_design_document(model)
    stack = loaded_stack(geo, doc.material, "spring")
    # up to the part's last regime (its locks 10.0, 29.0 and 30.6 N): a force past the last lock
    # is no force the sensor can give (flagged no_fit, issue 46), so the last press is 30.0 N
    loads = [(12.0, 2.0, -1.0, 3.0, -2.0), (28.0, -4.0, 3.0, -5.0, 2.5), (30.0, 6.0, 5.0, 1.0, 1.0)]
    rows = []
    for F, fx, fy, x, y in loads:
        B = 1e6 * field_T(stack, F, (fx, fy), (x, y), doc.chips_mm).ravel()
        rows.append(",".join(f"{b:.4f}" for b in B))
    csv_path = tmp_path / "r.csv"
    csv_path.write_text("Bx_uT,By_uT,Bz_uT,Bx2_uT,By2_uT,Bz2_uT\n" + "\n".join(rows) + "\n")
    res = run(["read", model, csv_path, "--estimate", "shear", "--out", tmp_path / "o"])
    assert res.exit_code == 0, res.output
    assert "building the two-chip reader's layer tables" in res.stderr  # said before the seconds it takes
    # the tables are kept: a second read (another --out) builds nothing and writes the same forces
    again = run(["read", model, csv_path, "--estimate", "shear", "--out", tmp_path / "o2"])
    assert again.exit_code == 0 and "layer tables" not in again.stderr, again.stderr
    assert (tmp_path / "o2" / "forces.csv").read_text() == (tmp_path / "o" / "forces.csv").read_text()
    # a kept file that is not such a table is passed over and built anew
    (kept,) = cache_dir().glob("two-chip-*.npz")
    kept.write_bytes(b"not a table")
    third = run(["read", model, csv_path, "--estimate", "shear", "--out", tmp_path / "o3"])
    assert third.exit_code == 0 and "building the two-chip reader's layer tables" in third.stderr
    assert (tmp_path / "o3" / "forces.csv").read_text() == (tmp_path / "o" / "forces.csv").read_text()
    import csv

    got = list(csv.DictReader((tmp_path / "o" / "forces.csv").open()))
    for row, (F, fx, fy, x, y) in zip(got, loads):
        assert row["assumption"] == "none" and row["estimate_flag"] == "ok"
        assert float(row["force_N"]) == pytest.approx(F, rel=2e-3)
        assert (float(row["shear_x_N"]), float(row["shear_y_N"])) == pytest.approx((fx, fy), abs=0.02)
        assert (float(row["x_mm"]), float(row["y_mm"])) == pytest.approx((x, y), abs=0.02)
        assert all(float(row[c]) > 0 for c in ("x_mm_sigma", "y_mm_sigma", "shear_x_N_sigma"))
