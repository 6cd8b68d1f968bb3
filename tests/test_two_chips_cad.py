"""Two chips in one body (issue 39): `mst export` cuts a board slot for each chip of
magnetometer.positions_mm, `mst check` verifies each, and a layout whose boards cannot lie
side by side is refused. Chips at different y each get their own slot floor (the second half).

The reference is configs/mohammadi2021-forward.yaml (Adafruit 4022 board, default housing,
D = 20 mm, 0.2 mm layers) with its chips at x = -14 and +13.8 mm, y = 0. Numbers worked by
hand from the board (25.4 x 17.78 x 1.6 mm, chip at (12.6, 8.3) from its corner, JST SH
sockets 2.95 mm tall, 6 mm along the short edges) and the housing defaults (clearance 0.2,
base floor 0.8, side wall 1.2 mm) and the config's chip clearance 0.65 mm:

* slot z: 0.8 (base floor) .. 0.8 + 1.6 + 2.95 + 0.65 = 6.0 mm;
* slot floor: the chip's y 0 less 8.3 is print height 1.7 mm, snapped to the nearest layer
  (halves up) 1.8 mm: y = -8.2 mm; the slot runs from there to the top face y = 10;
* chip 1's slot x: -14 - 12.6 - 0.2 = -26.8 .. -26.6 + 25.4 + 0.2 = -1.0; chip 2's:
  13.8 - 12.8 = 1.0 .. 13.8 + 13.0 = 26.8 (2 mm of wall between, 1.2 needed); both reach
  26.8 mm from the axis, so they need a face 2 (26.8 + 1.2) = 56 mm wide: the reference's
  family.width_mm is set to 56 (the footprint is the spec's; a narrower face is refused);
* windows: z 2.4 (board top) .. 6.0; floor y: -8.2 + 5.89 - 0.2 = -2.51, print height 7.49
  snapped down 7.4: y = -2.6.

One chip (at -14): its +x window runs from -1.0 out to the face at 28. Two chips: that span
is the 2 mm link window, chip 2's slot and its own 1.2 mm window to the face; the body loses
chip 2's slot less the part of it the one-chip window had already removed:
25.8 x (18.2 x 5.2 - 12.6 x 3.6) = 1271.424 mm^3.
"""

import json
from pathlib import Path

import numpy as np
import pytest
import trimesh
from click.testing import CliRunner
from mesh_rays import triangle_hits

from mst_cli.cad.expected_body import overlap_volume_mm3
from mst_cli.cli.app import main

ROOT = Path(__file__).resolve().parents[1]
FORWARD = ROOT / "configs" / "mohammadi2021-forward.yaml"
SPEC = ROOT / "configs" / "fingertip.yaml"
DEPTH_MM = 20.0
FACE_WIDTH_MM = 56.0  # 2 (26.8 + 1.2): both slots with a side wall outside them
CHIPS = [(-14.0, 0.0), (13.8, 0.0)]
SLOTS_X_MM = [(-26.8, -1.0), (1.0, 26.8)]
SLOT_Z_MM = (0.8, 6.0)
SLOT_FLOOR_Y_MM = -8.2
WINDOW_FLOOR_Y_MM = -2.6
# a window's section: 6.6 mm up the depth (the 6 mm socket, 0.2 mm clearance each side, on the
# layer grid) x 3.6 mm high, and its gable: 3.6 mm wide, 1.8 mm rise (half its width, on the grid)
WINDOW_SECTION_MM2 = 6.6 * 3.6 + 0.5 * 3.6 * 1.8
# the second slot, less the first chip's +x window over the same x (the one-chip body's)
EXTRA_SLOT_MM3 = 25.8 * 18.2 * 5.2 - 25.8 * WINDOW_SECTION_MM2
STL_VOLUME_TOL_MM3 = 0.05  # float32 vertices (~4e-6 mm at 30 mm) over ~6000 mm^2 of surface


def run(args):
    return CliRunner().invoke(main, [str(a) for a in args])


def with_chips(source: Path, folder: Path, chips, name="two.yaml") -> Path:
    """``source`` with its chip at chips[0] and, for more than one, magnetometer.positions_mm."""
    lines = f"  chip_offset_mm: {list(chips[0])}\n"
    if len(chips) > 1:
        lines += f"  positions_mm: {[list(c) for c in chips]}\n"
    text = source.read_text().replace("  board: adafruit-4022\n", "  board: adafruit-4022\n" + lines)
    text = text.replace("  width_mm: 30\n", f"  width_mm: {FACE_WIDTH_MM:g}\n")
    path = folder / name
    path.write_text(text)
    return path


