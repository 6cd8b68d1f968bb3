"""The offset reader's table (`mst read --estimate offset`): its direct inverse, its Cramer-Rao
sigmas and the command around it.

On fields given in closed form the roots are known by algebra: a field linear in (F, x0, y0) is
trilinear exactly, so the table gives its root and the analytic covariance sigma^2 (A^T A)^-1; a
field that folds over has two roots, and the direct inverse finds both (its second start, the
first end mirrored, reaches the other side); a field blind to x0 leaves x0 unidentifiable. On the bundled design's own
tilt rung, readings at the table's nodes come back exactly (trilinear interpolation is exact at
its nodes), and the exact solve polishes a reading between them to the truth.
"""

import shutil
from pathlib import Path

import numpy as np
import pytest
from click.testing import CliRunner
from serial_support import read_fed_stream

from mst_cli.cli.app import main
from mst_cli.estimation.inverse_map import inverse_map
from mst_cli.estimation.inverse_table import TABLE_FILE, InverseTable, TableGrid, source_hash
from mst_cli.estimation.table_start import start_field, start_index, start_nodes, start_quantum_uT
from mst_cli.estimation.table_store import build_beside, table_beside, table_hash
from mst_cli.model.general_load import pose_field_T
from mst_cli.model.response import simulate
from mst_cli.model.stack_pose import tilt_laws
from mst_cli.sensor.document import load_design_document

FORWARD = Path(__file__).resolve().parents[1] / "configs" / "mohammadi2021-forward.yaml"
SIGMA_T = 1e-6
GRID = TableGrid(np.linspace(0.0, 50.0, 11), np.linspace(-10.0, 10.0, 11), np.linspace(-10.0, 10.0, 9))


def table_of(field) -> InverseTable:
    """The table of a closed-form field (T) of p = (F N, x mm, y mm) on GRID."""
    P = np.stack(np.meshgrid(GRID.force_N, GRID.u, GRID.v, indexing="ij"), axis=-1)
    return InverseTable(GRID, np.apply_along_axis(field, -1, P), "closed form")


A = 1e-5 * np.array([[1.0, 0.2, 0.0], [0.1, 2.0, 0.3], [0.0, 0.5, 1.5]])  # T per (N, mm, mm)


def linear(p):
    return A @ p + np.array([0.0, 0.0, 3e-3])


def folded(p):
    return 1e-5 * np.array([p[0], (p[1] - 0.5) ** 2, p[2]])


def blind(p):
    return 1e-5 * np.array([p[0], p[0], p[2]])


def test_a_linear_field_gives_its_root_and_the_analytic_cramer_rao_bound():
    truth = np.array([[23.0, 3.3, -4.1], [1.5, -9.1, 7.7], [49.0, 0.1, 0.3]])  # off the nodes
    est = table_of(linear).estimate(np.array([linear(p) for p in truth]), SIGMA_T, 5.0)
    assert list(est.flag) == ["ok"] * 3 and list(est.roots) == [1, 1, 1]
    np.testing.assert_allclose(np.column_stack([est.force_N, est.x_mm, est.y_mm]), truth, atol=1e-9)
    crb = SIGMA_T * np.sqrt(np.diag(np.linalg.inv(A.T @ A)))
    for got in np.column_stack([est.sigma_force_N, est.sigma_x_mm, est.sigma_y_mm]):
        np.testing.assert_allclose(got, crb, rtol=1e-9)


def test_a_field_that_folds_over_is_ambiguous_by_construction():
    # (x - 0.5)^2 = 4 at x = 2.5 and x = -1.5: both roots are found, whatever came before (the
    # table is trilinear between its 2 mm nodes: each root lies within the parabola's chord error)
    est = table_of(folded).estimate(folded(np.array([21.0, 2.5, 1.1]))[None], SIGMA_T, 5.0)
    assert est.flag[0] == "ambiguous" and est.roots[0] == 2
    assert np.isnan(est.force_N[0])
    # (x - 0.5)^2 = 110.25 at x = -10 (the face's edge) and x = 11 (off it): one press
    edge = table_of(folded).estimate(1e-5 * np.array([[21.0, 110.25, 1.1]]), SIGMA_T, 5.0)
    assert edge.flag[0] == "ok" and edge.roots[0] == 1
    assert (edge.force_N[0], edge.x_mm[0], edge.y_mm[0]) == pytest.approx((21.0, -10.0, 1.1), abs=1e-9)


def test_a_field_blind_to_the_offset_leaves_it_unidentifiable_and_a_field_off_the_table_unfit():
    est = table_of(blind).estimate(np.array([blind(np.array([21.0, 3.1, 1.1])), [1e-5, 2e-4, 0.0]]), SIGMA_T, 5.0)
    assert list(est.flag) == ["not_identifiable", "no_fit"]
    assert est.roots[1] == 0


