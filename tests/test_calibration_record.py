"""The calibration's parts without the command line: the fit's iteration count and force-error
statistics, the C header against the inverse map it tabulates (issue 23)."""

from __future__ import annotations

import json
import re
import shutil
import subprocess

import numpy as np
import pytest
from test_calibrate import DESIGN, TRUTH, PrintedSensor

from mst_cli import api as mst
from mst_cli.calibration import fit as cal
from mst_cli.calibration.accuracy import force_errors
from mst_cli.calibration.calibration_json import CalibrationRecord, record_beside
from mst_cli.calibration.loadtest import setting_of as loadtest_setting_of
from mst_cli.calibration.tables import cell, quoted
from mst_cli.estimation.inverse_map import inverse_map
from mst_cli.firmware.header import c_header
from mst_cli.sensor.as_printed import PARAMETERS
from mst_cli.sensor.document import load_document


@pytest.fixture(scope="module")
def load_test():
    """40 noisy readings of the printed sensor of test_calibrate (known print errors)."""
    s = PrintedSensor()
    rng = np.random.default_rng(5)
    F = np.sort(rng.uniform(0.0, s.range_N, 40))
    codes = s.codes(F, rng)
    lsb = np.array([s.setting.xy_uT_per_lsb, s.setting.xy_uT_per_lsb, s.setting.z_uT_per_lsb]) * 1e-6
    return load_document(DESIGN), F, np.linalg.norm(codes * lsb, axis=1)


@pytest.mark.parametrize("mechanics", ["spring", "frame"])
def test_the_fit_counts_its_space_mapping_iterations(load_test, mechanics):
    doc, F, B = load_test
    fit = cal.fit_parameters(doc, F, B, 2e-6, tuple(PARAMETERS), mechanics)
    if mechanics == "spring":  # the fitted rung itself: one solve, no mapping
        assert fit.iterations == 1
        return
    # the dear rung is corrected at the start's wall offset and modulus factor (the insert does
    # not scale with the TPU); the fit moves them, so at least one more solve follows, and the
    # loop stops once the correction sits at the fitted values
    assert 2 <= fit.iterations <= cal.MAX_SPACE_MAPPING_ITERATIONS
    if fit.iterations < cal.MAX_SPACE_MAPPING_ITERATIONS:
        assert abs(fit.model.correction.wall_offset_mm - fit.values["wall_offset_mm"]) < 1e-4
        assert abs(fit.model.correction.modulus_factor - fit.values["modulus_factor"]) < 1e-5


def test_force_errors_by_hand():
    # range 10 N: readings from 1 N count; 0.5 N is left out, the NaN (flagged) is counted apart
    F_true = np.array([0.5, 2.0, 4.0, 10.0])
    F_model = np.array([0.6, 2.2, np.nan, 9.0])
    err = force_errors(F_model, F_true, 10.0)
    assert err["readings"] == 3 and err["flagged"] == 1 and err["from_force_N"] == pytest.approx(1.0)
    assert err["median_rel"] == pytest.approx(0.1) and err["max_rel"] == pytest.approx(0.1)
    assert err["rms_N"] == pytest.approx(np.sqrt((0.2**2 + 1.0**2) / 2))
    assert force_errors([np.nan], [5.0], 10.0) == {"readings": 1, "flagged": 1}


def test_csv_cells_quote_as_rfc_4180():
    assert quoted('a "b", c') == '"a ""b"", c"' and quoted("12.5") == "12.5"
    assert cell(float("nan")) == "" and cell(None) == "" and cell(0.25, ".6g") == "0.25"


@pytest.fixture(scope="module")
def calibrated_map():
    """The design's inverse map at GAIN_SEL 7, RES 0, calibrated to 30 N."""
    imap, _ = inverse_map(load_document(DESIGN))
    imap.calibrated_to_N = 30.0
    return imap, loadtest_setting_of(7, 0)


def _arrays(text):
    return {
        name: [float(v.strip().rstrip("f")) for v in body.split(",")]
        for name, body in re.findall(r"(mst_\w+)\[MST_TABLE_LEN\] = \{(.*?)\};", text, re.S)
    }


