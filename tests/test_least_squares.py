"""The estimators' one solver (issue 45): batched Levenberg-Marquardt.

Numbers fixed outside the code under test: a linear model's least-squares answer (numpy's lstsq),
a nonlinear model with a known exact root, and the rows of a batch fitted alone (each row is its
own fit, so the batch must not couple them).
"""

import numpy as np

from mst_cli.estimation.least_squares import levenberg_marquardt

RNG = np.random.default_rng(45)
A = RNG.normal(size=(6, 3))  # a linear model: fields = A theta


def _linear(theta, warm):
    return theta @ A.T, None


def _linear_jacobian(theta, fields, warm):
    return np.broadcast_to(A, (len(theta), *A.shape)).copy()


def _free(theta):
    return theta


def test_a_linear_model_ends_on_the_normal_equations_answer_row_by_row():
    data = RNG.normal(size=(4, 6))
    fit = levenberg_marquardt(_linear, _linear_jacobian, data, np.zeros((4, 3)), 0.1, _free, 50, 1e-10)
    want = np.linalg.lstsq(A, data.T, rcond=None)[0].T
    np.testing.assert_allclose(fit.theta, want, rtol=1e-8, atol=1e-10)
    residual = data - want @ A.T
    np.testing.assert_allclose(fit.chi2, np.sum((residual / 0.1) ** 2, axis=1), rtol=1e-8)


def test_a_batch_is_its_rows_fitted_alone():
    def model(theta, warm):  # exp(a x) + b at three x: a root at the truth
        x = np.array([0.0, 0.5, 1.0])
        return np.exp(theta[:, :1] * x) + theta[:, 1:2], None

    def jacobian(theta, fields, warm):
        x = np.array([0.0, 0.5, 1.0])
        return np.stack([x * np.exp(theta[:, :1] * x), np.ones((len(theta), 3))], axis=-1)

    truth = np.array([[0.3, 1.0], [-1.2, 0.5], [2.0, -3.0]])
    data = model(truth, None)[0]
    start = np.zeros((3, 2))
    batch = levenberg_marquardt(model, jacobian, data, start, 1e-3, _free, 100, 1e-9)
    np.testing.assert_allclose(batch.theta, truth, rtol=1e-6, atol=1e-8)
    for i in range(3):
        alone = levenberg_marquardt(model, jacobian, data[i : i + 1], start[i : i + 1], 1e-3, _free, 100, 1e-9)
        np.testing.assert_array_equal(alone.theta[0], batch.theta[i])


def test_held_unknowns_stay_and_the_clip_bounds_the_free_ones():
    data = (np.array([[1.0, 2.0, -5.0]]) @ A.T).reshape(1, 6)

    def jacobian_free(theta, fields, warm):  # the free columns only
        return np.broadcast_to(A[:, [0, 2]], (len(theta), 6, 2)).copy()

    def clip(theta):  # the third unknown kept at or above -1
        t = theta.copy()
        t[:, 2] = np.maximum(t[:, 2], -1.0)
        return t

    start = np.array([[0.0, 7.0, 0.0]])
    fit = levenberg_marquardt(_linear, jacobian_free, data, start, 1.0, clip, 200, 1e-10, free=(0, 2))
    assert fit.theta[0, 1] == 7.0
    assert fit.theta[0, 2] >= -1.0
    assert fit.chi2[0] > 0.0  # the truth (x2 = -5) is outside the clip and the held x1 is off


def test_a_load_the_model_cannot_answer_is_refused():
    def model(theta, warm):  # no answer past 2
        out = theta @ A.T
        out[theta[:, 0] > 2.0] = np.nan
        return out, None

    data = (np.array([[3.0, 0.0, 0.0]]) @ A.T).reshape(1, 6)
    fit = levenberg_marquardt(model, _linear_jacobian, data, np.zeros((1, 3)), 0.1, _free, 60, 1e-10)
    assert fit.theta[0, 0] <= 2.0
    assert np.isfinite(fit.chi2[0])
