"""The members' pose in section mode (mst_cli/model/member_pose.py): a compliance per regime of
the part, integrated along the load's ray. What is asserted is the integral's own algebra: in
one regime the pose is the figure times the load (a linear member), across the locks it is
continuous with the next regime's slope, and the tangent a linear model reads (``at``) is the
regime's figure. The figures' values come from the whole-part rung (tests/test_section_pose.py)."""

import numpy as np
import pytest

from mst_cli.model.member_pose import MEMBER_POSE_FIGURES, MemberPose

EDGES = (2.0, 5.0, 9.0)


def pose_of(**figures) -> MemberPose:
    values = {k: figures.get(k, (0.0, 0.0, 0.0)) for k in MEMBER_POSE_FIGURES}
    return MemberPose(EDGES, **values)


def test_in_the_first_regime_each_figure_is_a_linear_member():
    p = pose_of(
        drop_mm_per_N=(0.1, 0.0, 0.0),
        side_mm_per_N=(0.01, 0.0, 0.0),
        turn_rad_per_N=(2e-4, 0.0, 0.0),
        slide_mm_per_N=(0.3, 0.0, 0.0),
        turn_per_moment_rad_per_Nmm=(5e-4, 0.0, 0.0),
        turn_per_tangential_rad_per_N=(4e-3, 0.0, 0.0),
    )
    F, rx, x = np.array([0.5, 1.0, 2.0]), 0.2, 3.0
    shift, rotvec = p.pose(F, rx, x)
    np.testing.assert_allclose(shift[:, 2], -0.1 * F)  # a drop is down
    np.testing.assert_allclose(shift[:, 0], 0.01 * F + 0.3 * rx * F)  # the tangential force is rx F
    np.testing.assert_allclose(rotvec[:, 1], 2e-4 * F + 5e-4 * x * F + 4e-3 * rx * F)  # the moment is x F
    np.testing.assert_array_equal(shift[:, 1], 0.0)  # the rung's section is the x-z plane: nothing along y
    np.testing.assert_array_equal(rotvec[:, [0, 2]], 0.0)


def test_across_the_locks_the_pose_is_the_integral_of_each_regimes_figure():
    p = pose_of(slide_mm_per_N=(0.4, 0.2, 0.1))
    F = np.array([1.0, 2.0, 3.5, 5.0, 7.0, 12.0])
    shift, _ = p.pose(F, 1.0, 0.0)
    # by hand: 0.4 to 2 N, 0.2 from 2 to 5 N, 0.1 past 5 N (the last regime runs on past 9 N)
    expected = [0.4, 0.8, 0.8 + 0.3, 0.8 + 0.6, 1.4 + 0.2, 1.4 + 0.7]
    np.testing.assert_allclose(shift[:, 0], expected)
    # continuous at each lock, its slope the next regime's figure just past it
    h = 1e-4
    for edge, slope in zip(EDGES[:2], (0.2, 0.1)):
        below, at, past = (p.pose(np.array([edge + s]), 1.0, 0.0)[0][0, 0] for s in (-h, 0.0, h))
        assert at - below == pytest.approx(h * (0.4 if edge == 2.0 else 0.2))
        assert past - at == pytest.approx(h * slope)


def test_a_linear_models_tangent_is_the_regime_it_reads_in():
    p = pose_of(turn_per_moment_rad_per_Nmm=(3.0, 2.0, 1.0))
    assert [p.at(f)["turn_per_moment_rad_per_Nmm"] for f in (0.0, 1.9, 2.0, 4.0, 8.9, 9.0, 50.0)] == [
        3.0,
        3.0,
        2.0,  # right-continuous at a lock
        2.0,
        1.0,
        1.0,
        1.0,
    ]


def test_every_figure_needs_one_value_per_regime():
    with pytest.raises(ValueError, match="one value per regime"):
        MemberPose(EDGES, *([(0.0, 0.0)] * len(MEMBER_POSE_FIGURES)))


def test_the_gradient_is_the_poses_central_differences():
    p = pose_of(
        drop_mm_per_N=(0.1, 0.05, 0.02),
        side_mm_per_N=(0.01, -0.02, 0.005),
        turn_rad_per_N=(2e-4, 1e-4, -3e-4),
        slide_mm_per_N=(0.3, 0.2, 0.1),
        turn_per_moment_rad_per_Nmm=(5e-4, 3e-4, 1e-4),
        turn_per_tangential_rad_per_N=(4e-3, 2e-3, 1e-3),
    )
    # (Fz, Fx, Fy, x, y) in every regime, each a step's width from a lock
    theta = np.array([[1.0, 0.2, -0.1, 3.0, 1.0], [3.5, -0.7, 0.3, -2.0, 0.0], [12.0, 2.4, 1.0, 5.0, -4.0]])

    def pose(t):
        F = t[:, 0]
        return p.pose(F, t[:, 1] / F, t[:, 3])

    dshift, drot = p.pose_gradient(theta)
    h = 1e-6
    for k in range(5):
        up, down = theta.copy(), theta.copy()
        up[:, k] += h
        down[:, k] -= h
        (su, ru), (sd, rd) = pose(up), pose(down)
        np.testing.assert_allclose(dshift[:, :, k], (su - sd) / (2 * h), atol=1e-8)
        np.testing.assert_allclose(drot[:, :, k], (ru - rd) / (2 * h), atol=1e-8)
