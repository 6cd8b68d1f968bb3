"""The offset reader's solve (`mst read --estimate-offset`): which root it finds and what it flags.

On fields given in closed form, where the roots are known by algebra: a field with one root
gives it back with the covariance of its analytic Jacobian; a field that folds over (two exact
roots) is flagged ambiguous; arctan, from where an undamped Newton step is known to diverge
(|x0| > 1.39), still gives its root. On the bundled design's own tilt rung: a reading no press
can give is flagged, not read as the range's end.
"""

from pathlib import Path

import numpy as np
import pytest

from mst_cli.estimation.offset_reading import OffsetEstimator
from mst_cli.model.general_load import pose_field_T
from mst_cli.model.stack_pose import tilt_laws
from mst_cli.sensor.document import load_design_document

FORWARD = Path(__file__).resolve().parents[1] / "configs" / "mohammadi2021-forward.yaml"
SCALE_T = 1e-5  # the closed-form fields: 10 uT per N and per unit of their offset term
SIGMA_T = 1e-6


class ClosedFormEstimator(OffsetEstimator):
    """The estimator's solve on a field (T) of p = (force N, x mm, y mm) given in closed form:
    noise 1 uT, a 20 x 20 mm face, forces up to 50 N."""

    def __init__(self, field):
        self._field = field
        self.sigma_T, self.force_max_N, self.max_sigma_mm = SIGMA_T, 50.0, 1.0
        self.half_face_mm = np.array([10.0, 10.0])

    def field_T(self, p):
        return self._field(np.asarray(p, dtype=float))


def cubic(p):
    return SCALE_T * np.array([p[0], p[1] ** 3 + p[1], p[2]])


def folded(p):
    return SCALE_T * np.array([p[0], (p[1] - 0.5) ** 2, p[2]])


def arctan(p):
    return SCALE_T * np.array([p[0], np.arctan(p[1]), p[2]])


def test_a_single_root_comes_back_with_its_analytic_covariance():
    est = ClosedFormEstimator(cubic)
    e = est.estimate(cubic(np.array([20.0, 2.0, 1.0])), 12.0, (3.0, -2.0))
    assert e.flag == "ok"
    assert (e.force_N, e.x_mm, e.y_mm) == pytest.approx((20.0, 2.0, 1.0), abs=1e-6)
    # sigma = noise / slope: 1 uT / 10 uT per N, and / (3 x^2 + 1) = 13 times that in x; the
    # forward difference (1e-3 mm) is off by h f'' / (2 f') = 4.6e-4 in x
    assert e.sigma_force_N == pytest.approx(0.1, rel=1e-6)
    assert e.sigma_y_mm == pytest.approx(0.1, rel=1e-6)
    assert e.sigma_x_mm == pytest.approx(0.1 / 13.0, rel=1e-3)


def test_a_field_that_folds_over_is_ambiguous():
    # (x - 0.5)^2 = 4 at x = 2.5 and x = -1.5: the previous press finds one root, the centre the other
    est = ClosedFormEstimator(folded)
    e = est.estimate(folded(np.array([20.0, 2.5, 1.0])), 18.0, (2.0, 1.0))
    assert e.flag == "ambiguous"
    assert np.isnan(e.force_N) and np.isnan(e.x_mm)
    assert e.next_start_mm == pytest.approx((2.5, 1.0), abs=1e-6)  # a stream follows the previous press's root
    # near the fold's far side only one root is within reach of the one start: no doubt raised
    one = est.estimate(folded(np.array([20.0, 2.5, 1.0])), 18.0, (0.3, 0.0))
    assert one.flag == "ok" and one.x_mm == pytest.approx(-1.5, abs=1e-6)


def test_a_step_newton_would_overshoot_is_damped_to_the_root():
    est = ClosedFormEstimator(arctan)
    e = est.estimate(arctan(np.array([20.0, 0.2, 1.0])), 20.0, (2.0, 1.0))
    assert e.flag == "ok"
    assert (e.force_N, e.x_mm, e.y_mm) == pytest.approx((20.0, 0.2, 1.0), abs=1e-6)


@pytest.fixture(scope="module")
def design_reader():
    doc, _ = load_design_document(FORWARD)
    geo, mat = doc.geometry(), doc.material
    laws = tilt_laws(geo, mat, "spring")
    return geo, laws, OffsetEstimator(geo, mat, "spring", 2e-6, 50.0)


def test_a_reading_no_press_gives_is_flagged_and_keeps_its_centred_force(design_reader):
    geo, laws, est = design_reader
    B_top = pose_field_T(geo, laws, np.array([50.0]), (0.0, 0.0))[0]
    B = np.array([[0.0, 0.0, 1.5 * B_top[2]]])  # half as strong again as the range's end on the axis
    r = est.estimate_all(B, np.array([48.0]))
    assert list(r.flag) == ["no_fit"]
    assert r.force_N[0] == 48.0 and np.isnan(r.x_mm[0])
    assert "1 no fit" in r.summary()
