"""model.wall_thrust: the top layer's walls' thrust on the cap and the plate under it, and where
it enters the part: the centred press past the lock under the top layer, at no member's lever
under a pull (docs/design.md 4.7). The chain is held to the study's stiffness-method frame and to
the half-walls' closed form in tests/test_cap_plate_thrust.py; the general load past two locks is
held to the whole-part rung in tests/test_counter_turn.py."""

from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

import mst_cli as mst
from mst_cli.model import load_path as lp
from mst_cli.model.mechanics import layer_laws
from mst_cli.model.part_laws import OWN_LEVER, unit_members
from mst_cli.model.stack import Stack
from mst_cli.model.wall_thrust import (
    RIGID_CASES,
    RIGID_SIGNS,
    chain_drop_mm_per_N,
    scene_thrust_mm_per_N,
    thrust_extra_mm_per_N,
)

ROOT = Path(__file__).resolve().parents[1]


@pytest.fixture(scope="module")
def forward():
    doc, _ = mst.designed(ROOT / "configs" / "mohammadi2021-forward.yaml")
    g, m = doc.geometry(), doc.material
    s = lp.member_scene(g, m)
    theta, t, h = (np.array([getattr(c, k) for c in g.layers]) for k in lp.CELL_KEYS)
    return g, m, s, theta, t, h, lp.layer_supports(s, theta, t, h)[1]


def random_top_layers(count: int, seed: int = 0) -> tuple:
    rng = np.random.default_rng(seed)
    theta, t = np.radians(rng.uniform(10.0, 60.0, count)), rng.uniform(0.4, 1.4, count)
    h = 2.0 * t + rng.uniform(0.5, 2.5, count)
    return theta, t, h, rng.uniform(9.0, 14.0, count), rng.uniform(9.0, 14.0, count)


def test_the_four_chains_in_one_call_are_the_four_calls(forward):
    """The batched rigid cases (one call over a leading axis of 4) give each chain as a call of
    its own would, over random top layers (elementwise kernels: to round-off)."""
    s = forward[2]
    layers = random_top_layers(200)
    alone = [chain_drop_mm_per_N(s, *layers, cap, plate) for cap, plate in RIGID_CASES]
    expected = sum(sign * drop for sign, drop in zip(RIGID_SIGNS, alone))
    np.testing.assert_allclose(thrust_extra_mm_per_N(s, *layers), expected, rtol=1e-10, atol=1e-15)


def test_the_thrust_gives_and_vanishes_as_the_members_stiffen(forward):
    """Over random top layers the interaction is a compliance (> 0); with cap and plate both 1e6
    times stiffer (every chain then its half-walls) it falls by more than five orders."""
    s = forward[2]
    layers = random_top_layers(300, seed=1)
    extra = thrust_extra_mm_per_N(s, *layers)
    assert np.all(extra > 0.0)
    stiff = sum(
        sign * chain_drop_mm_per_N(s, *layers, 1e6 * cap, 1e6 * plate)
        for sign, (cap, plate) in zip(RIGID_SIGNS, RIGID_CASES)
    )
    assert np.all(np.abs(stiff) < 1e-5 * extra)


def test_only_the_plate_under_the_top_layer_carries_it(forward):
    """(..., n - 1): the top layer's term on the last plate, 0 on the others, none on one layer;
    a batch of stacks gives each stack's own."""
    _, _, s, theta, t, h, head = forward
    out = scene_thrust_mm_per_N(s, theta, t, h, head)
    assert out.shape == (2,) and out[0] == 0.0
    assert out[1] == pytest.approx(float(thrust_extra_mm_per_N(s, theta[2], t[2], h[2], head[2], head[1])), rel=1e-12)
    assert scene_thrust_mm_per_N(s, theta[:1], t[:1], h[:1], head[:1]).shape == (0,)
    two = scene_thrust_mm_per_N(s, theta[1:], t[1:], h[1:], head[1:])
    assert two[0] == pytest.approx(float(thrust_extra_mm_per_N(s, theta[2], t[2], h[2], head[2], head[1])), rel=1e-12)
    batch = scene_thrust_mm_per_N(
        s, np.stack([theta, theta[::-1]]), np.stack([t, t[::-1]]), np.stack([h, h]), np.stack([head, head[::-1]])
    )
    assert batch[0, 1] == pytest.approx(out[1], rel=1e-12)


def test_the_centred_press_gains_it_past_the_lock_under_the_top_layer_only(forward):
    """The forward part locks bottom first: the thrust adds its compliance to the part's drop
    over regime 3 (layers 1 and 2 locked, the top one open) and nothing over regimes 1 and 2
    (model.load_path.member_band_compliances, the forward model's own sums)."""
    g, m, *_ = forward
    parts = lp.members(g, m)
    thrust = parts.thrust_mm_per_N
    assert thrust[0] == 0.0 and thrust[1] > 0.0
    without = replace(
        parts,
        locked_plates_mm_per_N=tuple(np.subtract(parts.locked_plates_mm_per_N, thrust)),
        two_locked_plates_mm_per_N=tuple(np.subtract(parts.two_locked_plates_mm_per_N, thrust)),
        thrust_mm_per_N=(),
    )
    stack = Stack(layer_laws(g.layers, m, "spring"))
    (_, own, moving), (_, own0, moving0) = (lp.member_band_compliances(stack, p) for p in (parts, without))
    np.testing.assert_allclose(own, own0, rtol=1e-12)
    np.testing.assert_allclose(moving["plates"] - moving0["plates"], [0.0, 0.0, thrust[1]], atol=1e-15)


def test_under_a_pull_it_rides_with_its_layer_at_its_own_lever(forward):
    """model.part_laws.unit_members: past two locks the top layer carries the plate under it less
    the thrust (and the feet's press, model.past_lock) at that plate's lever and both at its own
    (OWN_LEVER), their sum the axial model's; below the lock under it no thrust rides, only the
    press of layer 2's feet on the block of layer 1."""
    g, m, *_ = forward
    parts = lp.members(g, m)
    riding = unit_members(layer_laws(g.layers, m, "spring"), parts, (0, 1, 2))
    thrust, press = parts.thrust_mm_per_N, parts.press_mm_per_N
    assert thrust[0] == 0.0 and thrust[1] > 0.0
    top = riding[2][2]
    assert (pytest.approx(thrust[1] + press[1], rel=1e-12), OWN_LEVER) in top
    assert (pytest.approx(parts.locked_plates_mm_per_N[1] - thrust[1] - press[1], rel=1e-12), 1) in top
    assert all(k is not OWN_LEVER for unit in riding[0] for _, k in unit)
    own = [(c, j) for j, unit in enumerate(riding[1]) for c, k in unit if k is OWN_LEVER]
    assert own == [(pytest.approx(press[0], rel=1e-12), 1)]
