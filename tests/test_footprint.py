"""The footprint is the spec's (issue 44 item 4, issue 46 "a layout that does not fit").

A spec's face (family.width_mm x depth_mm) bounds the body: a chip off the face is refused by
every command that loads the file, and a board slot that with its side wall reaches past the
face's width is refused by ``mst design`` and ``mst export`` in one line, nothing written.
``mst check`` measures the body and every slot against the face, so an export that widened
its base (0.17 did, silently) fails.

Numbers by hand: the Adafruit 4022 board is 25.4 mm long with its chip 12.6 mm from the -x
edge, clearance 0.2 and side wall 1.2 mm: a chip at x = 12 has its slot at -0.8 .. 25.0 mm,
which needs a face 2 (25.0 + 1.2) = 52.4 mm wide; the face is 30 mm.
"""

from pathlib import Path

import pytest
from click.testing import CliRunner

from mst_cli.cli.app import main
from mst_cli.model import board_slots

ROOT = Path(__file__).resolve().parents[1]
FORWARD = ROOT / "configs" / "mohammadi2021-forward.yaml"
SPEC = ROOT / "configs" / "mohammadi2021.yaml"


def run(args):
    return CliRunner().invoke(main, [str(a) for a in args])


def with_meter(source: Path, folder: Path, board: str, chips) -> Path:
    lines = f"  board: {board}\n  chip_offset_mm: {list(chips[0])}\n"
    if len(chips) > 1:
        lines += f"  positions_mm: {[list(c) for c in chips]}\n"
    path = folder / f"{source.stem}-{board}.yaml"
    path.write_text(source.read_text().replace("  board: adafruit-4022\n", lines))
    return path


def one_line_refusal(res, *words):
    assert res.exit_code == 2, res.output
    line = res.output.strip()
    assert "\n" not in line and line.startswith("mst: invalid input: magnetometer."), line
    for w in words:
        assert w in line, line


@pytest.mark.parametrize("verb", ["simulate", "design", "export"])
def test_a_chip_off_the_face_is_refused_by_every_command(tmp_path, verb):
    """Issue 46's layout: positions [[0,0],[40,0]] on the bare carrier, 40 mm from the axis of a 30 mm face."""
    source = SPEC if verb == "design" else FORWARD
    path = with_meter(source, tmp_path, "bare-qfn", [(0.0, 0.0), (40.0, 0.0)])
    out = tmp_path / "out"
    res = run([verb, path, "--out", out] + (["--stl"] if verb == "export" else ["--no-plot"]))
    one_line_refusal(res, "positions_mm", "chip 1 at (40, 0) mm lies off the face", "|x| <= 15 mm")
    assert not out.exists()


@pytest.mark.parametrize("verb", ["design", "export"])
@pytest.mark.parametrize(
    ("chips", "field", "needs"),
    [([(0.0, 0.0), (12.0, 0.0)], "positions_mm", "52.4 mm"), ([(-14.0, 0.0)], "chip_offset_mm", "56 mm")],
)
def test_a_layout_needing_a_wider_body_is_refused_in_one_line(tmp_path, verb, chips, field, needs):
    """-14: slot -26.8 .. -1.0 mm, a face 2 (26.8 + 1.2) = 56 mm wide; the spec's is 30 mm."""
    path = with_meter(SPEC, tmp_path, "adafruit-4022", chips)
    out = tmp_path / "out"
    res = run([verb, path, "--out", out] + (["--stl"] if verb == "export" else ["--no-plot"]))
    one_line_refusal(res, field, f"needs a face {needs} wide", "family.width_mm is 30 mm")
    assert not out.exists()


@pytest.mark.parametrize("verb", ["simulate", "read"])
def test_section_mode_refuses_a_layout_whose_boards_do_not_fit(tmp_path, verb):
    """model.load_path: section meshes the part's housing (docs/design.md 4.7), so the part must be
    one ``mst export`` makes: the layout 52.4 mm wide is refused before any solve, where the
    closed form simulates it (its cover over the slot is a beam, whatever the slot's place)."""
    path = with_meter(FORWARD, tmp_path, "adafruit-4022", [(0.0, 0.0), (12.0, 0.0)])
    section = path.with_name("section.yaml")
    section.write_text(path.read_text() + "model:\n  load_path: section\n")
    readings = tmp_path / "r.csv"
    readings.write_text("Bx_uT,By_uT,Bz_uT\n0,0,-20000\n")
    out = tmp_path / "out"
    args = ["simulate", section, "--out", out, "--no-plot"] if verb == "simulate" else ["read", section, readings]
    one_line_refusal(run(args), "positions_mm", "needs a face 52.4 mm wide")
    assert not out.exists()
    assert run(["simulate", path, "--out", tmp_path / "closed", "--no-plot"]).exit_code == 0


def test_the_body_is_never_wider_than_the_face(tmp_path):
    res = run(["export", FORWARD, "--stl", "--out", tmp_path / "o"])
    assert res.exit_code == 0, res.output
    res = run(["check", tmp_path / "o", "--load-path-max", "1"])  # the mesh's checks (the load path: test_checks)
    assert res.exit_code == 0, res.output
    row = next(line for line in res.output.splitlines() if line.startswith("footprint"))
    assert "PASS" in row and "body 30 mm along x" in row


def test_check_fails_a_body_that_was_widened_for_its_slots(tmp_path, monkeypatch):
    """An export made the 0.17 way (the base widened to hold chip 2's slot, no face rule):
    `mst check` measures the body at 56 mm against the 30 mm face and names both slots
    (-26.8 .. -1.0 and 1.0 .. 26.8 mm, tests/test_two_chips_cad.py)."""

    def widened(g):
        reach = max(max(-x0, x1) for x0, x1 in (board_slots.chip_slot_x_mm(g, c) for c in g.chips_xy_mm))
        return max(g.width_mm, 2 * (reach + g.housing.side_wall_mm))

    monkeypatch.setattr(board_slots, "base_length_mm", widened)
    monkeypatch.setattr(board_slots, "face_violations", lambda g: [])
    path = with_meter(FORWARD, tmp_path, "adafruit-4022", [(-14.0, 0.0), (13.8, 0.0)])
    res = run(["export", path, "--stl", "--out", tmp_path / "o"])
    assert res.exit_code == 0, res.output
    monkeypatch.undo()
    res = run(["check", tmp_path / "o"])
    assert res.exit_code == 1, res.output
    row = next(line for line in res.output.splitlines() if line.startswith("footprint"))
    assert "FAIL" in row and "body 56 mm along x" in row
    assert "the body is 56 mm wide, not the face's 30 mm" in res.output
    assert "chip 1's slot x -26.8..-1 mm leaves less than 1.2 mm of wall" in res.output
    assert "chip 2's slot x 1..26.8 mm leaves less than 1.2 mm of wall" in res.output
