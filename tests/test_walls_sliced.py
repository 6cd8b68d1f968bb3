"""The walls as sliced (issue 21, item 5): the width of extrusion a G-code lays across each
inclined wall, and the S_i and R_i the model predicts for those walls.

Kernel tests use hand-written extrusions whose widths across a wall the geometry fixes; the
wall centre lines are checked against the hex profile; the prediction against the model's own
uniform wall offset. The real slice of the reference export is in tests/test_slice.py.
"""

import json
import math

import numpy as np
import pytest

from mst_cli import api
from mst_cli.cad import gcode as G
from mst_cli.cad import layer_measure as M
from mst_cli.cad.expected_body import wall_centrelines_xz
from mst_cli.cad.manifest import Manifest, SliceManifest, export_manifest
from mst_cli.cad.print_check import walls_as_sliced
from mst_cli.cad.sliced_model import predict
from mst_cli.errors import InputError
from mst_cli.model.cell import HexCell
from mst_cli.sensor.as_printed import with_walls
from mst_cli.sensor.document import document_to_dict

ANGLE = math.radians(30.0)
U = np.array([math.cos(ANGLE), math.sin(ANGLE)])  # the wall's direction
N = np.array([-U[1], U[0]])  # across it


def lines_along(offsets_mm, widths_mm, length_mm=4.0, origin=(2.0, 1.0)):
    """Extrusions parallel to the wall (direction U through ``origin``), each at its offset
    across the wall, as (k, 5) segments."""
    o = np.asarray(origin)
    rows = []
    for off, w in zip(offsets_mm, widths_mm):
        a = o + off * N - 0.5 * length_mm * U
        b = o + off * N + 0.5 * length_mm * U
        rows.append([*a, *b, w])
    return np.array(rows)


def wall_ends(origin=(2.0, 1.0), half_mm=0.5):
    o = np.asarray(origin)
    return o - half_mm * U, o + half_mm * U


def test_one_line_across_a_wall_is_its_width():
    a, b = wall_ends()
    (one,) = M.material_across(lines_along([0.0], [0.41]), a, b, 1, 0.15)
    assert one.width_mm == pytest.approx(0.41) and one.n_lines == 1


def test_overlapping_perimeters_count_their_outer_edges_not_their_summed_widths():
    # two 0.45 mm lines 0.40 mm apart (overlapping 0.05 mm): the wall is 0.85 mm, not 0.90
    a, b = wall_ends()
    res = M.material_across(lines_along([-0.2, 0.2], [0.45, 0.45]), a, b, 5, 0.35)
    assert [r.width_mm for r in res] == pytest.approx([0.85] * 5)
    assert {r.n_lines for r in res} == {2}
    # three lines, the middle one a narrower gap fill overlapping both: outer edges 1.2 mm apart
    res = M.material_across(lines_along([-0.375, 0.0, 0.375], [0.45, 0.32, 0.45]), a, b, 3, 0.55)
    assert [r.width_mm for r in res] == pytest.approx([1.2] * 3) and {r.n_lines for r in res} == {3}


def test_material_beyond_air_is_not_the_wall_and_a_missing_wall_is_zero():
    a, b = wall_ends()
    # the wall (0.4 mm on the centre line) and a plate line 0.1 mm of air away from it
    segs = lines_along([0.0, 0.2 + 0.1 + 0.225], [0.4, 0.45])
    (r,) = M.material_across(segs, a, b, 1, 0.15)
    assert r.width_mm == pytest.approx(0.4) and r.n_lines == 1
    # a wall laid off the centre line by 0.1 mm is still the wall, at its own width
    (r,) = M.material_across(lines_along([0.1], [0.4]), a, b, 1, 0.15)
    assert r.width_mm == pytest.approx(0.4) and r.offset_mm == pytest.approx((-0.1, 0.3))
    # nothing reaches into the core: the wall is missing from the G-code
    (r,) = M.material_across(lines_along([1.0], [0.4]), a, b, 1, 0.15)
    assert (r.width_mm, r.n_lines, r.offset_mm) == (0.0, 0, None)


