"""The housing's base under a moment past layer 1's lock (docs/design.md 4.7, "The base's portal
under a moment"): the cover's turn in the tilt rung is the section frame's, exactly where it is
taken, and the frame's base against the whole-part rung's, an independent plane-strain FE of the
part's section (its member classes' figures stored by ``benchmarks/bench_whole_part.py
--off-centre --every-regime --out studies/data/member_turns.csv``, mst's general load against the
part's by ``--general --out studies/data/general_regimes.csv``)."""

from __future__ import annotations

import csv
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

import mst_cli as mst
from mst_cli.cad.whole_part_check import stated_shear_figures
from mst_cli.model import load_path as lp
from mst_cli.model.counter_turn import regime_start_N
from mst_cli.model.general_load import linear_response, loaded_stack
from mst_cli.model.mechanics import layer_laws
from mst_cli.model.mechanics.tilt import member_compliance
from mst_cli.model.plate_sway import locked_base_turn_rad_per_Nmm
from mst_cli.model.stack import Stack
from mst_cli.model.stack_pose import tilt_laws

ROOT = Path(__file__).resolve().parents[1]
TURNS = ROOT / "studies" / "data" / "member_turns.csv"
GENERAL = ROOT / "studies" / "data" / "general_regimes.csv"
DESIGNS = ("mohammadi2021-forward", "mohammadi2021", "fingertip")
BUDGET_REL = 0.10  # the issue's, on the turn per off-centre moment


def designed(name: str):
    doc, _ = mst.designed(ROOT / "configs" / f"{name}.yaml")
    return doc.geometry(), doc.material


def rows_of(path: Path) -> list[dict]:
    with path.open() as f:
        return list(csv.DictReader(f))


def cover_unit(laws):
    """The tilt law that carries the cover (model.part_laws.cover_host)."""
    (unit,) = [law for law in laws if law.member is not None]
    return unit


def test_past_layer_1s_lock_the_covers_turn_is_the_frames():
    """model.part_laws.unit_tilt_law: before layer 1's lock the cover turns by its centred rate
    over the chevron lever squared, C / x_c^2; past it by the section frame's base under a locked
    layer 1 (the cover's rate past the lock unchanged: it does not land on the forward design),
    and with every lever scaled by a calibration's factor f, by that over f^2, as C / x_c^2 is."""
    g, m = designed("mohammadi2021-forward")
    base = locked_base_turn_rad_per_Nmm(g, m)
    assert base > 0.0
    unit = cover_unit(tilt_laws(g, m, "spring"))
    lock = unit.member.moment_gain_after[0]
    assert lock == pytest.approx(min(law.lock_force_N for law in tilt_laws(g, m, "spring")), rel=1e-9)
    assert lp.cover_landing_N(lp.members(g, m), lock) > 3.0 * lock  # it does not land where we look
    before = member_compliance(unit, 0.5 * lock)
    assert before[1] == pytest.approx(unit.member.rate_mm_per_N(0.5 * lock) / unit.lever_mm**2, rel=1e-12)
    for F in (1.001 * lock, 3.0 * lock):
        assert member_compliance(unit, F)[1] == pytest.approx(base, rel=1e-12)
        assert member_compliance(unit, F)[0] == pytest.approx(unit.member.rate_mm_per_N(F), rel=1e-12)
    scaled = cover_unit(tilt_laws(g, m, "spring", lever_factor=1.25))
    assert member_compliance(scaled, 2.0 * lock)[1] == pytest.approx(base / 1.25**2, rel=1e-12)


@pytest.mark.parametrize("name", DESIGNS)
def test_the_frames_base_turns_as_the_rungs_past_layer_1s_lock(name):
    """The base alone in TPU (the rest rigid) under an off-centre press, past layer 1's lock: the
    section frame's turn per N mm within 15 % of the rung's on the three bundled designs
    (measured -4, +5 and +11 %; the closed form's C / x_c^2, the centred drop's, was -37 % on the
    forward design's 0.8 mm cover, where the portal's sway is the larger part)."""
    g, m = designed(name)
    order = [int(i) for i in Stack(layer_laws(g.layers, m, "spring")).lock_order]  # the bench's regimes
    rows = {(r["regime"], r["members"]): float(r["turn_per_moment_mrad_per_Nmm"]) for r in rows_of(TURNS)
            if r["design"] == name}  # fmt: skip
    frame = 1e3 * locked_base_turn_rad_per_Nmm(g, m)
    checked = 0
    for regime in range(2, len(order) + 1):  # the bench's regimes: 1 .. n
        if 0 not in order[: regime - 1]:
            continue
        rung = rows[(str(regime), "rigid")] - rows[(str(regime), "only the base")]  # its turns: the other sign
        assert 0.85 < frame / rung < 1.15, (name, regime, frame, rung)
        checked += 1
    assert checked >= 2
    if name == "mohammadi2021-forward":
        parts = lp.members(g, m)
        lever = cover_unit(tilt_laws(g, m, "spring")).lever_mm
        closed = 1e3 * parts.cover_locked_mm_per_N / lever**2
        assert closed / rung < 0.7


@pytest.mark.parametrize("name", DESIGNS)
def test_the_turn_per_moment_past_layer_1s_lock_is_the_rungs(name):
    """mst's turn per off-centre moment, linearised where each regime starts, within the issue's
    10 % of the whole-part rung's in every regime past layer 1's lock (measured 0 / -1 %
    forward, -1 / +4 % mohammadi2021, +6 / +3 % fingertip; the forward design read -12 / -17 %
    with the cover's C / x_c^2)."""
    g, m = designed(name)
    part = loaded_stack(g, m, "spring")
    locks = np.sort([t.lock_force_N for t in part.tilt])
    rung = {int(r["regime"]): float(r["turn_per_moment_mrad_per_Nmm"]) for r in rows_of(GENERAL) if r["design"] == name}
    for r in range(1, len(locks)):
        stated = stated_shear_figures(linear_response(part, regime_start_N(locks, r)))["turn_per_moment_mrad_per_Nmm"]
        assert stated == pytest.approx(rung[r + 1], rel=BUDGET_REL), (name, r + 1)


def test_the_portals_turn_moves_smoothly_with_the_cover():
    """Swept over the cover's thickness (0.8 to 3 mm, the forward design's layers, layer 1 locked),
    the section frame's base turn per N mm falls as the cover thickens (a stiffer beam on the same
    slot walls) and has no jump or sawtooth: at every point of the 0.2 mm sweep, halving the step
    takes the second difference down to less than half, as a smooth curve's (a jump would leave it
    at half or more)."""
    doc = mst.load(ROOT / "configs" / "mohammadi2021-forward.yaml")
    g, m = doc.geometry(), doc.material

    def turns(steps: int) -> np.ndarray:
        covers = np.linspace(0.8, 3.0, steps)
        return np.array([locked_base_turn_rad_per_Nmm(replace(g, housing=replace(g.housing, cover_mm=float(c))), m)
                         for c in covers])  # fmt: skip

    coarse, fine = turns(12), turns(23)  # steps of 0.2 and 0.1 mm: coarse point i is fine point 2i
    assert np.all(np.diff(fine) < 0.0)
    at_coarse = np.abs(np.diff(coarse, 2))  # centred on coarse points 1 to 10
    at_fine = np.abs(np.diff(fine, 2))[1::2]  # centred on fine points 2 to 20: the same places
    assert np.all(at_fine < 0.5 * at_coarse), at_fine / at_coarse
