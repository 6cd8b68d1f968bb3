"""mst read --serial: the streams real sketches print, fed byte-exact through a pseudo-terminal,
and one pipeline for files and streams (the same readings give the same forces.csv)."""

from __future__ import annotations

import json
import os
import threading
from pathlib import Path

import numpy as np
import pytest
from click.testing import CliRunner
from serial_support import PtyFeed, read_fed_lines

from mst_cli import api
from mst_cli.calibration.calibration_json import sha256_text
from mst_cli.calibration.temperature_fit import remanence_coeff_of
from mst_cli.cli.app import main
from mst_cli.errors import InputError
from mst_cli.estimation.inverse_map import inverse_map
from mst_cli.estimation.inverse_table import SHEAR_TABLE_FILE, TABLE_FILE
from mst_cli.estimation.table_store import build_beside
from mst_cli.io.line_columns import column_map
from mst_cli.model.temperature import modulus_scale, remanence_scale
from mst_cli.sensor.as_printed import CALIBRATION_JSON
from mst_cli.sensor.document import load_design_document

ROOT = Path(__file__).resolve().parents[1]
FORWARD = ROOT / "configs" / "mohammadi2021-forward.yaml"
BETA_PER_K = -0.004  # the test calibration's modulus coefficient (TPU softens when warm)


def calibrated_copy(d: Path, text: str | None = None) -> Path:
    """The forward design in ``d`` with a calibration.json beside it that holds an unloading
    model and a temperature law (what a rig's calibration writes)."""
    model = d / "model.yaml"
    text = text if text is not None else FORWARD.read_text()
    model.write_text(text)
    record = {
        "calibrated_yaml_sha256": sha256_text(text),
        "hysteresis": {"unloading_model": {"a": 0.25, "b": 0.1, "residual_rms_N": 0.05, "rows": 60}},
        "temperature": {"modulus_temp_coeff_per_K": BETA_PER_K},
    }
    (d / CALIBRATION_JSON).write_text(json.dumps(record))
    return model


@pytest.fixture(scope="module")
def forward(tmp_path_factory):
    """(the calibrated copy of the forward design, its inverse map)."""
    doc, _ = load_design_document(FORWARD)
    imap, _ = inverse_map(doc, "spring")
    return calibrated_copy(tmp_path_factory.mktemp("forward")), imap


@pytest.fixture(scope="module")
def forward_tables(forward):
    """``forward`` with coarse offset and shear tables beside it (current: built after the
    calibration.json their hash reads)."""
    model, imap = forward
    doc, _ = load_design_document(model)
    top = float(imap.force_N[-1])
    build_beside(model, doc, "spring", 1.0, top, (17, 3.0)).save(model.parent / TABLE_FILE)
    build_beside(model, doc, "spring", 1.0, top, (17, 0.1), kind="shear").save(model.parent / SHEAR_TABLE_FILE)
    return model, imap


# --------------------------------------------------------------------------- the sketches' streams
def _chips(values, order):
    """One line's numbers of five chips (x, y, z, t each) in ``order`` (xyzt or txyz)."""
    out = []
    for x, y, z, t in values:
        out += [t, x, y, z] if order == "txyz" else [x, y, z, t]
    return out


XYZT = [(-0.45, 1.50, 3072.19, 24.50), (0.12, -0.80, 3104.33, 24.62), (1.05, 0.33, 3350.70, 24.75)]
FIVE = [[(x + k, y - k, z + 10 * k, t) for k in range(5)] for x, y, z, t in XYZT]  # chip 1 first


