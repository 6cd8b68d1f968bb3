"""What the chips can tell apart (issue 39, item 3): the Cramer-Rao bound and the shear
estimator, one chip (Fz, Fx, Fy of a centred press) and two chips (all five).

Numbers fixed outside the code under test: the bound of a linear model (sigma / slope), the count
of numbers against unknowns (three from one chip cannot fix five), known truths put through the
forward model, the spread of estimates from seeded noise against the bound (an efficient
estimator's spread is the bound), and the direction of the readings no load explains (the left
null space of the Jacobian).
"""

import json
from pathlib import Path

import numpy as np
import pytest

from mst_cli.estimation.shear_reading import CHI2_FLAG, ShearReader
from mst_cli.model.general_load import field_T, loaded_stack
from mst_cli.model.load_bound import CENTRED, crb_sigma, field_jacobian
from mst_cli.sensor.as_printed import as_printed
from mst_cli.sensor.document import load_design_document

ROOT = Path(__file__).resolve().parents[1]
FORWARD = ROOT / "configs" / "mohammadi2021-forward.yaml"
TWO_CHIPS = [(0.0, 0.0), (10.0, 6.0)]


@pytest.fixture(scope="module")
def stack():
    doc, _ = load_design_document(FORWARD)
    printed = as_printed(doc)
    return loaded_stack(printed.geometry(), printed.material, "spring")


def test_the_bound_of_a_linear_model_is_noise_over_slope():
    J = np.array([[2.0, 0.0], [0.0, 0.5], [0.0, 0.0]])
    np.testing.assert_allclose(crb_sigma(J, 3.0), [1.5, 6.0], rtol=1e-12)
    # two unknowns the data see only as their sum: neither is bounded
    assert np.all(np.isinf(crb_sigma(np.array([[1.0, 1.0], [2.0, 2.0]]), 1.0)))


def test_one_chip_cannot_bound_five_unknowns_but_bounds_three(stack):
    theta = (12.0, 1.5, -1.0, 2.0, 1.0)
    assert np.all(np.isinf(crb_sigma(field_jacobian(stack, theta, [(0.0, 0.0)]), 1e-6)))
    assert np.all(np.isfinite(crb_sigma(field_jacobian(stack, theta, [(0.0, 0.0)], CENTRED), 1e-6)))
    assert np.all(np.isfinite(crb_sigma(field_jacobian(stack, theta, TWO_CHIPS), 1e-6)))


def test_noiseless_readings_give_the_load_back(stack):
    one = [(4.0, 0.8, -0.4), (25.0, -5.0, 3.0), (45.0, 9.0, 9.0)]
    B = np.array([field_T(stack, t[0], t[1:], (0.0, 0.0)) for t in one])
    r = ShearReader(stack).read(B, 1e-6)
    got = np.stack([r.estimate[k] for k in ("force_N", "shear_x_N", "shear_y_N")], axis=-1)
    np.testing.assert_allclose(got, one, rtol=1e-6, atol=1e-6)
    assert list(r.flag) == ["ok"] * 3
    five = [(5.0, 1.0, -0.5, 2.0, 1.0), (20.0, -3.0, 2.0, -4.0, 2.0), (8.0, 0.0, 2.0, -6.0, -3.0)]
    B2 = np.array([field_T(stack, t[0], t[1:3], t[3:], TWO_CHIPS) for t in five])
    r2 = ShearReader(stack, TWO_CHIPS).read(B2, 1e-6)
    got2 = np.stack([r2.estimate[k] for k in ("force_N", "shear_x_N", "shear_y_N", "x_mm", "y_mm")], axis=-1)
    np.testing.assert_allclose(got2, five, rtol=1e-5, atol=1e-5)


def test_the_spread_of_one_chips_estimates_is_the_bound(stack):
    truth = (15.0, 2.0, -1.0)
    noise = 2e-6
    B = field_T(stack, truth[0], truth[1:], (0.0, 0.0))[0]
    draws = B + np.random.default_rng(39).normal(0.0, noise, (60, 3))
    r = ShearReader(stack).read(draws, noise)
    for k, name in enumerate(("force_N", "shear_x_N", "shear_y_N")):
        err = r.estimate[name] - truth[k]
        bound = float(np.median(r.sigma[name]))
        # 60 draws: the sample spread is within ~20 % of the true one (2 sigma), the mean within 3 SE
        assert 0.75 * bound < err.std() < 1.3 * bound, (name, err.std(), bound)
        assert abs(err.mean()) < 3 * bound / np.sqrt(len(err))


def test_a_reading_no_load_explains_is_flagged(stack):
    # one chip: a sideways field far beyond what the friction cone allows at that little |B|
    B = field_T(stack, 0.5, (0.0, 0.0), (0.0, 0.0))[0] + np.array([500e-6, 0.0, 0.0])
    assert ShearReader(stack).read(B[None, :], 1e-6).flag[0] == "no_fit"
    # two chips: 10 sigma along the one direction of the six numbers no load moves
    theta = (20.0, -3.0, 2.0, -4.0, 2.0)
    J = field_jacobian(stack, theta, TWO_CHIPS)
    u = np.linalg.svd(J)[0][:, -1]  # the left null space of the 6 x 5 Jacobian
    clean = field_T(stack, theta[0], theta[1:3], theta[3:], TWO_CHIPS).ravel()
    r = ShearReader(stack, TWO_CHIPS).read((clean + 10 * 1e-6 * u)[None, :], 1e-6)
    assert r.chi2[0] > CHI2_FLAG[1] and r.flag[0] == "no_fit"
    assert ShearReader(stack, TWO_CHIPS).read(clean[None, :], 1e-6).flag[0] == "ok"