def index_scan(table: InverseTable, B_uT: np.ndarray) -> np.ndarray:
    """The C header's first start over every slab, written out: outward from the reading's place
    in :func:`start_index`'s order, each side stopped once the index's axis alone is further
    than the nearest node so far, a tie to the node first in C order."""
    axis, order = start_index(table)
    q = start_quantum_uT(table)
    field, out = start_field(1e6 * table.B_T, q).reshape(-1, 3)[order], []
    for b in start_field(B_uT, q):
        best, node, lo = np.inf, -1, int(np.searchsorted(field[:, axis], b[axis], side="left"))
        for side in (range(lo, len(order)), range(lo - 1, -1, -1)):
            for s in side:
                if (field[s, axis] - b[axis]) ** 2 > best:
                    break
                d = float(np.sum((field[s] - b) ** 2))
                if d < best or (d == best and order[s] < node):
                    best, node = d, int(order[s])
        out.append(node)
    return np.array(out)


@pytest.mark.parametrize("field", [linear, folded, blind])
def test_the_headers_indexed_start_is_the_nearest_node_ties_in_c_order(field):
    # blind ties every x0 node; readings at nodes and between them, and far off the table
    table = table_of(field)
    rng = np.random.default_rng(3)
    p = np.column_stack([rng.uniform(0, 50, 60), rng.uniform(-10, 10, 60), rng.uniform(-10, 10, 60)])
    on_table = 1e6 * np.array([field(x) for x in p]) + rng.normal(0.0, 0.5, (60, 3))
    at_nodes = 1e6 * np.array([table.B_T[2, 3, 4], table.B_T[7, 0, 8], 2 * table.B_T[10, 10, 0]])
    B_uT = np.vstack([on_table, at_nodes])
    nodes = np.stack(np.meshgrid(GRID.force_N, GRID.u, GRID.v, indexing="ij"), axis=-1).reshape(-1, 3)
    q = start_quantum_uT(table)
    ints = start_field(1e6 * table.B_T, q).reshape(-1, 3)
    brute = [int(np.argmin(np.sum((ints - b) ** 2, axis=1))) for b in start_field(B_uT, q)]  # the first on a tie
    assert list(index_scan(table, B_uT)) == brute
    starts = start_nodes(table, B_uT, np.full(len(GRID.force_N) - 1, 1e9))  # every slab allowed
    at_rest = nodes[brute][:, 0] == 0.0  # the no-load face's start is the middle of (u, v)
    np.testing.assert_array_equal(starts[~at_rest], nodes[brute][~at_rest])


@pytest.fixture(scope="module")
def design():
    doc, _ = load_design_document(FORWARD)
    imap, _ = inverse_map(doc, "spring")
    return doc, imap


@pytest.fixture(scope="module")
def coarse_model(tmp_path_factory, design):
    """A copy of the forward design with a coarse table (17 forces, 3 mm) beside it."""
    doc, imap = design
    model = tmp_path_factory.mktemp("coarse") / "model.yaml"
    shutil.copy(FORWARD, model)
    build_beside(model, doc, "spring", 1.0, float(imap.force_N[-1]), (17, 3.0)).save(model.parent / TABLE_FILE)
    return model


def test_readings_at_the_tables_nodes_come_back_exactly(coarse_model, design):
    doc, imap = design
    table, note = table_beside(coarse_model, doc, "spring", 1.0, float(imap.force_N[-1]))
    assert note is None  # current: not rebuilt
    g = table.grid
    i, j, k = np.array([4, 8, 12, 15]), np.array([7, 3, 9, 2]), np.array([5, 6, 2, 3])
    est = table.estimate(table.B_T[i, j, k], 2e-6, np.inf)  # the 3 mm cells err by more than 1 mm: no bound
    ok = est.flag == "ok"
    assert ok.sum() >= 3
    truth = np.column_stack([g.force_N[i], g.u[j], g.v[k]])
    np.testing.assert_allclose(np.column_stack([est.force_N, est.x_mm, est.y_mm])[ok], truth[ok], atol=1e-7)


def test_a_table_is_stale_once_its_model_or_calibration_changes(coarse_model, tmp_path):
    table = InverseTable.load(coarse_model.parent / TABLE_FILE)
    assert table is not None and table.source_hash == table_hash(coarse_model, "spring", table.grid)
    assert table.source_hash != table_hash(coarse_model, "frame", table.grid)
    text = coarse_model.read_text()
    assert source_hash(text, "{}", "spring", table.grid) != table.source_hash  # a calibration.json beside
    assert source_hash(text + "\n# edited\n", None, "spring", table.grid) != table.source_hash


