"""The fast two-chip reader (mst_cli/estimation/two_chip_table.py) against what fixes its answers
outside it: the scalar tilt solve and the exact general-load field (mst_cli/model/general_load.py),
the Cramer-Rao bound at the truth (mst_cli/model/load_bound.py), the chi^2 limit of one degree of
freedom, and the sensor's mirror symmetry.

The sensor: configs/mohammadi2021-forward.yaml as printed, spring rung, chips at (0, 0) and
(10, 6) mm (tests/test_shear_reading.py's layout, studies/shear_roundtrip.py's default).
"""

from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

from mst_cli.estimation.shear_reading import CHI2_FLAG
from mst_cli.estimation.two_chip_table import NEWTON_STEPS, TwoChipModel, TwoChipReader
from mst_cli.model.general_load import fd_steps, field_T, loaded_stack
from mst_cli.model.load_bound import crb_sigma, field_jacobian
from mst_cli.model.mechanics.tilt import _residual, member_state, solve_layer_tilt
from mst_cli.model.mechanics.tilt_batch import newton_many, residual_many
from mst_cli.model.member_pose import MemberPose
from mst_cli.sensor.as_printed import as_printed
from mst_cli.sensor.document import load_design_document

ROOT = Path(__file__).resolve().parents[1]
FORWARD = ROOT / "configs" / "mohammadi2021-forward.yaml"
TWO_CHIPS = [(0.0, 0.0), (10.0, 6.0)]
NOISE_T = 0.5e-6
FIELD_BOUND_T = 1e-9  # the vectorised model against the exact field: 1/500 of the chip noise


@pytest.fixture(scope="module")
def stack():
    doc, _ = load_design_document(FORWARD)
    printed = as_printed(doc)
    return loaded_stack(printed.geometry(), printed.material, "spring")


@pytest.fixture(scope="module")
def reader(stack):
    return TwoChipReader(stack, TWO_CHIPS, NOISE_T)


def loads(stack, rng, n: int, force_frac=(0.05, 1.0), ratio=0.3, face_frac=0.6) -> np.ndarray:
    """(n, 5) presses as studies/shear_roundtrip.py draws them: Fz uniform over ``force_frac`` of
    the range (the last lock), the shear up to ``ratio`` of it in a uniform direction, the press
    uniform over ``face_frac`` of the face."""
    g = stack.geometry
    top = max(t.lock_force_N for t in stack.tilt)
    Fz = rng.uniform(*force_frac, n) * top
    r = ratio * np.sqrt(rng.uniform(0.0, 1.0, n))
    a = rng.uniform(0.0, 2 * np.pi, n)
    xy = rng.uniform(-0.5, 0.5, (n, 2)) * face_frac * np.array([g.width_mm, g.depth_mm])
    return np.column_stack([Fz, r * Fz * np.cos(a), r * Fz * np.sin(a), xy])


def exact_fields(stack, theta, chips=TWO_CHIPS) -> np.ndarray:
    return np.array([field_T(stack, t[0], (t[1], t[2]), (t[3], t[4]), chips).ravel() for t in theta])


def test_the_batched_equilibrium_is_the_scalar_one(stack):
    rng = np.random.default_rng(1)
    for law in stack.tilt:
        u = np.column_stack([rng.uniform(-0.1, 1.2, 50), rng.normal(0, 0.03, 50), rng.normal(0, 0.03, 50)])
        u[:5, 1:] = 0.0  # untilted: the closure line does not cross the knots
        target = rng.normal(size=(50, 3))
        r, K = residual_many(law, u, target)
        own = u - member_state(law, target)  # the cover's unit: the layer's own state is the rest
        for i in range(50):
            r1, K1 = _residual(law, own[i], target[i])
            np.testing.assert_allclose(r[i], r1, rtol=1e-12, atol=1e-12 * np.abs(r1).max())
            np.testing.assert_allclose(K[i], K1, rtol=1e-12, atol=1e-12 * np.abs(K1).max())
        F = rng.uniform(0.5, 80.0, 30)
        off = rng.uniform(-15.0, 15.0, (30, 2))
        exact = [solve_layer_tilt(law, F[i], (off[i, 0], off[i, 1])) for i in range(30)]
        ex = np.array([(s.d_mm, s.phi_y_rad, s.phi_x_rad) for s in exact])
        got = newton_many(law, F, off, ex * (1.0 + rng.normal(0.0, 0.003, ex.shape)), 30)
        np.testing.assert_allclose(got, ex, rtol=1e-8, atol=1e-10)