def _sketch_lines(sketch: str) -> tuple[list[str], str | None]:
    """The lines a sketch prints for XYZT (its print statements, in its format), and --columns."""
    if sketch == "adafruit_basicdemo":  # readData one axis a line, then the unified event
        lines = ["Starting Adafruit MLX90393 Demo", "Found a MLX90393 sensor", "Gain set to: 2.5 x"]
        for x, y, z, _ in XYZT:
            lines += [f"X: {x:.4f} uT", f"Y: {y:.4f} uT", f"Z: {z:.4f} uT"]
        return lines, None
    if sketch == "adafruit_event":
        return [f"X: {x:.2f} \tY: {y:.2f} \tZ: {z:.2f} uTesla " for x, y, z, _ in XYZT], None
    if sketch == "circuitpython":
        return [f"X: {x} uT, Y: {y} uT, Z: {z} uT" for x, y, z, _ in XYZT], None
    if sketch == "plotter":
        return [f"X:{x:.2f},Y:{y:.2f},Z:{z:.2f}" for x, y, z, _ in XYZT], None
    if sketch == "sparkfun":
        return ["MLX90393 Read Example"] + [
            f"magX[{x:.2f}] magY[{y:.2f}] magZ[{z:.2f}] temperature(C)[{t:.2f}]" for x, y, z, t in XYZT
        ], None
    if sketch == "library_spaces":
        return [f"{x:.2f} {y:.2f} {z:.2f} {t:.2f}" for x, y, z, t in XYZT], None
    if sketch == "csv_header":
        return ["MLX90393 logger", "X,Y,Z,T"] + [f"{x:.2f},{y:.2f},{z:.2f},{t:.2f}" for x, y, z, t in XYZT], None
    if sketch == "reskin_one":
        return ["\t".join(f"{v:.2f}" for v in (x, y, z, t)) + "\t" for x, y, z, t in XYZT], None
    if sketch == "anyskin_one":
        return ["\t".join(f"{v:.2f}" for v in (t, x, y, z)) for x, y, z, t in XYZT], "anyskin"
    if sketch == "reskin_five":
        return ["\t".join(f"{v:.2f}" for v in _chips(c, "xyzt")) + "\t" for c in FIVE], "reskin"
    assert sketch == "anyskin_five"
    return ["\t".join(f"{v:.2f}" for v in _chips(c, "txyz")) for c in FIVE], "anyskin"


SKETCHES = [
    "adafruit_basicdemo",
    "adafruit_event",
    "circuitpython",
    "plotter",
    "sparkfun",
    "library_spaces",
    "csv_header",
    "reskin_one",
    "anyskin_one",
    "reskin_five",
    "anyskin_five",
]
WITH_T = {"sparkfun", "library_spaces", "csv_header", "reskin_one", "anyskin_one", "reskin_five", "anyskin_five"}


@pytest.mark.parametrize("ending", ["\n", "\r\n", "\r"])
@pytest.mark.parametrize("sketch", SKETCHES)
def test_every_sample_of_the_sketches_streams_is_read(forward, sketch, ending):
    model, _ = forward
    lines, columns = _sketch_lines(sketch)
    got, shown = read_fed_lines(
        model, [(line + ending).encode() for line in lines], count=len(XYZT), columns=columns, timeout_s=5.0
    )
    assert len(got.samples) == len(XYZT) and len(shown) == len(XYZT), (got.line(), shown)
    values = [tuple(float(c) for c in cells[:3]) for cells in got.samples]
    assert values == [(x, y, z) for x, y, z, _ in XYZT]
    if sketch in WITH_T:
        assert got.record.header()[-1] == "T_C" and [float(c[3]) for c in got.samples] == [t for *_, t in XYZT]
    assert got.bad == 0


def test_a_stream_without_a_sample_exits_2_saying_so_while_running(forward, tmp_path):
    model, _ = forward
    notes: list[str] = []
    lines = [b"MLX90393 demo\r\n"] + [b"reading failed, retrying\r\n"] * 8
    with pytest.raises(InputError, match="gave no sample"):
        read_fed_lines(model, lines, timeout_s=0.5, warn=notes.append, out=tmp_path / "o")
    assert any("lines are no sample so far" in n and "'MLX90393 demo'" in n for n in notes), notes
    assert not (tmp_path / "o").exists()


