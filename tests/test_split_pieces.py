"""The pieces issue 23's splits of cad/, calibrate/ and io/ made: the G-code reader, a load
test's forces, a design layer's drawn numbers, and the field-table command."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from mst_cli.cad.gcode import parse_gcode
from mst_cli.calibration.loadtest import parse_readings
from mst_cli.sensor.document import load_document

ROOT = Path(__file__).resolve().parents[1]


def test_the_field_tables_are_rewritten_by_the_schema_module(tmp_path):
    # sensor/document.py binds the generator (io/field_tables.py) to its sections: the documented
    # command still regenerates docs/file-format.md's tables, to the same text
    copy = tmp_path / "file-format.md"
    copy.write_text((ROOT / "docs" / "file-format.md").read_text())
    subprocess.run([sys.executable, "-m", "mst_cli.sensor.document", str(copy)], check=True, cwd=ROOT)
    assert copy.read_text() == (ROOT / "docs" / "file-format.md").read_text()


GCODE = """\
G28
G1 X5 Y5 E1 ; start G-code, before the first layer: ignored
;LAYER_CHANGE
;Z:0.2
;HEIGHT:0.2
M83
;TYPE:External perimeter
;WIDTH:0.45
G1 X10 Y0 E0.5
G1 X10 Y10 E0.5
G0 X0 Y10
G1 X0 Y0 E0.5
;LAYER_CHANGE
;Z:0.4
;HEIGHT:0.2
;PAUSE_PRINT
M117 insert the magnet
M601
G92 E0
M82
G1 X10 Y0 E1.0
G1 X10 Y0 E2.0 ; no move in x, y: no segment
; estimated printing time (normal mode) = 1h 2m 3s
; filament used [mm] = 12.5
; total filament used [g] = 0.04
"""


def test_the_gcode_reader_follows_the_head():
    g = parse_gcode(GCODE)
    assert [(lay.index, lay.z_mm, lay.height_mm, len(lay.segments)) for lay in g.layers] == [
        (1, 0.2, 0.2, 3),
        (2, 0.4, 0.2, 1),
    ]
    first = g.layers[0]
    assert first.segments[0].tolist() == [5.0, 5.0, 10.0, 0.0, 0.45]
    assert first.e_mm.tolist() == [0.5, 0.5, 0.5]  # relative E (M83)
    assert first.paths.tolist()[0] == first.paths.tolist()[1] != first.paths.tolist()[2]  # travel between
    # the pause: the ;PAUSE_PRINT marker named by the command PrusaSlicer wrote after it
    assert [(p.command, p.after_layer, p.z_mm, p.mid_layer) for p in g.pauses] == [("M601", 1, 0.2, False)]
    assert g.layers[1].e_mm.tolist() == [1.0]  # absolute E again (M82) after G92 E0
    assert (g.print_time_s, g.filament_mm, g.filament_g) == (3723.0, 12.5, 0.04)


def test_a_load_test_gives_its_forces_and_readings_without_a_force_column_refuse():
    lt = parse_readings("force_N,Bx_uT,By_uT,Bz_uT\n0,1,2,300\n1.5,1,2,310\n", "lt.csv", need_force=True)
    assert lt.load_N.tolist() == [0.0, 1.5]
    readings = parse_readings("Bx_uT,By_uT,Bz_uT\n1,2,300\n", "r.csv", need_force=False)
    assert readings.force_N is None
    with pytest.raises(ValueError, match="force_N"):
        readings.load_N  # noqa: B018


def test_a_design_layer_is_drawn_by_its_three_numbers():
    doc = load_document(ROOT / "configs" / "mohammadi2021-forward.yaml")
    cells = doc.geometry().layers
    assert [la.drawn for la in doc.layers] == [(c.theta_deg, c.t_mm, c.h_mm) for c in cells]
    assert np.all([len(la.drawn) == 3 for la in doc.layers])
