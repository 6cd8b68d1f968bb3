"""The one Cramer-Rao bound (model.load_bound.crb_sigma) every estimator states its 1-sigma with,
checked against what fixes it independently: the closed form of a diagonal Jacobian, and numpy's
inverse of the Fisher information J^T J / sigma^2 one Jacobian at a time."""

import numpy as np
import pytest

from mst_cli.model.load_bound import crb_sigma


def test_a_diagonal_jacobian_gives_the_noise_over_each_slope():
    # J = diag(j): the Fisher information is diag(j^2) / sigma^2, so sigma_i = sigma / |j_i|
    slopes = np.array([2.0, -0.5, 1e-3])
    J = np.vstack([np.diag(slopes), np.zeros((2, 3))])  # two axes that see nothing
    np.testing.assert_allclose(crb_sigma(J, 3.0), 3.0 / np.abs(slopes), rtol=1e-12)


def test_a_batch_agrees_with_numpys_inverse_of_the_fisher_information():
    rng = np.random.default_rng(45)
    J = rng.normal(size=(4, 6, 6, 5)) * np.array([1e-4, 1e-4, 1e-4, 1e-5, 1e-5])  # T/N and T/mm
    noise = rng.uniform(1e-6, 3e-6, size=(4, 6))
    got = crb_sigma(J, noise)
    assert got.shape == (4, 6, 5)
    for idx in np.ndindex(4, 6):
        fisher = J[idx].T @ J[idx] / noise[idx] ** 2
        np.testing.assert_allclose(got[idx], np.sqrt(np.diag(np.linalg.inv(fisher))), rtol=1e-9)


def test_one_jacobian_is_a_batch_of_one():
    J = np.random.default_rng(1).normal(size=(3, 3))
    np.testing.assert_array_equal(crb_sigma(J, 2.0), crb_sigma(J[None], np.array([2.0]))[0])


@pytest.mark.parametrize(
    "J",
    [
        np.array([[1.0, 1.0], [2.0, 2.0]]),  # two unknowns the data move alike
        np.array([[1.0, 0.0], [2.0, 0.0]]),  # one the data do not see
        np.array([[1.0, 1.0], [1.0, 1.0 + 1e-9]]),  # told apart below double precision
        np.array([[np.nan, 1.0], [1.0, 2.0]]),
    ],
)
def test_unknowns_the_data_cannot_tell_apart_have_no_bound(J):
    assert np.all(np.isinf(crb_sigma(J, 1.0)))
    assert np.all(np.isinf(crb_sigma(np.stack([J, np.eye(2)]), 1.0)[0]))
    np.testing.assert_allclose(crb_sigma(np.stack([J, np.eye(2)]), 1.0)[1], [1.0, 1.0])


def test_the_units_of_the_unknowns_do_not_decide_identifiability():
    # the same well-posed problem with one unknown in units 1e8 times smaller: a bound 1e8 times larger
    J = np.array([[1.0, 0.2], [0.3, 1.0], [0.1, 0.1]])
    scaled = J * np.array([1.0, 1e-8])
    np.testing.assert_allclose(crb_sigma(scaled, 1.0), crb_sigma(J, 1.0) * [1.0, 1e8], rtol=1e-9)