def test_the_layer_tables_read_as_scipy_interpolates_them(reader):
    """The compiled trilinear read against an independent library (scipy's regular-grid linear
    interpolator on the quadrant, the mirror signs applied by hand): values and, inside a cell,
    the gradient by central differences."""
    from scipy.interpolate import RegularGridInterpolator

    rng = np.random.default_rng(11)
    for table in reader.model.tables:
        F = rng.uniform(0.0, table.force_N[-1], 300)
        ox = rng.uniform(-table.x_mm[-1], table.x_mm[-1], 300)
        oy = rng.uniform(-table.y_mm[-1], table.y_mm[-1], 300)
        got, grad = table.read(F, ox, oy)
        interp = RegularGridInterpolator((table.force_N, table.x_mm, table.y_mm), table.state)
        want = interp(np.column_stack([F, np.abs(ox), np.abs(oy)]))
        want[:, 1] *= np.sign(ox)
        want[:, 2] *= np.sign(oy)
        np.testing.assert_allclose(got, want, rtol=1e-12, atol=1e-12 * np.abs(table.state).max())
        h = 1e-6  # N and mm: far inside a cell (a random load this near a node is a chance of 1e-5)
        for a in range(3):
            args_lo, args_hi = [F, ox, oy], [F, ox, oy]
            args_lo[a], args_hi[a] = args_lo[a] - h, args_hi[a] + h
            fd = (table.at(*args_hi) - table.at(*args_lo)) / (2 * h)
            np.testing.assert_allclose(grad[:, :, a], fd, rtol=1e-5, atol=1e-6 * np.abs(fd).max())


def test_the_vectorised_model_is_the_exact_field(stack, reader):
    rng = np.random.default_rng(2)
    model = reader.model
    theta = loads(stack, rng, 200, (0.02, 1.5), ratio=model.ratio_max, face_frac=1.0)  # the tables' whole range
    exact = exact_fields(stack, theta)
    assert np.max(np.abs(model.fields_T(theta, NEWTON_STEPS) - exact)) < FIELD_BOUND_T
    # the tangent Jacobian is the exact model's central differences
    t = theta[:20]
    B, S = reader.exact(t)
    J = model.jacobian_T(t, B, S)
    J_exact = np.array([field_jacobian(stack, x, TWO_CHIPS) for x in t])
    assert np.max(np.abs(J - J_exact)) < 1e-3 * np.max(np.abs(J_exact))


def assert_jacobian_is_central_differences(model, theta) -> None:
    """The chained Jacobian of the tables' model against its central differences (steps well
    inside a cell), every unknown."""
    J = model.table_jacobian_T(theta, None, None)
    h = 1e-2 * fd_steps(theta)
    for i in range(5):
        up, down = theta.copy(), theta.copy()
        up[:, i] += h[:, i]
        down[:, i] -= h[:, i]
        fd = (model.fields_of(up, model.states(up), False) - model.fields_of(down, model.states(down), False)) / (
            2 * h[:, i, None]
        )
        assert np.max(np.abs(J[:, :, i] - fd)) < 1e-4 * np.max(np.abs(fd)), i


def test_the_tables_model_and_its_jacobian(stack, reader):
    rng = np.random.default_rng(12)
    model = reader.model
    theta = loads(stack, rng, 200, (0.02, 1.5), ratio=model.ratio_max, face_frac=1.0)  # the tables' whole range
    states = model.states(theta)
    # the field table over every pose the tables give: the exact (magpylib's) field
    assert np.max(np.abs(model.fields_of(theta, states, exact=False) - model.fields_of(theta, states))) < FIELD_BOUND_T
    assert_jacobian_is_central_differences(model, theta)


def test_the_members_pose_of_section_mode_is_in_the_chained_jacobian(stack, reader):
    """model.load_path: section adds the whole-part rung's members to the pose, linear in the load
    per regime (figures of the rung's size, made up here: what is asserted is the chain rule)."""
    edges = tuple(sorted(t.lock_force_N for t in stack.tilt))
    figures = {
        "drop_mm_per_N": (0.01, 0.008, 0.006),
        "side_mm_per_N": (0.002, -0.001, 0.001),
        "turn_rad_per_N": (2e-4, 1e-4, -1e-4),
        "slide_mm_per_N": (0.01, 0.02, 0.005),
        "turn_per_moment_rad_per_Nmm": (5e-5, 3e-5, 1e-5),
        "turn_per_tangential_rad_per_N": (1e-3, 5e-4, 2e-4),
    }
    section = replace(stack, members_pose=MemberPose(edges, **figures))
    model = TwoChipModel(section, TWO_CHIPS, reader.model.tables, reader.model.ratio_max)
    theta = loads(stack, np.random.default_rng(13), 60, (0.02, 1.5), ratio=model.ratio_max, face_frac=1.0)
    theta = theta[np.min(np.abs(theta[:, :1] - np.array(edges)[None]), axis=1) > 0.05]  # off the knots
    B = model.fields_of(theta, model.states(theta), False)
    assert np.max(np.abs(B - reader.model.fields_of(theta, reader.model.states(theta), False))) > 10 * NOISE_T
    assert_jacobian_is_central_differences(model, theta)