def test_bad_numbers_are_skipped_and_counted_and_what_was_read_is_written(forward, tmp_path):
    """1e999, nan, a raw code past the chip's range: bad lines, never the end; a partial last line."""
    model, _ = forward
    good = [b"0.5,0.2,3100.0\n", b"0.6,0.1,3150.0\n", b"0.7,0.0,3200.0\n"]
    lines = [good[0], b"1e999,0,3100\n", b"nan,0,3100\n", good[1], b"0.1,0.2,3100,500\n", good[2], b"0.1,0.2,31"]
    got, _ = read_fed_lines(model, lines, timeout_s=0.5, out=tmp_path / "o")
    assert len(got.samples) == 3 and got.bad == 4, got.line()  # the cut-off last line is bad too
    text = (tmp_path / "o" / "forces.csv").read_text()
    assert len(text.splitlines()) == 4 and "inf" not in text and "nan" not in text
    # raw codes: 1e999 and a code past RES 0's range are bad lines, the rest read (no traceback)
    raw = [b"10 20 3000\n", b"1e999 20 3000\n", b"10 20 99999\n", b"10 20 3100\n"]
    got, _ = read_fed_lines(model, raw, count=2, raw=True, gain_sel=0, res=0, timeout_s=5.0)
    assert len(got.samples) == 2 and got.bad == 2, got.line()


def test_a_sketch_that_prints_only_when_asked_is_driven_by_send(forward):
    """T. Yapo's read_MLX90393 example: one sample per byte the host writes."""
    model, _ = forward
    feed = PtyFeed([])
    asked = threading.Event()

    def sketch():
        for x, y, z, t in XYZT:
            try:
                if not os.read(feed.master, 1):
                    return
            except OSError:
                return
            asked.set()
            os.write(feed.master, f"{x:.2f} {y:.2f} {z:.2f} {t:.2f}\r\n".encode())

    board = threading.Thread(target=sketch, daemon=True)
    board.start()
    try:
        got = api.read_serial(model, feed.port, count=len(XYZT), send="r", timeout_s=5.0, show=lambda _: None)
    finally:
        board.join(timeout=5)
        feed.close()
    assert asked.is_set() and len(got.samples) == len(XYZT)


@pytest.mark.parametrize(
    "spec, says",
    [("xyzq", "a preset"), ("x,y", "x, y and z"), ("x1,y1,z1,x", "number every role"), ("x,x,y,z", "once")],
)
def test_a_bad_columns_map_is_refused_naming_the_option(spec, says):
    with pytest.raises(InputError, match=says) as exc:
        column_map(spec)
    assert exc.value.field == "--columns"


def _cli(args):
    return CliRunner().invoke(main, [str(a) for a in args])


@pytest.mark.parametrize("port", ["DIR", "MISSING", ""])
def test_a_port_that_does_not_open_is_one_line_naming_it(forward, tmp_path, port):
    model, _ = forward
    path = {"DIR": tmp_path, "MISSING": tmp_path / "ttyNONE", "": ""}[port]
    r = _cli(["read", model, "--serial", path])
    assert r.exit_code == 2 and r.output.count("\n") == 1, r.output
    assert "reading" not in r.output and "(unknown path)" not in r.output
    assert (str(path) in r.output) if port else ("--serial" in r.output)


def test_a_timeout_that_never_fires_is_refused(forward):
    model, _ = forward
    r = _cli(["read", model, "--serial", "/dev/null", "--timeout", "nan"])
    assert r.exit_code == 2 and "--timeout" in r.output and r.output.count("\n") == 1, r.output


# --------------------------------------------------------------------------- one pipeline
def _recording(imap, rng, T_C=30.0):
    """A rig's stream at T_C: 10 readings at rest (the tare), one 8 uT below the unloaded field,
    a load to 70 % of the range, a hold, the unloading; as the lines a sketch prints (x,y,z,t)."""
    top = float(imap.force_N[-1])
    F = np.concatenate(
        [np.zeros(10), np.linspace(0, 0.7 * top, 40), np.full(8, 0.7 * top), np.linspace(0.7 * top, 0, 40)]
    )
    doc_alpha = remanence_coeff_of(load_design_document(FORWARD)[0])
    r, m = remanence_scale(T_C, doc_alpha), modulus_scale(T_C, BETA_PER_K)
    B = r * np.interp(F / m, imap.force_N, imap.B_abs_T) * 1e6 + rng.normal(0, 0.5, len(F))
    B[10] = imap.B_abs_T[0] * 1e6 * r - 8.0
    xy = rng.normal(0, 0.5, (len(F), 2))
    return [f"{x:.3f},{y:.3f},{b:.3f},{T_C:.2f}" for (x, y), b in zip(xy, B)]


