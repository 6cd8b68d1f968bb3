"""Series springs with step-by-step locking against hand-solved cases."""

import numpy as np
import pytest

from mst_cli.model.mechanics.spring import LinearLockingLayer
from mst_cli.model.stack import Stack, series_displacement_mm

# layer A: k 1 N/mm, locks after 1 mm (R 1 N); layer B: k 4, locks after 0.5 mm (R 2 N)
A = LinearLockingLayer(1.0, 1.0, 1000.0)
B = LinearLockingLayer(4.0, 0.5, 2000.0)


def test_hand_solved_two_layer_stack():
    s = Stack((A, B))
    # before any lock: compliance 1/1 + 1/4
    assert s.displacement_mm(0.5) == pytest.approx(0.5 + 0.125)
    assert s.displacement_mm(1.0) == pytest.approx(1.0 + 0.25)
    # between locks: A locked (1 mm + (F-1)/1000), B open
    assert s.displacement_mm(1.5) == pytest.approx(1.0 + 0.5 / 1000 + 1.5 / 4)
    assert s.displacement_mm(2.0) == pytest.approx(1.0 + 1.0 / 1000 + 0.5)
    # past the last lock: both locked
    assert s.displacement_mm(3.0) == pytest.approx(1.0 + 2.0 / 1000 + 0.5 + 1.0 / 2000)
    assert list(s.regime_bounds_N) == [0.0, 1.0, 2.0]
    assert s.local_compliance_mm_per_N(0.2) == pytest.approx(1.25)
    assert s.local_compliance_mm_per_N(1.2) == pytest.approx(1e-3 + 0.25)
    assert s.local_compliance_mm_per_N(5.0) == pytest.approx(1e-3 + 5e-4)


def test_lock_order_follows_force_not_file_order():
    s = Stack((B, A))
    assert list(s.lock_order) == [1, 0]
    assert list(s.regime_bounds_N) == [0.0, 1.0, 2.0]
    assert s.displacement_mm(1.5) == pytest.approx(Stack((A, B)).displacement_mm(1.5))


def test_curve_is_continuous_monotone_and_invertible():
    s = Stack((A, B, LinearLockingLayer(0.3, 0.8, 500.0)))
    F = np.linspace(0, 4 * s.last_lock_force_N, 5001)
    d = s.displacement_mm(F)
    assert np.all(np.diff(d) > 0)
    # continuity: no jump larger than the steepest segment allows
    assert np.max(np.abs(np.diff(d))) <= np.diff(F)[0] * max(1 / 0.3 + 1 / 1 + 1 / 4, 1) + 1e-12
    assert np.allclose(s.force_N(d), F, rtol=1e-12, atol=1e-12)


def test_vectorised_kernel_matches_stack_objects():
    rng = np.random.default_rng(3)
    k, dl = rng.uniform(0.5, 20, (50, 3)), rng.uniform(0.3, 1.5, (50, 3))
    kl = 300 * k
    F = np.linspace(0, 40, 17)
    d = series_displacement_mm(np.broadcast_to(F, (50, 17)), k, dl, kl)
    for i in range(50):
        s = Stack(tuple(LinearLockingLayer(*v) for v in zip(k[i], dl[i], kl[i])))
        assert np.allclose(d[i], s.displacement_mm(F), rtol=1e-13)


def test_extreme_stiffness_ratio_stays_exact():
    soft, hard = LinearLockingLayer(1e-2, 0.5, 1e3), LinearLockingLayer(1e2, 0.5, 1e6)
    s = Stack((soft, hard))
    assert s.displacement_mm(s.regime_bounds_N[1]) == pytest.approx(0.5 + 0.5e-2 / 1e2)
    F = np.geomspace(1e-3, 10 * s.last_lock_force_N, 400)
    assert np.all(np.isfinite(s.displacement_mm(F))) and np.all(np.diff(s.displacement_mm(F)) > 0)


def _compliance_one_segment(stack, force_N):
    """The definition, one force at a time: the secant of d(F) over the knot segment holding F."""
    knots = stack.knots_N
    if force_N >= knots[-1]:
        return stack.locked_compliance_mm_per_N
    i = int(np.searchsorted(knots, force_N, side="right")) - 1
    d = stack.displacement_mm(knots[i : i + 2])
    return float((d[1] - d[0]) / (knots[i + 1] - knots[i]))


@pytest.mark.parametrize("n_layers", [1, 3, 12])
def test_vectorised_compliance_is_the_per_force_definition_bit_for_bit(n_layers):
    from mst_cli.model.mechanics.frame import TabulatedLockingLayer

    rng = np.random.default_rng(n_layers)
    laws = []
    for j in range(n_layers):
        k, dl = rng.uniform(0.5, 20), rng.uniform(0.3, 1.5)
        if j % 2:  # a tabulated (frame-like) law: many knots, softening
            d = np.linspace(0, dl, 9)
            F = k * d * (1 - 0.3 * d / dl)
            laws.append(TabulatedLockingLayer.from_curve(d, F, k, 300 * k))
        else:
            laws.append(LinearLockingLayer(k, dl, 300 * k, 0.7 * k * dl))
    s = Stack(tuple(laws))
    F = np.concatenate([np.linspace(0, 1.3 * s.last_lock_force_N, 997), s.knots_N])  # knots: right-continuous
    got = s.local_compliance_mm_per_N(F)
    assert got.shape == F.shape
    assert [float(c) for c in got] == [_compliance_one_segment(s, float(f)) for f in F]
    assert isinstance(s.local_compliance_mm_per_N(0.5), float)


def test_compliance_is_the_sum_of_the_layer_slopes():
    s = Stack((A, B, LinearLockingLayer(0.3, 0.8, 500.0)))  # locks at 0.24 N, then A (1 N), B (2 N)
    assert s.local_compliance_mm_per_N(np.array([0.1, 0.2])) == pytest.approx([1 + 0.25 + 1 / 0.3] * 2)
    assert s.local_compliance_mm_per_N(0.5) == pytest.approx(1 + 0.25 + 1 / 500, rel=1e-12)
    assert s.local_compliance_mm_per_N(1.5) == pytest.approx(1e-3 + 0.25 + 1 / 500, rel=1e-12)


@pytest.mark.parametrize("n_layers", [1, 3, 12])
def test_curve_interpolated_on_the_knots_is_the_sum_of_the_layer_laws(n_layers):
    """d(F) is linear between the union of the knots, so interpolating there is exact: it
    equals the layers' own laws summed at every force, before and past the last lock."""
    from mst_cli.model.mechanics.frame import TabulatedLockingLayer

    rng = np.random.default_rng(10 + n_layers)
    laws = []
    for j in range(n_layers):
        k, dl = rng.uniform(0.5, 20), rng.uniform(0.3, 1.5)
        if j % 2:
            d = np.linspace(0, dl, 9)
            laws.append(TabulatedLockingLayer.from_curve(d, k * d * (1 - 0.3 * d / dl), k, 300 * k))
        else:
            laws.append(LinearLockingLayer(k, dl, 300 * k, 0.7 * k * dl))
    s = Stack(tuple(laws))
    F = np.concatenate([rng.uniform(0, 2 * s.last_lock_force_N, 2000), s.knots_N, [0.0]])
    direct = sum(law.displacement_mm(F) for law in laws)
    np.testing.assert_allclose(s.displacement_mm(F), direct, rtol=1e-12, atol=1e-15)
