"""The plates between unlike layers on the whole-part rung, one plate at a time
(``PartOptions.rigid_plates``; studies/unlike_plates.py --per-plate, docs/design.md 4.7)."""

from __future__ import annotations

import tempfile
from pathlib import Path

import pytest

from studies.unlike_plates import plate_rows, stack


def test_the_rung_gives_both_plates_of_an_unlike_stack_alike():
    """Stack A, B, A (20 and 40 degrees, t 0.4, h 1.8, 1.6 mm plates), regime 1, each plate alone
    in TPU, the other held rigid: plate 1 stands on A under B, plate 2 on B under A, mirror images
    about B's mid-plane, so the rung (an independent FE of the section) gives them within 1 %
    (measured 0.4 %), each some drop of its own."""
    with tempfile.TemporaryDirectory() as tmp:
        rows = plate_rows(stack(Path(tmp), 20.0, 40.0))
    one, two = rows
    assert one["rung"] == pytest.approx(two["rung"], rel=0.01)
    assert one["e"] == pytest.approx(-two["e"], rel=1e-9) and abs(one["e"]) > 1.0
    assert 0.0 < one["rung"] and 0.0 < two["rung"]