@pytest.mark.parametrize("estimate", ["none", "offset", "shear"])
def test_one_recording_gives_the_same_forces_from_a_file_and_from_a_stream(forward_tables, tmp_path, estimate):
    model, imap = forward_tables
    lines = _recording(imap, np.random.default_rng(7))
    csv = tmp_path / "r.csv"
    csv.write_text("Bx_uT,By_uT,Bz_uT,T_C\n" + "\n".join(lines) + "\n")
    # the coarse 3 mm offset table states its own interpolation error in its 1-sigma: identify the
    # press within 5 mm, so rows are estimated (the file and the stream take the same bound)
    bound = {"max_offset_sigma_mm": 5.0} if estimate == "offset" else {}
    from_file = api.read(model, csv, estimate=estimate, tare=10, out=tmp_path / "file", **bound)
    got, shown = read_fed_lines(
        model,
        [(line + "\r\n").encode() for line in lines],
        count=len(lines),
        estimate=estimate,
        tare=10,
        out=tmp_path / "stream",
        timeout_s=5.0,
        **bound,
    )
    file_text = (tmp_path / "file" / "forces.csv").read_text()
    stream_text = (tmp_path / "stream" / "forces.csv").read_text()
    assert stream_text.splitlines()[0].startswith("time_s,")
    assert "\n".join(line.split(",", 1)[1] for line in stream_text.splitlines()) + "\n" == file_text
    assert len(shown) == len(lines)  # every sample shown live (the tare's once they are all in)
    head = file_text.splitlines()[0].split(",")
    assert "branch" in head and "force_uncertainty_N" in head  # branch following with every estimate
    row = dict(zip(head, file_text.splitlines()[1 + 10].split(",")))
    assert (row["flag"], float(row["force_N"])) == ("ok", 0.0)  # 8 uT below no load: no load
    assert "unloading" in set(from_file.branches.branch)
    if estimate != "none":
        flags = [
            dict(zip(head, line.split(","))).get("offset_flag" if estimate == "offset" else "estimate_flag")
            for line in file_text.splitlines()[1:]
        ]
        assert flags.count("ok") >= 10, flags  # estimated rows, not only flagged ones


# --------------------------------------------------------------------------- two chips, warm and live
# inside the part's range (its locks 10.0, 29.0 and 30.6 N at 20 degC) at every temperature: at
# 40 degC the stack feels F / m = F / 0.92, so 28 N presses it as 30.4 N does at 20 degC (its last regime)
WARM_LOADS = [(12.0, 2.0, -1.0, 3.0, -2.0), (26.0, -4.0, 3.0, -5.0, 2.5), (28.0, 6.0, 5.0, 1.0, 1.0)]


@pytest.fixture(scope="module")
def two_chips(tmp_path_factory):
    """(the calibrated two-chip copy, its reader, the two-chip estimator built once, the stack)."""
    from mst_cli.estimation.table_reader import two_chip_reader
    from mst_cli.model.general_load import loaded_stack
    from mst_cli.readout.reading import ForceReader

    text = FORWARD.read_text().replace(
        "  noise_uT_rms: 2.0\n", "  noise_uT_rms: 2.0\n  positions_mm: [[0, 0], [10, 6]]\n"
    )
    model = calibrated_copy(tmp_path_factory.mktemp("two"), text)
    doc, geo = load_design_document(model)
    reader = ForceReader.open(doc, model, "spring")
    offsets = two_chip_reader(doc, reader.inverse_map, 1.0, "spring", False)
    return model, reader, offsets, loaded_stack(geo, doc.material, "spring")


