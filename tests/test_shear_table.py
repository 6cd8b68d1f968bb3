"""``mst read --estimate shear`` (one chip): the shear table over (Fz, Fx / Fz, Fy / Fz) of a
centred press, its direct inverse, its Cramer-Rao sigmas and the command around it.

Numbers fixed outside the table: the general-load model evaluated load by load
(:func:`~mst_cli.model.general_load.field_T`, not the table's paths), the chain rule of the
ratio coordinates checked on a field linear in (Fz, Fx, Fy), the bound at the exact model's
Jacobian (:mod:`~mst_cli.model.load_bound`), the mirror symmetry y -> -y of a centred sensor
(By and Fy change sign), and the friction cone the table stops at.
"""

import csv
import shutil
from pathlib import Path

import numpy as np
import pytest
from click.testing import CliRunner
from serial_support import read_fed_stream

from mst_cli import api
from mst_cli.cli.app import main
from mst_cli.estimation.inverse_map import inverse_map
from mst_cli.estimation.inverse_table import (
    SHEAR_TABLE_FILE,
    SHEAR_TABLE_RATIO,
    InverseTable,
    TableGrid,
    build_table,
    kink_edges_N,
)
from mst_cli.estimation.load_readings import LOAD_COLUMNS
from mst_cli.estimation.table_reader import ShearTableReader
from mst_cli.estimation.table_store import build_beside
from mst_cli.model.general_load import field_T, loaded_stack
from mst_cli.model.load_bound import CENTRED, crb_sigma, field_jacobian
from mst_cli.sensor.document import load_design_document

ROOT = Path(__file__).resolve().parents[1]
FORWARD = ROOT / "configs" / "mohammadi2021-forward.yaml"
NOISE_T = 0.5e-6
GRID_SMALL = (17, 0.1)  # forces, ratio step: the test's coarse table (the default is 33 x 0.05)


@pytest.fixture(scope="module")
def model():
    doc, geo = load_design_document(FORWARD)
    stack = loaded_stack(geo, doc.material, "spring")
    top = max(t.lock_force_N for t in stack.tilt)
    # its force nodes at every kink of the part's laws, as the reader's tables (the locks, the
    # layers' own knots and the cover's landing: 7 bands of 4 cells)
    edges = kink_edges_N(stack.tilt, None, top)
    grid = TableGrid.cone(top, GRID_SMALL[0], SHEAR_TABLE_RATIO, GRID_SMALL[1], edges)
    return stack, build_table(geo, doc.material, "spring", grid), top


def loads(rng, n, top, ratio_max=0.3):
    Fz = rng.uniform(0.1, 0.9, n) * top
    r = ratio_max * np.sqrt(rng.uniform(0.0, 1.0, n))
    a = rng.uniform(0.0, 2 * np.pi, n)
    return np.column_stack([Fz, r * Fz * np.cos(a), r * Fz * np.sin(a)])


def fields(stack, L):
    return np.array([field_T(stack, F, (fx, fy), (0.0, 0.0))[0] for F, fx, fy in L])


def test_the_table_holds_the_general_load_field_at_its_nodes(model):
    stack, table, _ = model
    g = table.grid
    for i, j, k in [(3, 0, 10), (8, 5, 5), (16, 10, 2), (12, 7, 9)]:
        F = g.force_N[i]
        exact = field_T(stack, F, (g.u[j] * F, g.v[k] * F), (0.0, 0.0))[0]
        np.testing.assert_allclose(table.B_T[i, j, k], exact, rtol=0, atol=1e-12)


def test_the_ratio_coordinates_carry_a_linear_field_and_its_bound_over_exactly():
    """B linear in (Fz, Fx, Fy) is not trilinear in (F, u, v) (Fx = u F), but at a node it is
    met exactly, and the bound there is the linear model's analytic sigma^2 (A^T A)^-1."""
    A = 1e-5 * np.array([[0.5, 2.0, 0.1], [0.2, 0.3, 1.8], [1.0, 0.05, 0.0]])
    grid = TableGrid.cone(40.0, 9, 0.5, 0.125)
    P = np.stack(np.meshgrid(grid.force_N, grid.u, grid.v, indexing="ij"), axis=-1)
    Q = np.stack([P[..., 0], P[..., 1] * P[..., 0], P[..., 2] * P[..., 0]], axis=-1)
    table = InverseTable(grid, Q @ A.T, "linear")
    truth = np.array([[20.0, 5.0, -2.5], [35.0, -8.75, 17.5]])  # (F, u F, v F) at nodes
    est = table.estimate(truth @ A.T, 1e-6, np.inf)
    assert list(est.flag) == ["ok", "ok"]
    np.testing.assert_allclose(est.p, truth, atol=1e-9)
    sigma = np.sqrt(np.diag(np.linalg.inv(A.T @ A / 1e-12)))
    np.testing.assert_allclose(est.sigma, [sigma, sigma], rtol=1e-6)


