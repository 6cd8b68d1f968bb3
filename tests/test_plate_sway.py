"""The plates' sway (model.plate_sway, general_load.plate_sway_law; docs/design.md 4.7): its walls
carry L0's k_x, its limits, a sweep of the plates' thickness, and the law by regime."""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

import mst_cli as mst
from mst_cli.model import plate_sway as ps
from mst_cli.model.general_load import loaded_stack, plate_sway_law

CONFIGS = Path(__file__).resolve().parents[1] / "configs"
FORWARD = CONFIGS / "mohammadi2021-forward.yaml"


def section(path: Path = FORWARD, **housing):
    doc = mst.load(path)
    g = doc.geometry()
    if housing:
        g = replace(g, housing=replace(g.housing, **housing))
    return g, doc.material, ps.stack_section(g, doc.material)


def test_each_layers_walls_carry_l0s_lateral_stiffness():
    """Scaled by wall_factors, the frame's layer alone between rigid plates (the one above held
    from turning) is L0's 1 / k_x: the factor takes the rigid members' own share out."""
    _, _, sec = section()
    walls = ps.wall_factors(sec)
    n = len(sec.theta_rad)
    for i in range(n):
        others = tuple(j for j in range(n) if j != i)
        slide, _ = ps.frame_pull(sec, others, None, walls, guided=True, roots=False)
        assert slide == pytest.approx(1.0 / sec.k_x_N_per_mm[i], rel=1e-5)  # the solve: about 3e-6


def test_a_plate_between_two_locked_layers_or_rigid_adds_nothing():
    """Between two filled blocks a plate is tied over its whole loaded width: it adds no
    translation; every plate rigid is the reference itself."""
    _, _, sec = section()
    n = len(sec.theta_rad)
    moved = ps.plate_translations_mm_per_N(sec, locked=tuple(range(n)))
    np.testing.assert_allclose(moved, 0.0, atol=1e-7)
    open_ = ps.plate_translations_mm_per_N(sec)
    assert np.all(open_ > 1e-3)  # 0.8 mm plates between open layers: tens of um per newton


def test_the_sway_falls_smoothly_as_the_plates_thicken():
    """Swept over the plates' thickness (0.8 to 2.4 mm, the forward design's layers), every
    regime's sway falls, and its steps shrink in a regular way: no jump, no sawtooth."""
    thick = np.linspace(0.8, 2.4, 9)
    rows = []
    for p in thick:
        _, _, sec = section(plate_mm=float(p))
        rows.append(ps.regime_sway_mm_per_N(sec, (0, 1, 2))[:2])
    c = np.array(rows)  # (9, 2): regimes 1 and 2
    assert np.all(np.diff(c, axis=0) < 0.0)
    ratio = c[1:] / c[:-1]
    assert np.all(np.abs(np.diff(ratio, axis=0)) < 0.05)


def test_the_law_steps_at_the_locks_and_holds_along_y():
    """general_load's plates' law: within each regime the slide per tangential newton is that
    regime's sway (regime_sway_mm_per_N), stepping at the part's lock forces; nothing along y;
    report.json's load_path states the same figures."""
    g, m, sec = section()
    stack = loaded_stack(g, m, "spring", whole_part=True)
    law = plate_sway_law(g, m, stack.tilt)
    locks = np.sort([t.lock_force_N for t in stack.tilt])
    c = ps.regime_sway_mm_per_N(sec, np.argsort([t.lock_force_N for t in stack.tilt]))
    edges = np.concatenate([[0.0], locks, [2.0 * locks[-1]]])
    for r in range(len(c)):
        a, b = edges[r] + 0.25 * (edges[r + 1] - edges[r]), edges[r] + 0.75 * (edges[r + 1] - edges[r])
        U = [law.compliance_mm_per_N(F)[0] * F for F in (a, b)]
        assert (U[1] - U[0]) / (b - a) == pytest.approx(c[r], rel=1e-6)  # the solves: 1e-7 between BLAS threads
    assert np.all(law.integral_y_mm == 0.0)
    assert stack.lateral[-1].integral_x_mm == pytest.approx(law.integral_x_mm, rel=1e-12)