def test_voids_inside_a_thick_wall_stay_inside_it():
    # a 3 mm wall: two perimeters on each face, infill between them, 0.125 mm of air either side of it
    a, b = wall_ends()
    offsets = [-1.275, -0.85, 0.0, 1.275, 0.85]
    widths = [0.45, 0.45, 1.0, 0.45, 0.45]  # infill -0.5..0.5, voids 0.5..0.625 and mirrored
    (r,) = M.material_across(lines_along(offsets, widths), a, b, 1, 1.45)
    assert r.width_mm == pytest.approx(3.0) and r.n_lines == 5


def test_a_line_crossing_the_wall_obliquely_covers_its_width_over_the_cosine():
    # a rectilinear infill line at 60 degrees to the wall: the line across meets w / cos(60)
    a, b = wall_ends()
    d = np.array([math.cos(ANGLE + math.radians(60)), math.sin(ANGLE + math.radians(60))])
    o = np.array([2.0, 1.0])
    segs = np.array([[*(o - 2 * d), *(o + 2 * d), 0.45]])
    (r,) = M.material_across(segs, a, b, 1, 0.3)
    assert r.width_mm == pytest.approx(0.45 / math.cos(math.radians(60)))


@pytest.mark.parametrize("theta, t, h", [(11.47, 0.4, 1.58), (25.0, 0.6, 2.0), (47.2, 1.4, 4.5)])
def test_wall_centre_lines_lie_midway_between_the_faces_on_the_free_stretch(theta, t, h):
    cell = HexCell(theta, t, h)
    outer, inner = np.array(cell.outer_profile_xz()), np.array(cell.inner_profile_xz())
    edges = {"lower right": (0, 1), "upper right": (1, 2), "upper left": (3, 4), "lower left": (4, 5)}
    walls = wall_centrelines_xz(cell)
    assert [w[0] for w in walls] == list(edges)
    for name, a, b in walls:
        k0, k1 = edges[name]
        for face in (outer, inner):
            p, q = face[k0], face[k1]
            nrm = np.array([-(q - p)[1], (q - p)[0]]) / np.hypot(*(q - p))
            # both ends t/2 from each face: on the centre line, parallel to the wall
            assert abs((np.asarray(a) - p) @ nrm) == pytest.approx(t / 2)
            assert abs((np.asarray(b) - p) @ nrm) == pytest.approx(t / 2)
        u = (outer[k1] - outer[k0]) / np.hypot(*(outer[k1] - outer[k0]))
        for end in (a, b):  # inside both faces' extent along the wall
            s = (np.asarray(end) - outer[k0]) @ u
            assert s >= (inner[k0] - outer[k0]) @ u - 1e-9 and s >= -1e-9
            assert s <= (outer[k1] - outer[k0]) @ u + 1e-9 and s <= (inner[k1] - outer[k0]) @ u + 1e-9


def gcode_of(layers_segments, layer_height=0.2):
    """G-code text with one 'Perimeter' feature per layer: segments (x0, y0, x1, y1, w)."""
    out = ["G90", "M83", "G92 E0"]
    for k, segs in enumerate(layers_segments, start=1):
        out += [
            ";LAYER_CHANGE",
            f";Z:{layer_height * k:.3f}",
            f";HEIGHT:{layer_height}",
            f"G1 Z{layer_height * k:.3f}",
            ";TYPE:Perimeter",
        ]
        for x0, y0, x1, y1, w in segs:
            out += [f";WIDTH:{w}", f"G1 X{x0:.4f} Y{y0:.4f} F600", f"G1 X{x1:.4f} Y{y1:.4f} E0.05"]
    return "\n".join(out) + "\n"