def exported(folder: Path, chips) -> Path:
    out = folder / f"out{len(chips)}"
    r = run(["export", with_chips(FORWARD, folder, chips, f"chips{len(chips)}.yaml"), "--stl", "--out", out])
    assert r.exit_code == 0, r.output + r.stderr
    return out


@pytest.fixture(scope="module")
def exports(tmp_path_factory):
    folder = tmp_path_factory.mktemp("two_chips")
    return exported(folder, CHIPS[:1]), exported(folder, CHIPS)


def sensor_mesh(out: Path) -> trimesh.Trimesh:
    """The STL in the sensor frame: print (x, y, z) = (x, -z, y + D/2) undone."""
    mesh = trimesh.load(out / "sensor.stl")
    to_sensor = np.array([[1, 0, 0, 0], [0, 0, 1, -0.5 * DEPTH_MM], [0, -1, 0, 0], [0, 0, 0, 1]], dtype=float)
    return mesh.apply_transform(to_sensor)


def ray_hits(mesh: trimesh.Trimesh, origin, direction) -> np.ndarray:
    """Distances along a ray of its crossings with the mesh (:func:`mesh_rays.triangle_hits`)."""
    return triangle_hits(np.asarray(mesh.triangles, dtype=float), origin, direction)


def air_along(mesh: trimesh.Trimesh, origin, direction) -> list[tuple[float, float]]:
    """Air intervals (start, end) in mm along a ray from outside the body, in the ray's own
    coordinate (origin + s * direction): each from leaving the solid to entering it again."""
    s = ray_hits(mesh, origin, direction)
    assert len(s) % 2 == 0, s  # in and out of a closed body
    return [(float(a), float(b)) for a, b in zip(s[1:-1:2], s[2::2])]


def test_each_chip_has_an_empty_slot_of_the_board_outline(exports):
    mesh = sensor_mesh(exports[1])
    far = 40.0
    # across x inside the board's thickness (z 0.8..2.4, below every window), just above the floor
    across = air_along(mesh, (-far, SLOT_FLOOR_Y_MM + 0.3071, 1.6123), (1, 0, 0))
    assert np.allclose([(a - far, b - far) for a, b in across], SLOTS_X_MM, atol=1e-4)
    for x, y in CHIPS:
        # up the stack under each chip: the slot is the lowest air, base floor to cover
        lowest = air_along(mesh, (x + 0.0123, y + 0.0071, -1.0), (0, 0, 1))[0]
        assert np.allclose(np.array(lowest) - 1.0, SLOT_Z_MM, atol=1e-4)
        # up the depth through the slot: solid below the floor, air from it out of the top face
        hits = ray_hits(mesh, (x + 0.0123, -15.0, 3.0123), (0, 1, 0)) - 15.0
        assert np.allclose(hits, [-DEPTH_MM / 2, SLOT_FLOOR_Y_MM], atol=1e-4)
    # the wall between the slots: the link window (air from the board top to the cover) above
    # the windows' floor, solid up to the base top below it
    above = air_along(mesh, (0.0123, WINDOW_FLOOR_Y_MM + 0.3071, -1.0), (0, 0, 1))[0]
    assert np.allclose(np.array(above) - 1.0, (2.4, SLOT_Z_MM[1]), atol=1e-4)
    below = air_along(mesh, (0.0123, WINDOW_FLOOR_Y_MM - 0.3071, -1.0), (0, 0, 1))[0]
    assert below[0] - 1.0 > 6.8 - 1e-4  # the first air is a layer's cavity, above the base


def test_the_two_chip_body_is_one_volume_lighter_by_the_second_slot(exports):
    one, two = (sensor_mesh(out) for out in exports)
    assert two.is_watertight and two.is_volume
    assert len(two.split(only_watertight=False)) == 3  # the body, its magnet pocket and its insert's slot
    assert np.allclose(one.bounds, two.bounds, atol=1e-5)  # both slots reach 26.8 mm: base 56 mm
    assert two.bounds[1][0] - two.bounds[0][0] == pytest.approx(56.0, abs=1e-5)
    assert one.volume - two.volume == pytest.approx(EXTRA_SLOT_MM3, abs=STL_VOLUME_TOL_MM3)