def test_noise_free_readings_give_the_load_back(stack, reader):
    theta = loads(stack, np.random.default_rng(3), 20)
    B = exact_fields(stack, theta).reshape(20, 2, 3)
    for every_start in (True, False):
        est = reader.estimate(B, every_start)
        assert not np.any(est.flag == "no_fit") and np.all(est.chi2 < 1e-2)
        # within a hundredth of the noise's spread of every unknown
        assert np.all(np.abs(est.theta - theta) < 0.01 * est.sigma), np.abs(est.theta - theta) / est.sigma


def test_noisy_readings_meet_the_targets_and_the_bound(stack, reader):
    rng = np.random.default_rng(4)
    theta = loads(stack, rng, 150)
    B = exact_fields(stack, theta) + rng.normal(0.0, NOISE_T, (150, 6))
    est = reader.estimate(B)
    err = est.theta - theta
    assert np.median(np.abs(err[:, 0]) / theta[:, 0]) <= 0.03  # normal force <= 3 % median
    assert np.median(np.hypot(err[:, 3], err[:, 4])) <= 0.5  # position <= 0.5 mm median
    crb = np.array([crb_sigma(field_jacobian(stack, t, TWO_CHIPS), NOISE_T) for t in theta])
    # an efficient unbiased estimator's error is Gaussian with the bound's sigma: its median |error|
    # is 0.674 sigma; 150 draws put that ratio within ~10 % (1 SE) of 1. (The mean square is no
    # test: at 0.5 uT the model's curvature puts a few chi^2 minima 3 to 4 sigma off; the exact
    # reader's fit lands on the same points wherever it reaches as low a chi^2.)
    ratio = np.median(np.abs(err) / crb, axis=0) / 0.6745
    assert np.all((ratio > 0.7) & (ratio < 1.3)), ratio
    assert np.mean(est.flag == "no_fit") < 0.02  # p = 0.001 each where the model holds


def test_a_reading_no_load_explains_is_flagged(stack, reader):
    rng = np.random.default_rng(5)
    earth = np.tile([20e-6, 0.0, -45e-6], 2)  # the magnet absent: the earth's field at both chips
    noise = rng.uniform(-3e-3, 3e-3, (5, 6))  # anything within the chips' range
    est = reader.estimate(np.vstack([earth, noise]))
    assert list(est.flag) == ["no_fit"] * 6 and np.all(est.chi2 > CHI2_FLAG[1])
    # 10 sigma along the one direction of the six numbers no load moves (the left null space)
    theta = (20.0, -3.0, 2.0, -4.0, 2.0)
    u = np.linalg.svd(field_jacobian(stack, theta, TWO_CHIPS))[0][:, -1]
    clean = exact_fields(stack, [theta])[0]
    est = reader.estimate(np.vstack([clean, clean + 10 * NOISE_T * u]))
    assert est.flag[0] == "ok" and est.flag[1] == "no_fit"


def test_mirrored_readings_give_mirrored_loads(stack, reader):
    mirrored_chips = [(-cx, cy) for cx, cy in TWO_CHIPS]
    load_flip = np.array([1.0, -1.0, 1.0, -1.0, 1.0])  # (Fz, Fx, Fy, x, y) mirrored in x
    field_flip = np.tile([-1.0, 1.0, 1.0], 2)  # (Bx, By, Bz) at each mirrored chip
    theta = loads(stack, np.random.default_rng(6), 10)
    B = exact_fields(stack, theta)
    # the physics: the exact model is mirror symmetric
    mirrored = exact_fields(stack, theta[:2] * load_flip, mirrored_chips)
    np.testing.assert_allclose(mirrored, B[:2] * field_flip, rtol=1e-9, atol=1e-15)
    noisy = B + np.random.default_rng(7).normal(0.0, NOISE_T, B.shape)
    model = TwoChipModel(stack, mirrored_chips, reader.model.tables, reader.model.ratio_max)
    a = reader.estimate(noisy)
    b = TwoChipReader(stack, mirrored_chips, NOISE_T, model=model).estimate(noisy * field_flip)
    assert np.all(np.abs(b.theta - a.theta * load_flip) <= 0.01 * a.sigma)
    assert list(a.flag) == list(b.flag)


def test_the_polish_is_the_exact_readers_fit_from_the_fast_one(stack, reader):
    theta = loads(stack, np.random.default_rng(8), 3)
    B = exact_fields(stack, theta) + np.random.default_rng(9).normal(0.0, NOISE_T, (3, 6))
    fast = reader.estimate(B)
    polished = reader.polish(B, fast)
    # the fast fit is the exact model's minimum already: the exact fit stays there
    assert np.all(polished.chi2 <= fast.chi2 + 1e-3)
    assert np.all(np.abs(polished.theta - fast.theta) <= 0.05 * fast.sigma)
    np.testing.assert_allclose(polished.sigma, fast.sigma, rtol=1e-2)
