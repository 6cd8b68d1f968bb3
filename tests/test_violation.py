"""One shape for a broken rule (model/violation.py), for the cell and the assembly alike (issue 23)."""

from __future__ import annotations

import pytest

from mst_cli.errors import InputError
from mst_cli.model.assembly import Housing, SensorGeometry, printer_violations
from mst_cli.model.cell import HexCell
from mst_cli.model.printer import Printer
from mst_cli.model.violation import Violation


def _thin_wall_sensor() -> SensorGeometry:
    ok = HexCell(30.0, 1.0, 3.0)
    thin = HexCell(30.0, 0.3, 3.0)
    return SensorGeometry((ok, thin))


def test_a_cell_rule_broken_in_a_sensor_names_its_layer_field_and_value():
    (v,) = _thin_wall_sensor().violations()
    assert isinstance(v, Violation)
    assert (v.rule, v.layer, v.field) == ("wall", 1, "layers[1]")
    assert v.value == {"theta_deg": 30.0, "t_mm": 0.3, "h_mm": 3.0}
    assert v.margin_mm == pytest.approx(0.3 - Printer().min_wall_mm)


def test_the_input_error_of_a_broken_cell_is_the_one_the_loaders_raised():
    (v,) = _thin_wall_sensor().violations()
    err = v.input_error("invalid cell")
    assert isinstance(err, InputError)
    assert (err.field, err.value) == ("layers[1]", {"theta_deg": 30.0, "t_mm": 0.3, "h_mm": 3.0})
    assert err.allowed == f"invalid cell (wall): {v.message}"


def test_an_assembly_rule_is_the_same_shape():
    odd = SensorGeometry((HexCell(30.0, 1.0, 3.0, depth_mm=20.1),))
    (v,) = odd.housing_violations()
    assert isinstance(v, Violation)
    assert (v.field, v.value, v.layer, v.margin_mm) == ("family.depth_mm", 20.1, None, None)
    assert v.allowed == v.message
    err = v.input_error()
    assert (err.field, err.value, err.allowed) == ("family.depth_mm", 20.1, v.message)


def test_printer_violations_are_violations_too():
    bad = Printer(wall_offset_mm=-0.39, min_wall_mm=0.2)
    (v,) = printer_violations(bad, Housing(), 0.1)
    assert isinstance(v, Violation) and v.field == "printer.wall_offset_mm" and v.value == -0.39


def test_the_sensor_judges_its_cells_by_its_own_printer():
    # a wall of 0.3 mm breaks the default printer's minimum but not a 0.25 mm printer's
    g = SensorGeometry((HexCell(30.0, 0.3, 3.0),), printer=Printer(nozzle_mm=0.25, min_wall_mm=0.25, min_gap_mm=0.25))
    assert g.violations() == []
    assert [v.rule for v in g.violations(Printer())] == ["wall"]