def test_export_json_lists_every_slot_and_a_one_chip_export_keeps_its_keys(exports):
    one = json.loads((exports[0] / "export.json").read_text())
    two = json.loads((exports[1] / "export.json").read_text())
    assert "board_slots" not in one
    assert two["board_slot"] == two["board_slots"][0]
    assert (one["board_slot"]["x0_mm"], one["board_slot"]["x1_mm"]) == pytest.approx(SLOTS_X_MM[0], abs=1e-9)
    slots = two["board_slots"]
    assert np.allclose([(s["x0_mm"], s["x1_mm"]) for s in slots], SLOTS_X_MM, atol=1e-9)
    assert [s["chip_xy_nominal_mm"] for s in slots] == [list(c) for c in CHIPS]
    assert [s["floor_y_mm"] for s in slots] == pytest.approx([SLOT_FLOOR_Y_MM] * 2, abs=1e-9)
    # chip 1's +x window now ends at chip 2's slot, and chip 2's -x window is the same span
    spans = [[(w["x_inner_mm"], w["x_outer_mm"]) for w in s["cable_windows"]] for s in slots]
    assert np.allclose(spans, [[(-26.8, -28.0), (-1.0, 1.0)], [(1.0, -1.0), (26.8, 28.0)]], atol=1e-9)
    assert np.allclose([w["floor_y_mm"] for s in slots for w in s["cable_windows"]], WINDOW_FLOOR_Y_MM, atol=1e-9)


def check_json(out: Path) -> dict:
    r = run(["check", out, "--json"])
    return json.loads(r.stdout)


def test_check_passes_with_two_chips_and_names_the_slot_that_is_filled(exports, tmp_path):
    report = check_json(exports[1])
    assert report["passed"], report["failed"]
    checks = {c["name"]: c for c in report["checks"]}
    slot = checks["board_slot"]["values"]
    assert slot["chip_2_x0_mm"] == pytest.approx(SLOTS_X_MM[1][0], abs=1e-4)
    assert slot["chip_2_floor_y_mm"] == pytest.approx(SLOT_FLOOR_Y_MM, abs=1e-4)
    gap = checks["magnet_chip_gap"]["values"]
    assert gap["chip_2_measured_mm"] == pytest.approx(gap["measured_mm"], abs=1e-4)

    # fill chip 2's slot: its checks fail by name. The box x 0.95..26.9, y -8.4..1.2 (past chip
    # 2; both on the layer grid), z 0.7..5.75 (past the slot's floor and cover; the link window
    # from x -1 to 1 stays open)
    report = check_json(filled(exports[1], tmp_path, ((0.95, -8.4, 0.7), (26.9, 1.2, 5.75))))
    assert report["failed"] == ["volume", "board_slot", "magnet_chip_gap"]
    checks = {c["name"]: c for c in report["checks"]}
    mismatched = checks["board_slot"]["note"].removeprefix("mismatch: ").split(", ")
    assert mismatched and all(k.startswith("chip_2_") for k in mismatched), mismatched
    assert "off under chip 2" in checks["magnet_chip_gap"]["note"]


@pytest.mark.parametrize(
    "chips, says",
    [
        ([(-14.0, 0.0), (12.0, 0.0)], "leave 0.2 mm between them: chips must be at least 27 mm apart along x"),
        # -1 - 8.3 is print height 0.7, snapped to 0.8: under the 1.2 mm wall the one-chip rule keeps
        ([(-14.0, 0.0), (13.8, -1.0)], "chip 1's board slot and cable windows reach y = -9.2 mm, 0.8 mm above"),
    ],
)
def test_boards_that_cannot_lie_side_by_side_are_refused_and_nothing_written(tmp_path, chips, says):
    for source in (FORWARD, SPEC):  # a spec is refused before it is designed
        out = tmp_path / f"out_{source.stem}"
        r = run(["export", with_chips(source, tmp_path, chips), "--stl", "--out", out])
        assert r.exit_code == 2, (r.output, r.stderr)
        line = r.stderr.strip()
        assert "\n" not in line and line.startswith("mst: invalid input: magnetometer.positions_mm = "), line
        assert says in line
        assert not out.exists()
    # the reading side models any layout: simulate still takes it
    r = run(["simulate", with_chips(FORWARD, tmp_path, chips), "--out", tmp_path / "sim", "--no-plot"])
    assert r.exit_code == 0, r.stderr


def test_overlap_of_boxes_counts_what_two_cover():
    unit = ((0.0, 0.0, 0.0), (1.0, 2.0, 3.0))
    assert overlap_volume_mm3([unit, unit]) == pytest.approx(6.0)
    assert overlap_volume_mm3([unit, ((1.0, 0.0, 0.0), (2.0, 2.0, 3.0))]) == 0.0  # touching
    assert overlap_volume_mm3([unit, ((0.5, 1.0, 1.0), (4.0, 4.0, 4.0))]) == pytest.approx(0.5 * 1.0 * 2.0)