def test_a_table_is_stale_under_another_version_of_the_model(coarse_model, monkeypatch):
    """A table kept from another version of the physics modules is not read as current, with no
    manual format bump: the modules' source is hashed in (the same model file, calibration,
    mechanics and grid)."""
    from mst_cli.estimation import inverse_table
    from mst_cli.sensor.rung_store import model_source_hash

    table = InverseTable.load(coarse_model.parent / TABLE_FILE)
    assert table is not None and table.source_hash == table_hash(coarse_model, "spring", table.grid)
    monkeypatch.setattr(inverse_table, "model_source_hash", lambda: model_source_hash() + " edited")
    assert table_hash(coarse_model, "spring", table.grid) != table.source_hash


def run(args):
    return CliRunner().invoke(main, [str(a) for a in args])


def regime_middles_N(doc) -> np.ndarray:
    """The middle force of each regime of the design's part (its own simulate)."""
    r = simulate(doc.geometry(), doc.material, whole_part=doc.whole_part)
    return np.array([0.5 * (g.force_from_N + g.force_to_N) for g in r.regimes])


def readings_csv(path: Path, B: np.ndarray, F: np.ndarray) -> Path:
    path.write_text(
        "Bx_uT,By_uT,Bz_uT,force_N\n"
        + "".join(f"{b[0] * 1e6:.6f},{b[1] * 1e6:.6f},{b[2] * 1e6:.6f},{f}\n" for b, f in zip(B, F))
    )
    return path


def test_read_estimates_the_offset_with_its_sigmas_and_polishes_to_the_truth(coarse_model, design, tmp_path):
    doc, _ = design
    geo, mat = doc.geometry(), doc.material
    # one press in the middle of each regime of the part (model.load_path: part); past the last
    # lock every layer is locked and the stack hardly turns, so a press there no longer tells
    # where it was (not_identifiable)
    F = regime_middles_N(doc)
    csv = readings_csv(tmp_path / "r.csv", pose_field_T(geo, tilt_laws(geo, mat, "spring"), F, (6.0, 3.0)), F)
    res = run(["read", coarse_model, csv, "--out", tmp_path / "o", "--estimate", "offset", "--polish"])
    assert res.exit_code == 0, res.output
    assert not (tmp_path / "o" / TABLE_FILE).exists()  # the table beside the model was current
    import csv as csvmod

    rows = list(csvmod.DictReader((tmp_path / "o" / "forces.csv").open()))
    assert [r["offset_flag"] for r in rows] == ["ok"] * 3
    for r, f in zip(rows, F):
        assert float(r["force_N"]) == pytest.approx(f, rel=1e-6)
        assert (float(r["x_mm"]), float(r["y_mm"])) == pytest.approx((6.0, 3.0), abs=1e-4)
        assert all(float(r[c]) > 0 for c in ("force_N_sigma", "x_mm_sigma", "y_mm_sigma"))


@pytest.mark.parametrize(
    "header, args, says",
    [
        ("Bz_uT,force_N", ["--estimate", "offset"], "Bx_uT"),
        ("Bz_uT,force_N", ["--estimate", "shear"], "Bx_uT"),
        ("Bx_uT,By_uT,Bz_uT", ["--estimate", "tilt"], "--estimate"),
        ("Bx_uT,By_uT,Bz_uT", ["--estimate", "offset", "--max-offset-sigma-mm", "1e-6"], "cannot tell"),
    ],
)
def test_read_refuses_what_it_cannot_estimate_in_one_line_and_writes_nothing(
    coarse_model, tmp_path, header, args, says
):
    csv = tmp_path / "r.csv"
    csv.write_text(header + "\n" + ",".join(["10"] * (header.count(",") + 1)) + "\n")
    res = run(["read", coarse_model, csv, "--out", tmp_path / "o", *args])
    assert res.exit_code == 2 and says in res.output, res.output
    errors = [line for line in res.output.splitlines() if not line.startswith("mst read: warning:")]
    assert len(errors) == 1  # (the model has no calibration.json beside it: warned)
    assert not (tmp_path / "o").exists()


def test_a_serial_stream_is_estimated_live(coarse_model, design, tmp_path):
    doc, _ = design
    geo, mat = doc.geometry(), doc.material
    F = regime_middles_N(doc)  # one press in each of the part's regimes (as above)
    B = pose_field_T(geo, tilt_laws(geo, mat, "spring"), F, (6.0, 3.0)) * 1e6
    # the coarse table's 3 mm cells err by millimetres themselves (its stated 1-sigma says so): no bound
    got, shown = read_fed_stream(coarse_model, B, estimate="offset", out=tmp_path / "o", max_offset_sigma_mm=100.0)
    assert len(got.samples) == 3 and all("at (" in line for line in shown)
    x = [float(line.split(",")[-6]) for line in (tmp_path / "o" / "forces.csv").read_text().splitlines()[1:]]
    assert x == pytest.approx([6.0] * 3, abs=0.5)  # the coarse table's 3 mm cells, unpolished