def two_chip_file(tmp_path, positions: str) -> Path:
    text = FORWARD.read_text().replace("  noise_uT_rms: 2.0\n", f"  noise_uT_rms: 2.0\n  positions_mm: {positions}\n")
    path = tmp_path / "two.yaml"
    path.write_text(text)
    return path


def run(args):
    from click.testing import CliRunner

    from mst_cli.cli.app import main

    return CliRunner().invoke(main, [str(a) for a in args])


@pytest.mark.parametrize(
    "positions, says",
    [
        ("[[1, 0], [10, 6]]", "chip_offset_mm"),
        ("[[0, 0], [1, 1]]", ">= 3 mm from chip 0"),
        ("[[0, 0], [150, 0]]", "<= 100"),
        ("[[0, 0], [5, 0], [0, 5], [-5, 0], [0, -5]]", "1 to 4"),
    ],
)
def test_a_bad_chip_layout_is_refused_in_one_line(tmp_path, positions, says):
    res = run(["simulate", two_chip_file(tmp_path, positions), "--out", tmp_path / "o", "--no-plot"])
    assert res.exit_code == 2
    assert len(res.output.strip().splitlines()) == 1 and "positions_mm" in res.output and says in res.output


def test_simulate_states_what_the_chips_tell_apart(tmp_path):
    out = tmp_path / "o"
    res = run(
        [
            "simulate",
            two_chip_file(tmp_path, "[[0, 0], [10, 6]]"),
            "--out",
            out,
            "--no-plot",
            "--shear-ratio",
            "0.2,0.1",
        ]
    )
    assert res.exit_code == 0, res.output
    b = json.loads((out / "report.json").read_text())["shear_bound"]
    assert b["chips_mm"] == [[0.0, 0.0], [10.0, 6.0]] and len(b["estimates"]) == 5
    assert b["region_mm"] == [pytest.approx(9.0), pytest.approx(6.0)]  # 60 % of the 30 x 20 mm face
    lo, hi = (next(r for r in b["noise"] if r["noise_uT"] == n) for n in (0.5, 2.0))
    for name in b["estimates"]:  # the bound is linear in the noise
        assert hi[f"{name}_crb_median"] == pytest.approx(4 * lo[f"{name}_crb_median"], rel=1e-9)
    assert "can tell apart" in res.output
    one = run(["simulate", FORWARD, "--out", tmp_path / "p", "--no-plot", "--shear-ratio", "0,0"])
    b1 = json.loads((tmp_path / "p" / "report.json").read_text())["shear_bound"]
    assert b1["estimates"] == ["force_N", "shear_x_N", "shear_y_N"] and "a second chip tells position" in one.output


@pytest.mark.slow
def test_design_states_what_a_two_chip_layout_tells_apart(tmp_path):
    """The bound is off the design loop: mst design names the command, mst simulate --shear-ratio
    states it for the designed layout."""
    spec = (ROOT / "configs" / "mohammadi2021.yaml").read_text()
    two = tmp_path / "two.yaml"
    two.write_text(
        spec.replace(  # two bare boards that fit the 30 mm face side by side (the footprint is the spec's)
            "  board: adafruit-4022\n",
            "  board: bare-qfn\n  chip_offset_mm: [-7, 0]\n  positions_mm: [[-7, 0], [7, 6]]\n",
        )
        + "model:\n  load_path: layers\n"  # the paper's targets: the layers alone reach them (design.md 4.6)
    )
    res = run(["design", two, "--out", tmp_path / "o", "--no-plot"])
    assert res.exit_code == 0, res.output
    assert "shear_bound" not in json.loads((tmp_path / "o" / "report.json").read_text())["design"]
    assert "2 chips: what they tell apart" in res.output and "--shear-ratio 0.2,0.1" in res.output
    res = run(
        ["simulate", tmp_path / "o" / "design.yaml", "--out", tmp_path / "s", "--no-plot", "--shear-ratio", "0.2,0.1"]
    )
    assert res.exit_code == 0, res.output
    b = json.loads((tmp_path / "s" / "report.json").read_text())["shear_bound"]
    assert b["chips_mm"] == [[-7.0, 0.0], [7.0, 6.0]] and len(b["estimates"]) == 5 and b["shear_ratio"] == [0.2, 0.1]
    lo, hi = (next(r for r in b["noise"] if r["noise_uT"] == n) for n in (0.5, 2.0))
    for name in b["estimates"]:  # the bound is linear in the noise
        assert hi[f"{name}_crb_median"] == pytest.approx(4 * lo[f"{name}_crb_median"], rel=1e-9)
    assert "can tell apart" in res.output


@pytest.mark.parametrize("chips", [None, TWO_CHIPS])
def test_no_readings_give_no_estimates(stack, chips):
    """A batch of none (a stream's empty block, a polish with no ok reading) is no fit at all."""
    r = ShearReader(stack, chips).read(np.zeros((0, 3 * len(chips or [0]))), 1e-6)
    assert r.chi2.shape == (0,) and r.flag.shape == (0,)
    assert all(v.shape == (0,) for v in (*r.estimate.values(), *r.sigma.values()))