def test_walls_as_sliced_reads_the_gcode_widths_over_the_walls_print_layers():
    # one wall along U through (2, 1) (print frame); the G-code frame is shifted by (100, 50)
    a, b = wall_ends()
    shift = (100.0, 50.0)
    manifest = SliceManifest.from_dict(
        {
            "print": {
                "wall_lines": [
                    {
                        "layer": 1,
                        "wall": "lower right",
                        "t_mm": 0.8,
                        "x0_mm": a[0],
                        "y0_mm": a[1],
                        "x1_mm": b[0],
                        "y1_mm": b[1],
                        "z_low_mm": 0.2,
                        "z_high_mm": 0.8,
                    }
                ]
            }
        }
    )
    two = lines_along([-0.2, 0.2], [0.45, 0.45]) + [shift[0], shift[1], shift[0], shift[1], 0]
    wide = lines_along([0.0], [1.5]) + [shift[0], shift[1], shift[0], shift[1], 0]
    # layer 1 (a wide first layer) and layer 5 (above z_high) are outside the wall's z range
    g = G.parse_gcode(gcode_of([wide, two, two, two, wide]))
    (row,) = walls_as_sliced(g, manifest, shift, 0.0).values["layers"]
    (wall,) = row["walls"]
    assert wall["sliced_t_mm"] == pytest.approx(0.85) and wall["n_lines"] == 2
    assert wall["samples"] == 3 * 5 and wall["missing"] == 0
    assert row["sliced_t_mm"] == pytest.approx(0.85) and row["difference_mm"] == pytest.approx(0.05)
    # no wall lines (an export.json from before): not given
    assert walls_as_sliced(g, SliceManifest.from_dict({}), shift, 0.0).values["layers"] == "not given"


@pytest.fixture(scope="module")
def forward():
    from pathlib import Path

    return api.load_design(Path(__file__).resolve().parents[1] / "configs" / "mohammadi2021-forward.yaml")


def test_uniformly_thicker_sliced_walls_predict_what_the_printer_wall_offset_predicts(forward):
    # the per-layer path (sliced t written into the design) against the model's own uniform wall
    # offset (printer.wall_offset_mm, applied by as_printed): the same physics, reached two ways
    dt = 0.05
    p = predict(forward, [la.t_mm + dt for la in forward.layers])
    from dataclasses import replace

    offset = api.simulate(replace(forward, printer=replace(forward.printer, wall_offset_mm=dt)))
    designed = api.simulate(forward)
    for row, reg, d in zip(p["regimes"], offset.regimes, designed.regimes):
        assert row["S_sliced_per_N"] == pytest.approx(reg.sensitivity_secant_per_N, rel=1e-9)
        assert row["R_sliced_N"] == pytest.approx(reg.force_to_N, rel=1e-9)
        assert row["S_designed_per_N"] == pytest.approx(d.sensitivity_secant_per_N, rel=1e-12)
        assert row["R_change_rel"] == pytest.approx(reg.force_to_N / d.force_to_N - 1)
    # 0.05 mm on every wall is no small change to the model: the two paths agree on a real difference
    assert max(abs(row["S_change_rel"]) for row in p["regimes"]) > 0.01


def test_sliced_walls_thinner_than_the_printing_rules_are_still_simulated(forward):
    # 0.35 mm is below printer.min_wall_mm: the model of the print lowers the rule, it does not refuse
    doc = with_walls(forward, [0.35, 1.0, 1.4])
    assert doc.layers[0].t_mm == 0.35 and doc.printer.min_wall_mm <= 0.35
    assert "error" not in predict(forward, [0.35, 1.0, 1.4])
    assert predict(forward, [0.0, 1.0, 1.4])["error"].startswith("a wall is missing")


@pytest.mark.parametrize("kind", [Manifest, SliceManifest])
def test_a_malformed_design_in_export_json_names_its_field(forward, kind):
    # check and slice read it with one rule: the design file's
    d = document_to_dict(forward)
    assert SliceManifest.from_dict({"design": d}).design.layers == forward.layers
    base = export_manifest(forward.name, forward.geometry(), forward.printer, 0.01, ["sensor.stl"], design=d)
    assert kind.from_dict(json.loads(json.dumps(base))).design.layers == forward.layers
    for edit, field in (
        (lambda m: m["design"]["layers"][1].update(t_mm=-1), "export.json.design.layers[1].t_mm"),
        (lambda m: m["design"]["layers"][0].update(t_mm=0.95), "export.json.design.layers[0]"),
        (lambda m: m["design"]["layers"][2].pop("t_mm"), "export.json.design.layers"),
        (lambda m: m.update(design=[1, 2]), "export.json.design"),
    ):
        bad = json.loads(json.dumps(base))
        edit(bad)
        with pytest.raises(InputError) as exc:
            kind.from_dict(bad)
        assert exc.value.field.startswith(field), (exc.value.field, field)