# Chips at different y (docs/printing.md "Two or more chips"): each board on its own floor.
# Chip 1 at (-14, -0.4): -0.4 - 8.3 is print height 1.3, snapped (halves up) to 1.4: floor
# y -8.6; its windows -8.6 + 5.89 - 0.2 = -2.91, print 7.09 down to 7.0: y -3.0. Chip 2 at
# (13.8, 0.5): 0.5 - 8.3 is print height 2.2 (on the grid): floor y -7.8; its windows -2.11,
# print 7.89 down to 7.8: y -2.2. The link window between them takes the lower floor, -3.0.
# Against chip 1 alone (its +x window from -1 to the face at 28, floor -3.0): over chip 2's
# slot (x 1..26.8) the body loses 25.8 x (17.8 x 5.2 - 13 x 3.6); beyond it (x 26.8..28) chip
# 2's own window starts 0.8 mm higher than chip 1's did, so the body keeps 1.2 x 0.8 x 3.6.
STEP_CHIPS = [(-14.0, -0.4), (13.8, 0.5)]
STEP_FLOORS_Y_MM = [-8.6, -7.8]
STEP_WINDOW_FLOORS_Y_MM = [[-3.0, -3.0], [-3.0, -2.2]]  # chip 1's -x and link; chip 2's link and +x
# two chips: the second slot, the link window (2 mm of wall, from the lower floor -3.0 to the
# higher top 4.4: 7.4 mm) and chip 2's +x window (1.2 mm of wall); one chip: its +x window, 29 mm
# from its slot to the face
STEP_EXTRA_MM3 = (
    25.8 * 17.8 * 5.2 + 2.0 * (7.4 * 3.6 + 0.5 * 3.6 * 1.8) + 1.2 * WINDOW_SECTION_MM2 - 29.0 * WINDOW_SECTION_MM2
)


@pytest.fixture(scope="module")
def step_exports(tmp_path_factory):
    folder = tmp_path_factory.mktemp("two_floors")
    return exported(folder, STEP_CHIPS[:1]), exported(folder, STEP_CHIPS)


def test_chips_at_different_y_each_have_a_slot_on_their_own_floor(step_exports):
    mesh = sensor_mesh(step_exports[1])
    far = 40.0
    for (x, y), floor in zip(STEP_CHIPS, STEP_FLOORS_Y_MM):
        # up the depth through each slot: solid from the -y face up to its own floor
        hits = ray_hits(mesh, (x + 0.0123, -15.0, 3.0123), (0, 1, 0)) - 15.0
        assert np.allclose(hits, [-DEPTH_MM / 2, floor], atol=1e-4)
        lowest = air_along(mesh, (x + 0.0123, y + 0.0071, -1.0), (0, 0, 1))[0]
        assert np.allclose(np.array(lowest) - 1.0, SLOT_Z_MM, atol=1e-4)
    # across, in the board's thickness: between the floors only chip 1's slot is open
    between = air_along(mesh, (-far, -8.2071, 1.6123), (1, 0, 0))
    assert np.allclose([(a - far, b - far) for a, b in between], SLOTS_X_MM[:1], atol=1e-4)
    above = air_along(mesh, (-far, -7.5071, 1.6123), (1, 0, 0))
    assert np.allclose([(a - far, b - far) for a, b in above], SLOTS_X_MM, atol=1e-4)
    # the windows' floors, up the depth at the windows' height: -x face, link, +x face
    # and each window's top: a 45 deg gable over it, the side wall above it up to the +y face
    for x, floor in [(-27.4, -3.0), (0.0, -3.0), (27.4, -2.2)]:
        hits = ray_hits(mesh, (x + 0.0123, -15.0, 4.0123), (0, 1, 0)) - 15.0
        assert len(hits) == 4 and hits[-1] == pytest.approx(DEPTH_MM / 2, abs=1e-4), x
        assert np.allclose(hits[:2], [-DEPTH_MM / 2, floor], atol=1e-4), x