def _warm_lines(two_chips, loads=WARM_LOADS, temperatures_C=(25.0, 30.0, 40.0)):
    """Each load of ``loads`` at each of ``temperatures_C``, as six fields and T_C: B = r(T) B_20(L / m(T)).
    The fields are the loading branch's, so the stream only loads (the loads ascending, each at
    the three temperatures): a fall from 28 N to 12 N is an unloading the reader follows with the
    calibration's unloading model (rig_reading.follow_branches), which these fields do not hold."""
    from mst_cli.model.general_load import field_T

    model, reader, _, stack = two_chips
    alpha = remanence_coeff_of(reader.document)
    lines, truth = [], []
    for F, fx, fy, x, y in loads:
        for T in temperatures_C:
            r, m = float(remanence_scale(T, alpha)), float(modulus_scale(T, BETA_PER_K))
            B = r * 1e6 * field_T(stack, F / m, (fx / m, fy / m), (x, y), reader.document.chips_mm).ravel()
            lines.append(",".join(f"{b:.4f}" for b in B) + f",{T:.1f}")
            truth.append((F, fx, fy, x, y))
    return lines, np.array(truth)


@pytest.mark.slow
def test_warm_two_chip_readings_are_ok_within_their_sigma_from_a_file_and_live(two_chips, tmp_path):
    from mst_cli.calibration.loadtest import parse_readings
    from mst_cli.readout.live import LiveOptions, read_stream

    model, reader, offsets, _ = two_chips
    lines, truth = _warm_lines(two_chips)
    header = "Bx_uT,By_uT,Bz_uT,Bx2_uT,By2_uT,Bz2_uT,T_C"
    rd = parse_readings(header + "\n" + "\n".join(lines) + "\n", "warm.csv", need_force=False)
    got = reader.read(rd, offsets)
    est = got.offset
    assert list(est.flag) == ["ok"] * len(lines), list(est.flag)
    values = np.column_stack([got.force_N, est.shear_x_N, est.shear_y_N, est.x_mm, est.y_mm])
    assert np.all(np.abs(values - truth) <= est.sigma), (values - truth) / est.sigma  # within the stated 1-sigma
    # live: the same lines through a pseudo-terminal give the same forces.csv, time_s aside
    feed = PtyFeed([(line + "\n").encode() for line in lines])
    try:
        live = read_stream(
            reader, feed.port, LiveOptions(count=len(lines), timeout_s=5.0), None, lambda _: None, offsets
        )
    finally:
        feed.close()
    assert "\n".join(line.split(",", 1)[1] for line in live.csv().splitlines()) + "\n" == got.csv()


@pytest.mark.slow
def test_a_warm_press_past_the_last_lock_at_its_temperature_is_not_ok(two_chips):
    """The last lock's force scales with the modulus: at 40 degC (m = 0.92) the part's last lock,
    30.6 N at 20 degC, comes at 28.2 N. A 30 N press is inside the range at 20 degC and past it at
    40 degC (the stack feels it as 32.6 N would at 20 degC), so only the cold one is ok."""
    from mst_cli.calibration.loadtest import parse_readings

    _, reader, offsets, _ = two_chips
    load = [(30.0, 2.0, -1.0, 1.0, 1.0)]
    assert float(reader.inverse_map.force_N[-1]) == pytest.approx(30.6, abs=0.05)  # the lock the docstring counts on
    lines, _ = _warm_lines(two_chips, load, (20.0, 40.0))
    header = "Bx_uT,By_uT,Bz_uT,Bx2_uT,By2_uT,Bz2_uT,T_C"
    got = reader.read(parse_readings(header + "\n" + "\n".join(lines) + "\n", "warm.csv", need_force=False), offsets)
    assert got.offset.flag[0] == "ok" and got.force_N[0] == pytest.approx(30.0, abs=3 * got.offset.sigma[0, 0])
    assert got.offset.flag[1] != "ok" and not (got.flag[1] == "ok" and got.force_N[1] > 30.6 * 0.92)
