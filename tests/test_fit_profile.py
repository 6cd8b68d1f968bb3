"""The fit's sigma at a corner of its cost (mst_cli.calibration.fit_profile): on a cost whose two
sides are parabolas of known curvature, the profile's sigma is the flat side's, 1 / k_flat."""

import numpy as np
import pytest

from mst_cli.calibration.fit_profile import corner_sigmas

K_STEEP, K_FLAT = 40.0, 4.0


def corner(x):
    """One residual, slope K_STEEP below 0 and K_FLAT above: chi2 = (k x)^2 each side."""
    return np.array([x[0] * (K_STEEP if x[0] < 0 else K_FLAT)])


def test_a_corner_gets_the_flat_sides_sigma_and_a_smooth_cost_keeps_the_jacobians():
    jacobian_sigma = 2.0 / (K_STEEP + K_FLAT)  # the central difference's slope is the sides' mean
    got = corner_sigmas(corner, np.array([0.0]), np.array([[jacobian_sigma**2]]), 1.0, [-10.0], [10.0])
    assert got[0] == pytest.approx(1.0 / K_FLAT, rel=1e-3)  # chi2 rises by 4 at 2 / K_FLAT

    def smooth(x):
        return np.array([K_FLAT * x[0]])

    got = corner_sigmas(smooth, np.array([0.0]), np.array([[1.0 / K_FLAT**2]]), 1.0, [-10.0], [10.0])
    assert got[0] == 1.0 / K_FLAT  # no corner: the Jacobian's sigma, untouched


def test_a_degenerate_partner_is_refitted_along_the_profile():
    """Two parameters, the second free to follow the first: the profile of x0 refits x1, so
    only the part of the cost x1 cannot absorb rises (the corner in x0 alone)."""

    def cost(x):
        return np.array([x[0] * (K_STEEP if x[0] < 0 else K_FLAT), 100.0 * (x[1] - x[0])])

    J = np.array([[0.5 * (K_STEEP + K_FLAT), 0.0], [-100.0, 100.0]])
    cov = np.linalg.inv(J.T @ J)
    got = corner_sigmas(cost, np.zeros(2), cov, 1.0, [-10.0, -10.0], [10.0, 10.0])
    assert got[0] == pytest.approx(1.0 / K_FLAT, rel=1e-3)
