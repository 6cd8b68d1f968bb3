"""studies/cap_plate_thrust.py's frame of the top layer's half cell, held to beam closed forms
(its figures against the rung are the study's, docs/design.md 4.7)."""

from pathlib import Path

import numpy as np
import pytest

import mst_cli as mst
from mst_cli.model import load_path as lp
from mst_cli.model.cell import wall_centreline_length_mm
from studies import cap_plate_thrust as cpt

ROOT = Path(__file__).resolve().parents[1]


@pytest.fixture(scope="module")
def forward():
    doc, _ = mst.designed(ROOT / "configs" / "mohammadi2021-forward.yaml")
    return doc.geometry(), doc.material


def test_with_cap_and_plate_rigid_the_frame_is_its_half_walls(forward):
    """Cap, plate and roots rigid: the press goes down two half-walls in series, each clamped at
    its pad and guided at the hexagon's side vertex, on each side: per side 1/2 N through
    2 (cos^2 theta L^3 (1 + phi) / (12 E'I) + sin^2 theta L / (E'A)), phi = 12 E'I / (kGA L^2).
    The rigid members are RIGID times stiffer, not infinitely: 1e-3 is their share."""
    g, m = forward
    s = lp.member_scene(g, m)
    cell = g.layers[-1]
    theta, t, h = np.radians(cell.theta_deg), cell.t_mm, cell.h_mm
    ED = s.E_prime_MPa * s.depth_mm
    L = float(wall_centreline_length_mm(theta, t, h))
    EI, EA, kGA = ED * t**3 / 12.0, ED * t, 5.0 / 6.0 * s.G_MPa * s.depth_mm * t
    phi = 12.0 * EI / (kGA * L * L)
    half_wall = np.cos(theta) ** 2 * L**3 * (1.0 + phi) / (12.0 * EI) + np.sin(theta) ** 2 * L / EA
    expected_um = 1e3 * 0.5 * 2.0 * half_wall
    for offsets in (True, False):
        assert cpt.frame_drop_um_per_N(g, m, True, True, offsets) == pytest.approx(expected_um, rel=1e-3)


def test_the_walls_thrust_needs_the_offsets(forward):
    """Cap and plate soft together give more than each alone only where the walls meet them off
    their mid-planes: with the offsets the forward design's extra is several times the control's
    (the study: 1.06 against 0.15 um/N; the rung 0.89)."""
    g, m = forward
    with_offsets, control = (cpt.frame_um_per_N(g, m, o) for o in (True, False))
    extra = [f[2] - f[0] - f[1] for f in (with_offsets, control)]
    assert extra[0] > 3.0 * extra[1] > 0.0


@pytest.mark.parametrize("cap_rigid, plate_rigid", [(False, False), (True, False), (False, True), (True, True)])
@pytest.mark.parametrize("offsets", [True, False])
def test_the_chain_is_the_frame(forward, cap_rigid, plate_rigid, offsets):
    """The vectorised chain (flexibility method) and the study's frame (stiffness method, with
    stiff links for the offsets) are one structure: the same drop to 1e-3 (the links' round-off is
    about 1e-4), on the forward design (its feet on the block) and with its top layer's heads moved
    1 mm out (the plate hangs 0.75 mm beyond the block)."""
    g, m = forward
    s = lp.member_scene(g, m)
    theta, t, h = (np.array([getattr(c, k) for c in g.layers]) for k in lp.CELL_KEYS)
    head = lp.layer_supports(s, theta, t, h)[1]
    factors = (cpt.RIGID if cap_rigid else 1.0, cpt.RIGID if plate_rigid else 1.0)
    chain = 1e3 * cpt.chain_drop_mm_per_N(s, theta[-1], t[-1], h[-1], head[-1], head[-2], *factors, offsets)
    frame = cpt.frame_drop_um_per_N(g, m, cap_rigid, plate_rigid, offsets)
    assert float(chain) == pytest.approx(frame, rel=1e-3)
    # the heads moved 1 mm out: the plate hangs beyond the block, in both
    out = float(head[-1]) + 1.0
    hanging = 1e3 * cpt.chain_drop_mm_per_N(s, theta[-1], t[-1], h[-1], out, head[-2], *factors, offsets)
    frame_factors = (cpt.RIGID if rigid else 1.0 for rigid in (cap_rigid, plate_rigid))
    by_frame = cpt.cell_frame_drop_um_per_N(s, theta[-1], t[-1], h[-1], out, head[-2], *frame_factors, offsets)
    assert float(hanging) == pytest.approx(by_frame, rel=1e-3)
    both = 1e3 * cpt.chain_drop_mm_per_N(
        s, theta[-1], t[-1], h[-1], head[-1] + np.array([0.0, 1.0]), head[-2], *factors, offsets
    )
    np.testing.assert_allclose(both, [float(chain), float(hanging)], rtol=1e-12)  # one call over an array


@pytest.mark.parametrize("hang_mm", [0.0, 1.0])
def test_a_stiffer_member_divides_its_part_of_the_chain(forward, hang_mm):
    """The chain scales each member's flexibility by 1 / its factor (the four rigid cases cost one
    chain); the study's frame scales the members' stiffness in its stiffness matrix: the same
    drop to 1e-3 with the cap 2.5 times and the plate 0.4 times as stiff, and the drop between the
    printed chain's and the cap's rigid one."""
    g, m = forward
    s = lp.member_scene(g, m)
    theta, t, h = (np.array([getattr(c, k) for c in g.layers]) for k in lp.CELL_KEYS)
    head = lp.layer_supports(s, theta, t, h)[1]
    top = (s, theta[-1], t[-1], h[-1], float(head[-1]) + hang_mm, head[-2])
    chain = 1e3 * float(cpt.chain_drop_mm_per_N(*top, 2.5, 0.4))
    assert chain == pytest.approx(cpt.cell_frame_drop_um_per_N(*top, 2.5, 0.4), rel=1e-3)
    printed, cap_rigid = (1e3 * float(cpt.chain_drop_mm_per_N(*top, f, 1.0)) for f in (1.0, np.inf))
    stiffer = 1e3 * float(cpt.chain_drop_mm_per_N(*top, 2.5, 1.0))
    assert cap_rigid < stiffer < printed