def test_noise_free_presses_come_back_within_the_tables_interpolation(model):
    stack, table, top = model
    L = loads(np.random.default_rng(5), 40, top)
    est = table.estimate(fields(stack, L), NOISE_T, np.inf)
    assert np.all(est.flag == "ok")
    F_err = np.abs(est.p[:, 0] - L[:, 0]) / L[:, 0]
    Ft = np.hypot(L[:, 1], L[:, 2])
    big = Ft >= 0.2
    Ft_err = np.hypot(*(est.p[big, 1:] - L[big, 1:]).T) / Ft[big]
    # the coarse test table (17 forces, ratio step 0.1): its interpolation error, not noise
    assert np.median(F_err) < 0.01 and np.median(Ft_err) < 0.05


def test_the_tables_bound_is_the_exact_models_bound(model):
    """The table's Jacobian is its cell's trilinear slope, a secant: across a layer's lock (a kink
    in the layer law) it differs from the exact tangent (up to 20-35 % in a cell of the test's
    coarse table, docs/design.md section 4.5), elsewhere it is the tangent to the cell's
    curvature. The noise it is taken at is the chip's and the table's own error in the root's
    force slab in quadrature (a bound linear in the noise). The median over presses is the check."""
    stack, table, top = model
    L = loads(np.random.default_rng(6), 30, top)
    est = table.estimate(fields(stack, L), NOISE_T, np.inf)
    slab = np.clip(np.searchsorted(table.grid.force_N, est.p[:, 0]) - 1, 0, len(table.grid.force_N) - 2)
    noise_T = np.hypot(NOISE_T, 1e-6 * table.slab_error_uT()[slab])
    rel = []
    for load, got, noise in zip(L, est.sigma, noise_T):
        theta = np.array([*load, 0.0, 0.0])
        exact = crb_sigma(field_jacobian(stack, theta, [stack.geometry.chip_offset_mm], list(CENTRED)), noise)
        rel.append(np.abs(got / exact - 1.0))
    assert np.all(np.median(rel, axis=0) < 0.05)


def test_mirrored_readings_give_mirrored_shear(model):
    """y -> -y maps the centred sensor onto itself: By and Fy change sign, the rest stays."""
    stack, table, top = model
    L = loads(np.random.default_rng(7), 10, top)
    B = fields(stack, L)
    a, b = table.estimate(B, NOISE_T, np.inf), table.estimate(B * np.array([1.0, -1.0, 1.0]), NOISE_T, np.inf)
    np.testing.assert_allclose(b.p * np.array([1.0, 1.0, -1.0]), a.p, atol=1e-9)


def test_a_press_beyond_the_tables_friction_cone_is_no_fit(model):
    stack, table, top = model
    F = 0.5 * top
    inside = field_T(stack, F, (0.45 * F, 0.0), (0.0, 0.0))
    beyond = field_T(stack, F, (0.9 * F, 0.0), (0.0, 0.0))
    est = table.estimate(np.vstack([inside, beyond]), NOISE_T, np.inf)
    assert list(est.flag) == ["ok", "no_fit"]


def test_the_reader_keeps_the_centred_force_and_says_its_assumption(model):
    stack, table, top = model
    F = 0.5 * top
    B = np.vstack([field_T(stack, F, (0.2 * F, -0.1 * F), (0.0, 0.0)), field_T(stack, F, (0.9 * F, 0.0), (0.0, 0.0))])
    r = ShearTableReader(table, NOISE_T).estimate_all(B, np.array([F + 1.0, F - 1.0]))
    assert list(r.flag) == ["ok", "no_fit"] and r.assumption == "centred"
    assert r.force_N[1] == F - 1.0 and np.isnan(r.shear_x_N[1])
    assert (r.x_mm[0], r.y_mm[0]) == (0.0, 0.0) and np.all(np.isnan(r.sigma[0, 3:]))
    assert r.shear_x_N[0] == pytest.approx(0.2 * F, rel=0.02)