def test_c_header_tabulates_the_inverse_map(calibrated_map, tmp_path):
    imap, setting = calibrated_map
    text = c_header(imap, setting, "unit", "a test", ["one limitation"])
    codes, F, regime, res = imap.z_code_table(setting)
    arrays = _arrays(text)
    assert arrays["mst_z_code"] == [float(c) for c in codes]
    assert arrays["mst_force_mN"] == [float(round(f * 1e3)) for f in F]
    assert arrays["mst_regime"] == [float(r) for r in regime]
    assert np.allclose(arrays["mst_resolution_mN"], res * 1e3, rtol=1e-3)
    assert f"#define MST_TABLE_LEN {len(codes)}\n" in text and "#define MST_N_REGIMES 3\n" in text
    # the code of the calibrated force: |Bz| there, in LSB
    lsb = setting.z_uT_per_lsb * 1e-6
    top = int(np.floor(abs(np.interp(30.0, imap.force_N, imap.Bz_T)) / lsb))
    assert f"#define MST_Z_CALIBRATED_LSB {top}\n" in text and " *   - one limitation\n" in text

    gcc = shutil.which("gcc")
    if gcc is None:
        pytest.skip("gcc not installed: the header is not compiled")
    (tmp_path / "force_table.h").write_text(text)
    subprocess.run(
        [gcc, "-fsyntax-only", "-std=c99", "-Wall", "-Wextra", "-Werror", "-x", "c", str(tmp_path / "force_table.h")],
        check=True,
        capture_output=True,
    )
    # halfway between two entries the C lookup interpolates linearly, in integer mN
    (tmp_path / "main.c").write_text(
        '#include <stdio.h>\n#include <stdlib.h>\n#define MST_FORCE_IMPLEMENTATION\n#include "force_table.h"\n'
        "int main(int argc, char **argv) { int32_t f = -1; uint8_t r = 0;\n"
        '  int flag = mst_force_from_z((int32_t)atol(argv[1]), &f, &r); printf("%d %ld %d\\n", flag, (long)f, r);\n'
        "  return 0; }\n"
    )
    exe = tmp_path / "lookup"
    subprocess.run(
        [gcc, "-std=c99", "-I", str(tmp_path), str(tmp_path / "main.c"), "-o", str(exe)],
        check=True,
        capture_output=True,
    )
    i = len(codes) // 3
    mid = int((codes[i] + codes[i + 1]) // 2)
    flag, force, reg = map(
        int, subprocess.run([str(exe), str(mid)], check=True, capture_output=True, text=True).stdout.split()
    )
    f0, f1 = round(F[i] * 1e3), round(F[i + 1] * 1e3)
    assert flag == 0 and reg == regime[i]
    assert force == f0 + (f1 - f0) * (mid - codes[i]) // (codes[i + 1] - codes[i])


def test_force_table_h_is_defined_once_in_a_program_of_two_files(calibrated_map, tmp_path):
    # one file defines MST_FORCE_IMPLEMENTATION (the tables and the function), another includes
    # the header plainly and reads a table and the function: the program links, the tables are in
    # the first object only, and the lookup gives the Python table's entry at a node
    imap, setting = calibrated_map
    gcc = shutil.which("gcc")
    if gcc is None:
        pytest.skip("gcc not installed: the header is not compiled")
    (tmp_path / "force_table.h").write_text(c_header(imap, setting, "unit", "a test", ["one limitation"]))
    (tmp_path / "one.c").write_text('#define MST_FORCE_IMPLEMENTATION\n#include "force_table.h"\n')
    (tmp_path / "two.c").write_text(
        '#include <stdio.h>\n#include <stdlib.h>\n#include "force_table.h"\n'
        "int main(int argc, char **argv)\n{\n    int32_t f = -1;\n    uint8_t r = 0;\n    (void)argc;\n"
        "    int flag = mst_force_from_z(mst_z_code[atoi(argv[1])], &f, &r);\n"
        '    printf("%d %ld %d\\n", flag, (long)f, r);\n    return 0;\n}\n'
    )
    strict = ["-Wall", "-Wextra", "-Wpedantic", "-Wshadow", "-Wconversion", "-Wdouble-promotion", "-Werror"]
    objs = []
    for name in ("one", "two"):
        obj = tmp_path / f"{name}.o"
        subprocess.run([gcc, "-std=c99", "-O2", *strict, "-c", tmp_path / f"{name}.c", "-o", obj], check=True)
        objs.append(obj)
    nm = shutil.which("nm")
    if nm is not None:
        symbols = [subprocess.run([nm, o], capture_output=True, text=True).stdout for o in objs]
        for table in ("mst_z_code", "mst_force_mN", "mst_regime", "mst_resolution_mN", "mst_force_from_z"):
            assert f" R {table}" in symbols[0] or f" T {table}" in symbols[0]  # defined in one.o ...
            assert f" U {table}" in symbols[1] or table not in symbols[1]  # ... only referenced in two.o
    exe = tmp_path / "two"
    subprocess.run([gcc, *objs, "-o", exe], check=True)
    codes, F, regime, _ = imap.z_code_table(setting)
    i = len(codes) // 2
    flag, force, reg = map(
        int, subprocess.run([exe, str(i)], check=True, capture_output=True, text=True).stdout.split()
    )
    assert (flag, force, reg) == (0, round(F[i] * 1e3), regime[i])  # an entry's own force, exactly


@pytest.fixture(scope="module")
def calibration(tmp_path_factory):
    """mst_cli.calibrate (the api) on a load test of the printed sensor of test_calibrate."""
    d = tmp_path_factory.mktemp("api")
    s = PrintedSensor()
    (d / "loadtest.csv").write_text(s.csv_uT(*s.load_test()))  # docs/examples/loadtest.csv
    return mst.calibrate(DESIGN, d / "loadtest.csv", out=d / "out"), d / "out"


def test_the_api_calibration_finds_the_print_errors(calibration):
    result, _ = calibration
    for name in result.fit.names:  # the identifiable ones, within 3 sigma of the truth
        assert abs(result.fit.values[name] - TRUTH[name]) < 3 * result.fit.std[name] + 1e-3, name


def test_the_record_round_trips_and_guards_its_model(calibration, tmp_path):
    result, out = calibration
    written = json.loads((out / "calibration.json").read_text())
    assert CalibrationRecord.from_json(written).to_json() == written == result.record.to_json()
    note, record = record_beside(out / "calibrated.yaml")
    assert note is None and record.calibrated_top_N() == pytest.approx(result.load_test.force_N.max())
    # the same model file edited: the record belongs to another file
    shutil.copy(out / "calibration.json", tmp_path / "calibration.json")
    (tmp_path / "calibrated.yaml").write_text((out / "calibrated.yaml").read_text() + "# edited\n")
    note, record = record_beside(tmp_path / "calibrated.yaml")
    assert record is None and "belongs to another file" in note


def test_the_next_design_takes_the_calibrated_printer(calibration):
    result, out = calibration
    spec = DESIGN.parent / "mohammadi2021.yaml"
    designed = mst.design(spec, seed=0, calibration=out / "calibration.json")
    assert designed.document.printer.wall_offset_mm == pytest.approx(result.fit.values["wall_offset_mm"])
    assert designed.status == "met"
