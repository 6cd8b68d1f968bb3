"""Hostile input, round four (issue 46): the files ``mst read`` finds beside the model, a
hand-edited calibration.json, values no sensor can give, columns and counts, force units and
small messages; and issue 45's table kept for the next call. One section per class; each test
failed on 0.17 (a traceback, a hang, an interrupt reported for a non-interrupt, or exit 0 with a
wrong, impossible or duplicated output) and passes now. Section 3 is the property suite over the
readers.

The tables are built on small grids (the default's build takes a minute on a busy machine): the
grid is monkeypatched, the checks are the same.
"""

import io
import json
import os
import re
import shutil
import subprocess
import sys
import warnings
import zipfile
from pathlib import Path

import numpy as np
import pytest
from click.testing import CliRunner
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import mst_cli.estimation.table_store as table_store
from mst_cli.calibration.calibration_json import CalibrationRecord
from mst_cli.calibration.loadtest import parse_readings
from mst_cli.cli.app import main
from mst_cli.errors import InputError
from mst_cli.estimation.inverse_table import SHEAR_TABLE_FILE, TABLE_FILE, InverseTable
from mst_cli.estimation.table_reader import OffsetTableReader, ShearTableReader, TwoChipLoadReader
from mst_cli.estimation.table_store import build_beside, table_beside
from mst_cli.estimation.two_chip_table import TwoChipReader
from mst_cli.model.general_load import loaded_stack
from mst_cli.model.response import simulate
from mst_cli.model.temperature import modulus_scale
from mst_cli.readout.reading import ForceReader
from mst_cli.sensor.document import load_design_document, load_document

ROOT = Path(__file__).resolve().parents[1]
FORWARD = ROOT / "configs" / "mohammadi2021-forward.yaml"
SMALL_SHEAR = (5, 0.25)  # forces, ratio step: 5 x 5 x 5 nodes
SMALL_OFFSET = (5, 6.0)  # forces, mm between offsets
MST = "import sys; from mst_cli.cli.app import main; sys.exit(main())"


def run(args):
    return CliRunner().invoke(main, [str(a) for a in args])


def refused(r, field: str) -> str:
    """Exit 2, one line on stderr naming ``field``; returns the line."""
    assert r.exit_code == 2, (r.exit_code, r.output, r.exception)
    lines = r.stderr.strip().splitlines()
    assert len(lines) == 1, lines
    assert lines[0].startswith("mst: invalid input: ") and field in lines[0], lines[0]
    return lines[0]


@pytest.fixture
def small_grids(monkeypatch):
    monkeypatch.setattr(table_store, "SHEAR_GRID_DEFAULT", SMALL_SHEAR)
    monkeypatch.setattr(table_store, "GRID_DEFAULT", SMALL_OFFSET)


@pytest.fixture(scope="module")
def design():
    doc = load_document(FORWARD)
    resp = simulate(doc.geometry(), doc.material, noise_uT_rms=doc.noise_uT_rms)
    return doc, resp


def field_rows_uT(resp, F: np.ndarray, rng, noise_uT: float = 2.0) -> np.ndarray:
    B = np.stack([np.interp(F, resp.force_N, resp.B_T[:, i]) for i in range(3)], -1) * 1e6
    return B + rng.normal(0, noise_uT, B.shape)


def csv_text(header: str, *columns) -> str:
    rows = zip(*columns)
    return (
        header + "\n" + "".join(",".join(f"{v:.6g}" if not isinstance(v, str) else v for v in r) + "\n" for r in rows)
    )


