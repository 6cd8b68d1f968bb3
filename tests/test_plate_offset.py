"""The plates between unlike layers on the whole-part rung, one plate at a time
(``PartOptions.rigid_plates``; studies/unlike_plates.py --per-plate, docs/design.md 4.7)."""

from __future__ import annotations

import tempfile
from pathlib import Path

import pytest

import mst_cli as mst
from mst_cli.model.mechanics import whole_part as wp
from studies.unlike_plates import plate_rows, stack


def test_the_rung_gives_both_plates_of_an_unlike_stack_alike():
    """Stack A, B, A (20 and 40 degrees, t 0.4, h 1.8, 1.6 mm plates), regime 1, each plate alone
    in TPU, the other held rigid: plate 1 stands on A under B, plate 2 on B under A, mirror images
    about B's mid-plane, so the rung (an independent FE of the section) gives them within 1 %
    (measured 0.4 %). Each alone is a share of both plates in TPU: more than a third, less than
    two thirds (the option holds the other one rigid: were it ignored, each would be both)."""
    with tempfile.TemporaryDirectory() as tmp:
        path = stack(Path(tmp), 20.0, 40.0)
        one, two = plate_rows(path)
        doc, _ = mst.designed(path)
        g, m = doc.geometry(), doc.material
        rigid = wp.press(g, m, wp.PartOptions(member_factor=wp.RIGID_FACTOR)).drop_mm_per_N
        plates = wp.PartOptions(member_factor=wp.RIGID_FACTOR, scaled=("base", "cap"))
        both = wp.press(g, m, plates).drop_mm_per_N - rigid
    assert one["rung"] == pytest.approx(two["rung"], rel=0.01)
    assert one["e"] == pytest.approx(-two["e"], rel=1e-9) and abs(one["e"]) > 1.0
    assert both / 3.0 < one["rung"] < 2.0 * both / 3.0