def test_the_stepped_body_is_one_volume_lighter_by_the_hand_worked_slot(step_exports):
    one, two = (sensor_mesh(out) for out in step_exports)
    assert two.is_watertight and two.is_volume
    assert len(two.split(only_watertight=False)) == 3  # the body, its magnet pocket and its insert's slot
    assert np.allclose(one.bounds, two.bounds, atol=1e-5)
    assert one.volume - two.volume == pytest.approx(STEP_EXTRA_MM3, abs=STL_VOLUME_TOL_MM3)
    slots = json.loads((step_exports[1] / "export.json").read_text())["board_slots"]
    assert [s["floor_y_mm"] for s in slots] == pytest.approx(STEP_FLOORS_Y_MM, abs=1e-9)
    floors = [[w["floor_y_mm"] for w in s["cable_windows"]] for s in slots]
    assert np.allclose(floors, STEP_WINDOW_FLOORS_Y_MM, atol=1e-9)


def filled(out: Path, folder: Path, box_mm) -> Path:
    """A copy of the export with the sensor-frame box ((x0, y0, z0), (x1, y1, z1)) made solid."""
    import manifold3d as mf

    bad = folder / "filled"
    bad.mkdir()
    (bad / "export.json").write_text((out / "export.json").read_text())
    mesh = trimesh.load(out / "sensor.stl")
    body = mf.Manifold(
        mf.Mesh(
            vert_properties=np.ascontiguousarray(mesh.vertices, np.float32),
            tri_verts=np.ascontiguousarray(mesh.faces, np.uint32),
        )
    )
    (x0, y0, z0), (x1, y1, z1) = box_mm  # to the print frame (x, -z, y + D/2)
    fill = mf.Manifold.cube((x1 - x0, z1 - z0, y1 - y0)).translate((x0, -z1, y0 + 0.5 * DEPTH_MM))
    solid = (body + fill).to_mesh()
    trimesh.Trimesh(solid.vert_properties[:, :3], solid.tri_verts).export(bad / "sensor.stl")
    return bad


def test_check_passes_on_the_stepped_layout_and_names_chip_2_when_its_slot_is_filled(step_exports, tmp_path):
    report = check_json(step_exports[1])
    assert report["passed"], report["failed"]
    slot = {c["name"]: c for c in report["checks"]}["board_slot"]["values"]
    assert [slot["floor_y_mm"], slot["chip_2_floor_y_mm"]] == pytest.approx(STEP_FLOORS_Y_MM, abs=1e-4)
    assert slot["chip_2_window_2_floor_y_mm"] == pytest.approx(-2.2, abs=1e-4)
    # chip 2's slot from under its floor to past its chip, on the layer grid; the link stays open
    report = check_json(filled(step_exports[1], tmp_path, ((0.95, -8.0, 0.7), (26.9, 1.6, 5.75))))
    assert report["failed"] == ["volume", "board_slot", "magnet_chip_gap"]
    checks = {c["name"]: c for c in report["checks"]}
    mismatched = checks["board_slot"]["note"].removeprefix("mismatch: ").split(", ")
    assert mismatched and all(k.startswith("chip_2_") for k in mismatched), mismatched
    assert "off under chip 2" in checks["magnet_chip_gap"]["note"]


def test_a_link_window_below_the_next_floor_stops_at_that_slot_wall(tmp_path):
    """D = 40: chip 1 at (-14, -10) has its floor at y -18.2 and windows at -12.6; chip 2 at
    (13.8, 8) its floor at -0.2. The link window (floor -12.6) ends at chip 2's slot wall x 1.0:
    below chip 2's floor that wall is solid, so the cut must not run on into it."""
    text = with_chips(FORWARD, tmp_path, [(-14.0, -10.0), (13.8, 8.0)]).read_text()
    deep = tmp_path / "deep.yaml"
    deep.write_text(text.replace("  depth_mm: 20\n", "  depth_mm: 40\n"))
    out = tmp_path / "deep"
    r = run(["export", deep, "--stl", "--out", out])
    assert r.exit_code == 0, r.output + r.stderr
    mesh = trimesh.load(out / "sensor.stl")
    mesh.apply_transform(np.array([[1, 0, 0, 0], [0, 0, 1, -20.0], [0, -1, 0, 0], [0, 0, 0, 1]], dtype=float))
    assert mesh.is_watertight and len(mesh.split(only_watertight=False)) == 3
    # across at y -5 (between the link's floor and chip 2's), window height: air from the -x
    # face through chip 1's slot and the link to x 1.0, then solid to the +x face
    assert np.allclose(ray_hits(mesh, (-40.0, -5.0071, 4.0123), (1, 0, 0)) - 40.0, [1.0, 28.0], atol=1e-4)
    report = check_json(out)
    assert report["passed"], report["failed"]