@pytest.fixture(scope="module")
def files(tmp_path_factory, design):
    """A load test and readings of the forward design, and its calibration (mst calibrate)."""
    _, resp = design
    rng = np.random.default_rng(5)
    F = np.sort(rng.uniform(0, resp.max_force_N, 40))
    B = field_rows_uT(resp, F, rng)
    d = tmp_path_factory.mktemp("read")
    (d / "lt.csv").write_text(csv_text("force_N,Bx_uT,By_uT,Bz_uT", F, *B.T))
    (d / "readings.csv").write_text(csv_text("Bx_uT,By_uT,Bz_uT", *B.T))
    r = run(["calibrate", FORWARD, d / "lt.csv", "--out", d / "cal"])
    assert r.exit_code == 0, r.output
    return {"dir": d, "F": F, "B_uT": B, "cal": d / "cal", "top_N": resp.max_force_N}


# ----------------------------------------------------------------- 1. a table beside the model that is not one
@pytest.fixture(scope="module")
def good_tables(tmp_path_factory, design):
    """A model file and its current small shear and offset tables' bytes."""
    doc, resp = design
    d = tmp_path_factory.mktemp("tables")
    model = d / "model.yaml"
    shutil.copy(FORWARD, model)
    top = float(resp.force_N[resp.in_range][-1])
    out = {}
    for kind, grid in (("shear", SMALL_SHEAR), ("offset", SMALL_OFFSET)):
        buf = io.BytesIO()
        np.savez(buf, **build_beside(model, doc, "spring", 1.0, top, grid, kind).arrays())
        out[kind] = buf.getvalue()
    return model, out


def npz_with(data: bytes, **changes) -> bytes:
    with np.load(io.BytesIO(data)) as z:
        arrays = {k: z[k] for k in z.files}
    arrays.update(changes)
    buf = io.BytesIO()
    np.savez(buf, **arrays)
    return buf.getvalue()


def huge_header(data: bytes, shape: tuple | None = None) -> bytes:
    """B_T.npy's header claims 200,000 bytes (numpy refuses more than 10,000 unless told), or,
    with ``shape``, an array of that shape (its data a few bytes)."""
    buf = io.BytesIO()
    with zipfile.ZipFile(io.BytesIO(data)) as src, zipfile.ZipFile(buf, "w") as dst:
        for name in src.namelist():
            raw = src.read(name)
            if name == "B_T.npy" and shape is None:
                raw = b"\x93NUMPY\x02\x00" + (200_000).to_bytes(4, "little") + b"{" + b" " * 199_999
            elif name == "B_T.npy":
                header = f"{{'descr': '<f8', 'fortran_order': False, 'shape': {shape}, }}".ljust(117) + "\n"
                raw = b"\x93NUMPY\x01\x00" + len(header).to_bytes(2, "little") + header.encode() + b"\0" * 64
            dst.writestr(name, raw)
    return buf.getvalue()


