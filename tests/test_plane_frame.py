"""The linear plane frame (model.plane_frame) against beam formulas solved by hand and against
rung L1's corotational element linearised at rest."""

from __future__ import annotations

import math

import numpy as np
import pytest

from mst_cli.model.mechanics.frame import _element_forces
from mst_cli.model.plane_frame import Frame, element_stiffness, element_stiffnesses

EI, KGA, EA = 120.0, 800.0, 1e7  # N mm^2, N, N (axially near rigid)


@pytest.mark.parametrize("angle_deg", [0.0, 30.0, 90.0, 137.0])
def test_a_cantilever_deflects_as_timoshenko_says_whichever_way_it_points(angle_deg):
    """A cantilever L long, a tip load P across it: P L^3 / 3EI + P L / kGA across (plus P along
    it stretching nothing), and the tip turns P L^2 / 2EI, along any direction in the plane."""
    L, P = 7.0, 2.0
    c, s = math.cos(math.radians(angle_deg)), math.sin(math.radians(angle_deg))
    f = Frame(tie_N_per_mm=1e9)
    root, tip = f.node(0.0, 0.0), f.node(L * c, L * s)
    f.beam(root, tip, EA, EI, KGA)
    f.hold(root)
    u = f.solve({3 * tip: -P * s, 3 * tip + 1: P * c})  # P across the beam, counter-clockwise of it
    across, along = -u[3 * tip] * s + u[3 * tip + 1] * c, u[3 * tip] * c + u[3 * tip + 1] * s
    assert across == pytest.approx(P * L**3 / (3 * EI) + P * L / KGA, rel=1e-9)
    assert abs(along) < 1e-12
    assert u[3 * tip + 2] == pytest.approx(P * L**2 / (2 * EI), rel=1e-9)


def test_a_portal_frame_sways_as_slope_deflection_gives():
    """Two columns h tall (EI_c) on held feet, a beam L long (EI_b) across their tops, a force F
    at the beam's level: the sway F h^2 (2a + 3b) / (12 a (a + 6b)), a = EI_c/h, b = EI_b/L (slope
    deflection, both joints turning alike); a rigid beam gives F h^3 / 24 EI_c (two guided
    columns), a limp one F h^3 / 6 EI_c (two cantilevers)."""
    h, L, F, EI_c, stiff = 5.0, 12.0, 1.0, 80.0, 1e9

    def sway(EI_b: float) -> float:
        f = Frame(tie_N_per_mm=stiff)
        feet = [f.node(x, 0.0) for x in (0.0, L)]
        tops = [f.node(x, h) for x in (0.0, L)]
        for foot, top in zip(feet, tops):
            f.beam(foot, top, stiff, EI_c, math.inf)
            f.hold(foot)
        f.beam(tops[0], tops[1], stiff, EI_b, math.inf)
        return f.solve({3 * tops[0]: F})[3 * tops[0]]

    a = EI_c / h
    for EI_b in (10.0, 80.0, 500.0):
        b = EI_b / L
        assert sway(EI_b) == pytest.approx(F * h * h * (2 * a + 3 * b) / (12 * a * (a + 6 * b)), rel=1e-6)
    assert sway(1e9) == pytest.approx(F * h**3 / (24 * EI_c), rel=1e-5)
    assert sway(1e-9) == pytest.approx(F * h**3 / (6 * EI_c), rel=1e-5)


def test_a_spring_between_two_nodes_adds_its_turn_and_nothing_else():
    """A cantilever on a rotational spring k at its root: a tip load P adds P L^2 / k to the tip's
    deflection; the two nodes the spring joins do not part."""
    L, P, k = 4.0, 1.0, 50.0
    f = Frame(tie_N_per_mm=1e12)
    ground, root, tip = f.node(0.0, 0.0), f.node(0.0, 0.0), f.node(L, 0.0)
    f.hold(ground)
    f.spring(ground, root, k)
    f.beam(root, tip, EA, EI, math.inf)
    u = f.solve({3 * tip + 1: P})
    assert u[3 * tip + 1] == pytest.approx(P * L**3 / (3 * EI) + P * L * L / k, rel=1e-9)
    assert abs(u[3 * root]) + abs(u[3 * root + 1]) < 1e-9


def test_the_element_is_rung_l1s_corotational_one_at_rest():
    """Rung L1's corotational Timoshenko element (model.mechanics.frame), its tangent at zero
    displacement, is the same linear element, written independently."""
    rng = np.random.default_rng(3)
    for _ in range(4):
        X = rng.normal(size=(2, 2))
        dx = X[1] - X[0]
        L, beta = float(np.hypot(*dx)), float(np.arctan2(dx[1], dx[0]))
        EA_, EI_, kGA_ = rng.uniform(1.0, 10.0, 3)
        phi = 12.0 * EI_ / (kGA_ * L * L)
        _, K = _element_forces(X, np.zeros((2, 3)), np.array([L]), np.array([beta]), EA_, EI_, phi)
        np.testing.assert_allclose(element_stiffness(X[0], X[1], EA_, EI_, kGA_), K[0], rtol=1e-10, atol=1e-12)


def test_the_batched_elements_are_the_single_ones_and_symmetric():
    rng = np.random.default_rng(5)
    a, b = rng.normal(size=(5, 2)), rng.normal(size=(5, 2))
    EA_, EI_, kGA_ = rng.uniform(1, 10, 5), rng.uniform(1, 10, 5), np.array([1.0, 2.0, math.inf, 4.0, 5.0])
    batch = element_stiffnesses(a, b, EA_, EI_, kGA_)
    for i in range(5):
        np.testing.assert_allclose(batch[i], element_stiffness(a[i], b[i], EA_[i], EI_[i], kGA_[i]), rtol=1e-12)
        np.testing.assert_allclose(batch[i], batch[i].T, atol=1e-12)