@pytest.mark.slow
def test_mst_read_estimate_shear_writes_the_shear_columns(tmp_path, model):
    stack, _, top = model
    L = loads(np.random.default_rng(8), 12, top)
    B = 1e6 * fields(stack, L)
    path = tmp_path / "readings.csv"
    path.write_text("Bx_uT,By_uT,Bz_uT\n" + "".join(f"{b[0]:.5f},{b[1]:.5f},{b[2]:.5f}\n" for b in B))
    res = CliRunner().invoke(
        main, ["read", str(FORWARD), str(path), "--estimate", "shear", "--out", str(tmp_path / "o")]
    )
    assert res.exit_code == 0, res.output
    rows = list(csv.DictReader((tmp_path / "o" / "forces.csv").open()))
    assert set(LOAD_COLUMNS) <= set(rows[0])
    assert (tmp_path / "o" / "shear_table.npz").is_file()
    for row, load in zip(rows, L):
        assert row["assumption"] == "centred" and row["estimate_flag"] == "ok"
        assert float(row["force_N"]) == pytest.approx(load[0], rel=0.01)
        assert float(row["shear_x_N"]) == pytest.approx(load[1], abs=0.05 * np.hypot(*load[1:]) + 0.05)


@pytest.fixture(scope="module")
def coarse_model(tmp_path_factory):
    """A copy of the forward design with the test's coarse shear table beside it."""
    doc, _ = load_design_document(FORWARD)
    imap, _ = inverse_map(doc, "spring")
    model = tmp_path_factory.mktemp("coarse") / "model.yaml"
    shutil.copy(FORWARD, model)
    table = build_beside(model, doc, "spring", 1.0, float(imap.force_N[-1]), GRID_SMALL, kind="shear")
    table.save(model.parent / SHEAR_TABLE_FILE)
    return model


def test_polish_brings_a_reading_between_nodes_to_the_truth(coarse_model, model, tmp_path):
    stack, _, top = model
    L = np.array([[0.3 * top, 0.07 * top, -0.04 * top], [0.6 * top, -0.1 * top, 0.13 * top]])
    B = 1e6 * fields(stack, L)
    path = tmp_path / "r.csv"
    path.write_text("Bx_uT,By_uT,Bz_uT\n" + "".join(f"{b[0]:.7f},{b[1]:.7f},{b[2]:.7f}\n" for b in B))
    got = api.read(coarse_model, path, estimate="shear", polish=True)
    assert got.offset is not None and list(got.offset.flag) == ["ok", "ok"]
    est = np.column_stack([got.force_N, got.offset.shear_x_N, got.offset.shear_y_N])
    np.testing.assert_allclose(est, L, atol=2e-3)  # the exact fit, from 1e-7 T rounding of the file


def test_a_serial_stream_is_estimated_live_with_shear(coarse_model, model, tmp_path):
    stack, _, top = model
    L = np.array([[0.4 * top, 0.1 * top, 0.0]] * 3)
    B = 1e6 * fields(stack, L)
    got, shown = read_fed_stream(coarse_model, B, estimate="shear", out=tmp_path / "o")
    assert len(got.samples) == 3 and all("Ft (" in line for line in shown)
    rows = list(csv.DictReader((tmp_path / "o" / "forces.csv").open()))
    assert [r["assumption"] for r in rows] == ["centred"] * 3
    assert [float(r["shear_x_N"]) for r in rows] == pytest.approx([0.1 * top] * 3, rel=0.03)


@pytest.mark.slow
@pytest.mark.parametrize("beside", ["garbage", "an offset table"])
def test_a_shear_table_file_that_is_not_one_is_rebuilt_and_said(tmp_path, beside):
    model = tmp_path / "model.yaml"
    shutil.copy(FORWARD, model)
    target = tmp_path / SHEAR_TABLE_FILE
    if beside == "garbage":
        target.write_bytes(b"\x00not a table")
    else:  # the right hash for its grid, the wrong kind
        doc, _ = load_design_document(FORWARD)
        build_beside(model, doc, "spring", 1.0, 40.0, (5, 10.0)).save(target)
    path = tmp_path / "r.csv"
    path.write_text("Bx_uT,By_uT,Bz_uT\n0,0,4000\n")
    notes: list[str] = []
    got = api.read(model, path, estimate="shear", out=tmp_path / "o", warn=notes.append)
    said = "is not a table" if beside == "garbage" else "is stale"  # what the file is, named
    assert any(said in n and "--shear-table" in n for n in notes), notes
    assert got.offset is not None and got.offset.flag[0] == "ok"
    assert InverseTable.load(tmp_path / "o" / SHEAR_TABLE_FILE).grid.kind == "shear"