def hostile_table(case: str, data: bytes) -> bytes:
    with np.load(io.BytesIO(data)) as z:
        B, force_N = z["B_T"], z["force_N"]
    npy = io.BytesIO()
    np.save(npy, B)
    crc = bytearray(data)
    crc[len(crc) // 2] ^= 0xFF
    return {
        "zero-byte": b"",
        "truncated": data[: len(data) // 2],
        "crc-corrupt": bytes(crc),
        "plain-npy": npy.getvalue(),
        "array-for-scalar": npz_with(data, format=np.arange(3)),
        "string-arrays": npz_with(data, force_N=force_N.astype(str)),  # the nodes, as text
        "huge-header": huge_header(data),
        "huge-shape": huge_header(data, shape=(10**6, 10**6, 3)),
        "all-nan": npz_with(data, B_T=np.full_like(B, np.nan)),
    }[case]


TABLE_CASES = [
    "zero-byte",
    "truncated",
    "crc-corrupt",
    "plain-npy",
    "array-for-scalar",
    "string-arrays",
    "huge-header",
    "huge-shape",
    "all-nan",
]


@pytest.mark.parametrize("kind", ["shear", "offset"])
@pytest.mark.parametrize("case", TABLE_CASES)
def test_a_table_beside_the_model_that_is_not_good_is_rebuilt_and_named(
    tmp_path, good_tables, design, small_grids, case, kind
):
    src, data = good_tables
    model = tmp_path / "model.yaml"
    shutil.copy(src, model)
    path = tmp_path / (SHEAR_TABLE_FILE if kind == "shear" else TABLE_FILE)
    path.write_bytes(hostile_table(case, data[kind]))
    doc, resp = design
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # no numpy warning leaks
        table, note = table_beside(model, doc, "spring", 1.0, float(resp.force_N[resp.in_range][-1]), kind)
    assert table.grid.kind == kind and np.all(np.isfinite(table.B_T))
    assert note is not None and str(path) in note and "built the" in note, note
    assert "\n" not in note


def test_a_zero_byte_table_is_not_reported_as_an_interrupt(tmp_path, files, small_grids):
    cal = tmp_path / "cal"
    shutil.copytree(files["cal"], cal)
    (cal / SHEAR_TABLE_FILE).write_bytes(b"")
    r = run(
        ["read", cal / "calibrated.yaml", files["dir"] / "readings.csv", "--estimate", "shear", "--out", tmp_path / "o"]
    )
    assert r.exit_code == 0, (r.exit_code, r.stderr)
    assert "interrupted" not in r.stderr and f"{cal / SHEAR_TABLE_FILE} is not a table" in r.stderr, r.stderr


@pytest.mark.parametrize("special", ["fifo", "folder"])
def test_a_fifo_or_folder_in_the_tables_place_is_passed_over_without_blocking(tmp_path, files, special):
    cal = tmp_path / "cal"
    shutil.copytree(files["cal"], cal)
    if special == "fifo":
        os.mkfifo(cal / SHEAR_TABLE_FILE)
    else:
        (cal / SHEAR_TABLE_FILE).mkdir()
    script = (
        "import sys; import mst_cli.estimation.table_store as t; t.SHEAR_GRID_DEFAULT = (5, 0.25); "
        "from mst_cli.cli.app import main; sys.exit(main())"
    )
    args = [
        "read",
        cal / "calibrated.yaml",
        files["dir"] / "readings.csv",
        "--estimate",
        "shear",
        "--out",
        tmp_path / "o",
    ]
    p = subprocess.run([sys.executable, "-c", script, *map(str, args)], capture_output=True, text=True, timeout=300)
    assert p.returncode == 0, p.stderr
    kind = "a FIFO (named pipe)" if special == "fifo" else "a folder"
    assert f"{cal / SHEAR_TABLE_FILE} is {kind}, not a table" in p.stderr, p.stderr


def test_a_table_that_cannot_be_rebuilt_is_one_line_naming_the_file(tmp_path, files, small_grids, monkeypatch):
    cal = tmp_path / "cal"
    shutil.copytree(files["cal"], cal)
    (cal / SHEAR_TABLE_FILE).write_bytes(b"PK\x03\x04 truncated")

    def fails(*args, **kwargs):
        raise ValueError("the model gives no field here")

    monkeypatch.setattr(table_store, "build_table", fails)
    r = run(
        ["read", cal / "calibrated.yaml", files["dir"] / "readings.csv", "--estimate", "shear", "--out", tmp_path / "o"]
    )
    assert r.exit_code not in (0, 1, 130) and r.exception is None or isinstance(r.exception, SystemExit)
    lines = r.stderr.strip().splitlines()
    assert str(cal / SHEAR_TABLE_FILE) in lines[-1] and "cannot be rebuilt" in lines[-1], lines
    assert not (tmp_path / "o").exists()


# ----------------------------------------------------------------- 2. a table built once per model (issue 45)
def test_a_table_is_built_once_and_reused_whatever_out_says(tmp_path, files, small_grids):
    model = tmp_path / "model.yaml"
    shutil.copy(FORWARD, model)  # the design itself: no table beside it, none written there
    readings = files["dir"] / "readings.csv"
    first = run(["read", model, readings, "--estimate", "shear", "--out", tmp_path / "a"])
    assert first.exit_code == 0 and "built the shear table" in first.stderr, first.stderr
    second = run(["read", model, readings, "--estimate", "shear", "--out", tmp_path / "b"])
    assert second.exit_code == 0 and "built" not in second.stderr, second.stderr
    assert (tmp_path / "a" / "forces.csv").read_text() == (tmp_path / "b" / "forces.csv").read_text()
    kept = list(Path(os.environ["MST_CACHE_DIR"]).glob("shear-*.npz"))
    assert len(kept) == 1 and InverseTable.load(kept[0]) is not None
    assert not (tmp_path / SHEAR_TABLE_FILE).exists()  # nothing written beside the user's file


# ----------------------------------------------------------------- 3. a hand-edited calibration.json
def edited(files, dest: Path, change) -> Path:
    """A copy of the calibration whose calibration.json ``change`` edited (the model file, and so
    its hash, as written)."""
    shutil.copytree(files["cal"], dest)
    path = dest / "calibration.json"
    record = json.loads(path.read_text())
    change(record)
    path.write_text(json.dumps(record))
    return dest / "calibrated.yaml"


def with_columns(files, dest: Path, **columns) -> Path:
    B = files["B_uT"]
    header = "Bx_uT,By_uT,Bz_uT" + "".join(f",{k}" for k in columns)
    dest.write_text(csv_text(header, *B.T, *columns.values()))
    return dest


def temperature(beta):
    return lambda r: r.__setitem__("temperature", {"modulus_temp_coeff_per_K": beta})


def unloading(**terms):
    model = {"a": 0.2, "b": 0.0, "residual_rms_N": 0.1, "rows": 10, **terms}
    return lambda r: r["hysteresis"].__setitem__("unloading_model", model)


def zero(**terms):
    law = {"rested_zero_uT": 3000.0, "drift_uT_per_min": 1.0, "offset_after_unloading_uT": -20.0}
    law.update({"recovery_uT_per_decade": 20.0, "span_uT": 500.0, "rests": 3, **terms})
    return lambda r: r.__setitem__("zero", law)


@pytest.mark.parametrize(
    "change, key",
    [
        (temperature(-0.01), "temperature.modulus_temp_coeff_per_K"),  # m(125 degC) = -0.05
        (temperature(1e300), "temperature.modulus_temp_coeff_per_K"),
        (temperature(50), "temperature.modulus_temp_coeff_per_K"),
        (temperature("1"), "temperature.modulus_temp_coeff_per_K"),
        (unloading(a=50), "hysteresis.unloading_model.a"),
        (unloading(a=-1e300), "hysteresis.unloading_model.a"),
        (unloading(a=0.9, b=3.0), "hysteresis.unloading_model.coefficients"),
        (unloading(rows="ten"), "hysteresis.unloading_model.rows"),
        (unloading(rows=1e20), "hysteresis.unloading_model.rows"),
        (unloading(coefficients=[0.0, "1"]), "hysteresis.unloading_model.coefficients"),
        (unloading(coefficients=[0.0] * 100), "hysteresis.unloading_model.coefficients"),
        (zero(span_uT="text"), "zero.span_uT"),
        (zero(drift_uT_per_min=1e300), "zero.drift_uT_per_min"),
        (zero(rests=2.5), "zero.rests"),
    ],
)
def test_fitted_values_out_of_their_physical_bounds_are_refused_naming_the_key(tmp_path, files, change, key):
    model = edited(files, tmp_path / "cal", change)
    n = len(files["F"])
    order = np.r_[np.arange(n), np.arange(n)[::-1]]  # loading then unloading
    B = files["B_uT"][order]
    readings = tmp_path / "r.csv"
    readings.write_text(csv_text("Bx_uT,By_uT,Bz_uT,T_C,time_s", *B.T, np.full(2 * n, 125.0), np.arange(2.0 * n)))
    track = ["--track-zero"] if key.startswith("zero.") else []  # the zero's law is read to track the zero
    refused(run(["read", model, readings, "--out", tmp_path / "o", *track]), f"calibration.json {key} =")
    assert not (tmp_path / "o").exists()


def test_the_bounds_keep_the_modulus_scale_positive_over_the_chips_range():
    """m(T) = 1 + beta (T - 20) at the bounds is 0.1 at the range's ends (MLX90393: -40..125 degC); an
    unloading reading means a force between none and the turn's, to within 5 % of it."""
    from mst_cli.calibration.record_bounds import BOUNDS, MIN_MODULUS_SCALE, unloading_loop

    b = BOUNDS["temperature.modulus_temp_coeff_per_K"]
    assert float(modulus_scale(125.0, b.lo)) == pytest.approx(MIN_MODULUS_SCALE, abs=1e-12)
    assert float(modulus_scale(-40.0, b.hi)) == pytest.approx(MIN_MODULUS_SCALE, abs=1e-12)
    # h = F_turn x (1 - x), mst 0.17's widest loop (a = 1, b = 0): an unloading reading means x^2 F_turn
    unloading_loop([0.0, 1.0, -1.0])
    unloading_loop([-0.04])  # a loop of -4 %: x + 0.04 <= 1.05
    unloading_loop([0.0], after_hold=0.06)  # x - 0.06 x^4 stays in [0, 1]
    # past the margin: at x = 0 (-0.06), at x = 1 (1.06, 1.06 with the hold), inside (3x^2 - 2x = -1/3 at x = 1/3)
    for coefficients, hold in (([0.06], 0.0), ([-0.06], 0.0), ([0.0], -0.06), ([0.0, 3.0, -3.0], 0.0)):
        with pytest.raises(InputError, match="between no force and the turn's"):
            unloading_loop(coefficients, after_hold=hold)


def test_brackets_nested_200000_deep_are_no_traceback(tmp_path, files):
    cal = tmp_path / "cal"
    shutil.copytree(files["cal"], cal)
    (cal / "calibration.json").write_text("[" * 200_000 + "]" * 200_000)
    r = run(["read", cal / "calibrated.yaml", files["dir"] / "readings.csv", "--out", tmp_path / "o"])
    assert r.exit_code == 0 and r.exception is None, (r.exit_code, r.exception)
    assert "no calibration.json beside it" in r.stderr


# ----------------------------------------------------------------- 4. no force a sensor cannot give is ok
@pytest.fixture(scope="module")
def readers(design, files):
    """The forward design's plain reader and its small shear and offset table readers."""
    doc, resp = design
    reader = ForceReader.open(doc, FORWARD, "spring")
    top = float(reader.inverse_map.force_N[-1])
    sigma = reader.inverse_map.field_resolution_T
    geometry = doc.geometry()
    shear = table_store.build_table(
        geometry, doc.material, "spring", table_store.grid_of("shear", doc, top, SMALL_SHEAR)
    )
    offset = table_store.build_table(
        geometry, doc.material, "spring", table_store.grid_of("offset", doc, top, SMALL_OFFSET)
    )
    return {
        "reader": reader,
        "none": None,
        "shear": ShearTableReader(shear, sigma),
        "offset": OffsetTableReader(offset, sigma, 1.0),
        "sigma_T": sigma,
    }


@pytest.fixture(scope="module")
def two_chip(readers):
    """The two-chip reader of the forward design, chips at (0, 0) and (10, 6) mm (its tables take
    a minute on a busy machine)."""
    doc, _ = load_design_document(FORWARD)
    stack = loaded_stack(doc.geometry(), doc.material, "spring")
    return TwoChipLoadReader(TwoChipReader(stack, [(0.0, 0.0), (10.0, 6.0)], readers["sigma_T"]))


@st.composite
def hostile_reads(draw, resp):
    """Readings (fields along the model's curve and beyond it, any temperature of the chip's
    range, in time order) and a calibration record with any temperature law and unloading model."""
    n = draw(st.integers(6, 24))
    top = float(resp.max_force_N)
    F = np.array(draw(st.lists(st.floats(-0.2 * top, 1.5 * top), min_size=n, max_size=n)))
    B = np.stack([np.interp(F, resp.force_N, resp.B_T[:, i], right=np.nan) for i in range(3)], -1) * 1e6
    wild = np.array(draw(st.lists(st.floats(-49_000, 49_000), min_size=3 * n, max_size=3 * n))).reshape(n, 3)
    B = np.where(np.isfinite(B), B, wild)
    T = np.array(draw(st.lists(st.floats(-40, 125), min_size=n, max_size=n)))
    number = st.floats(allow_nan=False, allow_infinity=False, min_value=-1e300, max_value=1e300)
    small = st.floats(-0.02, 0.02)
    beta = draw(st.one_of(small, number, st.just(-0.01)))
    a, b = draw(st.one_of(small, st.floats(-1.5, 1.5), number)), draw(st.one_of(st.floats(-8, 8), number))
    record = CalibrationRecord.from_json(
        {
            "temperature": {"modulus_temp_coeff_per_K": beta},
            "hysteresis": {"unloading_model": {"a": a, "b": b, "residual_rms_N": 0.05, "rows": 10}},
        }
    )
    return B, T, beta, record


def readings_text(B: np.ndarray, T: np.ndarray, chips: int) -> str:
    cols = [*B.T] + ([*(B * [1.02, 0.97, 1.01]).T] if chips == 2 else [])
    header = "Bx_uT,By_uT,Bz_uT" + (",Bx2_uT,By2_uT,Bz2_uT" if chips == 2 else "") + ",T_C,time_s"
    return csv_text(header, *cols, T, np.arange(len(T), dtype=float))


NON_FINITE = re.compile(r"(^|,)[+-]?(nan|inf|infinity)(,|$)", re.IGNORECASE | re.MULTILINE)


@pytest.mark.parametrize("estimate", ["none", "shear", "offset", pytest.param("two-chip", marks=pytest.mark.slow)])
@settings(max_examples=25, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(data=st.data())
def test_property_no_ok_force_outside_what_the_sensor_can_give(readers, design, estimate, data, request):
    _, resp = design
    B, T, beta, record = data.draw(hostile_reads(resp))
    reader = readers["reader"]
    reader.record = record
    rd = parse_readings(readings_text(B, T, 2 if estimate == "two-chip" else 1), "r.csv", need_force=False)
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("error")
            got = reader.read(rd, request.getfixturevalue("two_chip") if estimate == "two-chip" else readers[estimate])
    except InputError as exc:  # refused: a bound of the calibration, named in one line
        assert str(exc.field).startswith("calibration.json ") and "\n" not in str(exc)
        return
    top = float(reader.inverse_map.force_N[-1]) * np.maximum(modulus_scale(T, beta), 1.0) * (1 + 1e-9)
    ok = got.flag == "ok"
    F = got.force_N[ok]
    assert np.all(np.isfinite(F)) and np.all(F >= 0) and np.all(F <= top[ok]), (F, top[ok])
    if got.offset is not None:
        est_ok = got.offset.flag == "ok"
        Fe = got.offset.force_N[est_ok]
        assert np.all(np.isfinite(Fe)) and np.all(Fe >= 0) and np.all(Fe <= top[est_ok])
    assert not NON_FINITE.search(got.csv())


# ----------------------------------------------------------------- 5. columns and counts
def test_a_chip_column_is_matched_as_written(tmp_path, files):
    B = files["B_uT"]
    path = tmp_path / "r.csv"
    path.write_text(csv_text("Bx_uT,By_uT,Bz_uT,Bx02_uT,By02_uT,Bz02_uT", *B.T, *B.T))
    line = refused(
        run(["read", files["cal"] / "calibrated.yaml", path, "--out", tmp_path / "o"]), "r.csv column 'Bx02_uT'"
    )
    assert "Bx2_uT" in line


def test_a_cycle_of_1e20_is_refused(tmp_path, files):
    path = tmp_path / "lt.csv"
    F, B = files["F"], files["B_uT"]
    path.write_text(csv_text("force_N,Bx_uT,By_uT,Bz_uT,cycle", F, *B.T, np.full(len(F), 1e20)))
    refused(run(["calibrate", FORWARD, path, "--out", tmp_path / "o"]), "lt.csv line 2 cycle")


def test_time_steps_of_a_subnormal_size_are_refused(tmp_path, files):
    n = len(files["F"])
    order = np.r_[np.arange(n), np.arange(n)[::-1]]
    F, B = files["F"][order], files["B_uT"][order]
    path = tmp_path / "lt.csv"
    times = [repr(i * 5e-324) for i in range(2 * n)]
    path.write_text(csv_text("force_N,Bx_uT,By_uT,Bz_uT,time_s", F, *B.T, times))
    refused(run(["calibrate", FORWARD, path, "--out", tmp_path / "o"]), "lt.csv line 3 time_s")


@pytest.mark.parametrize("option", ["--shear-ratio", "--load-offset-mm"])
def test_an_empty_pair_option_is_refused(tmp_path, option):
    refused(run(["simulate", FORWARD, option, "", "--out", tmp_path / "o"]), option)


def test_an_input_column_named_like_an_output_column_is_written_once(tmp_path, files):
    B = files["B_uT"]
    n = len(B)
    path = tmp_path / "r.csv"
    path.write_text(csv_text("Bx_uT,By_uT,Bz_uT,shear_x_N,flag", *B.T, np.ones(n), ["mine"] * n))
    r = run(["read", files["cal"] / "calibrated.yaml", path, "--out", tmp_path / "o"])
    assert r.exit_code == 0, r.stderr
    header = (tmp_path / "o" / "forces.csv").read_text().splitlines()[0].split(",")
    assert len(header) == len(set(header)), header
    assert "shear_x_N_reference" in header and "flag_reference" in header and "flag" in header


# ----------------------------------------------------------------- 6. force units
@pytest.mark.parametrize(
    "unit, newtons", [("kgf", 9.80665), ("lbf", 4.4482216152605), ("g", 0.00980665), ("mN", 0.001)]
)
def test_a_load_test_in_a_known_other_force_unit_is_named(tmp_path, files, unit, newtons):
    path = tmp_path / "lt.csv"
    path.write_text(csv_text("force_N,Bx_uT,By_uT,Bz_uT", files["F"] / newtons, *files["B_uT"].T))
    line = refused(run(["calibrate", FORWARD, path, "--out", tmp_path / "o"]), "lt.csv force_N")
    assert f"look like {unit} " in line and f"x {newtons:g}" in line, line


# ----------------------------------------------------------------- 7. small messages
def test_a_hold_at_no_load_prints_no_nan(tmp_path, design):
    _, resp = design
    top = 0.8 * resp.max_force_N
    up = np.linspace(0.0, top, 16)
    F = np.r_[up, np.full(6, top), up[::-1], np.zeros(8), up, up[::-1]]  # a hold at 0 N between two cycles
    B = field_rows_uT(resp, F, np.random.default_rng(2))
    path = tmp_path / "lt.csv"
    path.write_text(csv_text("force_N,Bx_uT,By_uT,Bz_uT,time_s", F, *B.T, np.arange(len(F), dtype=float)))
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        r = run(["calibrate", FORWARD, path, "--out", tmp_path / "o"])
    assert r.exit_code == 0, (r.stderr, r.exception)
    assert "creep under the hold" in r.output, r.output  # the loaded hold still measured
    assert not re.search(r"\b(nan|inf)\b", r.output + r.stderr, re.IGNORECASE), r.output
    text = (tmp_path / "o" / "calibration.json").read_text()
    assert not re.search(r"\b(NaN|Infinity)\b", text)
