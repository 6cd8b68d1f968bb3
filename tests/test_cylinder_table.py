"""The cylinder's field tabulated over (rho, z) (mst_cli/model/cylinder_table.py) against an
independent exact field, magpylib's (value and central differences of it), and against what
the axial symmetry fixes: no transverse field on the axis, a field that turns with the magnet."""

import numpy as np
import pytest

from mst_cli.model import magnet_field as fld
from mst_cli.model.cylinder_table import CylinderFieldTable, rotation_and_left_jacobian

DIAMETER, THICKNESS, REMANENCE = 6.0, 2.0, 1.3  # the bundled sensor's N42 disc
Z_RANGE = (-16.0, -4.0)  # the chip 3 mm or more below the magnet's face
RHO_MAX = 24.0


@pytest.fixture(scope="module")
def table():
    return CylinderFieldTable.build(DIAMETER, THICKNESS, REMANENCE, RHO_MAX, Z_RANGE, 0.1)


def points(rng, m: int) -> tuple[np.ndarray, np.ndarray]:
    """(q (m, 3), rotation vectors (m, 3)): chips inside the table's domain whatever the turn."""
    rho = RHO_MAX * 0.9 * np.sqrt(rng.uniform(0.0, 1.0, m))
    a = rng.uniform(0.0, 2 * np.pi, m)
    own = np.array([rho * np.cos(a), rho * np.sin(a), rng.uniform(Z_RANGE[0] + 1.0, Z_RANGE[1] - 1.0, m)])
    rot = rng.normal(0.0, 0.05, (m, 3))
    R = rotation_and_left_jacobian(rot.T)[0]
    return np.einsum("ijm,jm->mi", R, own), rot  # q = R own: seen from the turned magnet, own


def test_the_table_is_magpylibs_field_far_below_the_noise(table):
    q, rot = points(np.random.default_rng(1), 3000)
    B, _, _ = table.field_T(q.T, rot.T, gradient=False)
    exact = fld.cylinder_pose_B_T(q, DIAMETER, THICKNESS, REMANENCE, rot)
    assert np.max(np.abs(B.T - exact)) < 1e-8  # 10 nT: 1/200 of the chips' 2 uT noise, 1/50 of 0.5 uT
    # on the axis of an upright magnet: no transverse field, and B_z the axial closed form
    z = np.linspace(-15.0, -4.5, 7)
    on_axis = np.array([np.zeros_like(z), np.zeros_like(z), z])
    B0, G0, _ = table.field_T(on_axis, np.zeros((3, 7)))
    assert np.all(B0[:2] == 0.0)
    axial = fld.axial_Bz_T(-z - 0.5 * THICKNESS, 0.5 * DIAMETER, THICKNESS, REMANENCE)
    np.testing.assert_allclose(B0[2], axial, rtol=1e-7)
    # div B = 0 there: dBx/dx + dBy/dy = -dBz/dz
    np.testing.assert_allclose(G0[0, 0] + G0[1, 1], -G0[2, 2], rtol=1e-5)


def test_the_gradients_are_magpylibs_central_differences(table):
    q, rot = points(np.random.default_rng(2), 400)
    _, dB_dq, dB_drot = table.field_T(q.T, rot.T)
    h = 1e-4
    for k in range(3):
        e = np.zeros(3)
        e[k] = h
        for grad, arg in ((dB_dq, 0), (dB_drot, 1)):
            up = [q + e, rot] if arg == 0 else [q, rot + e]
            down = [q - e, rot] if arg == 0 else [q, rot - e]
            fd = (
                fld.cylinder_pose_B_T(up[0], DIAMETER, THICKNESS, REMANENCE, up[1])
                - fld.cylinder_pose_B_T(down[0], DIAMETER, THICKNESS, REMANENCE, down[1])
            ) / (2 * h)
            scale = np.max(np.abs(fd))
            assert np.max(np.abs(grad[:, k].T - fd)) < 1e-5 * scale


def test_the_rotation_is_rodrigues():
    rng = np.random.default_rng(3)
    phi = rng.normal(0.0, 0.3, (3, 50))
    phi[:, :5] *= 1e-6  # the series near zero
    R, Jl = rotation_and_left_jacobian(phi)
    from scipy.spatial.transform import Rotation

    np.testing.assert_allclose(R.transpose(2, 0, 1), Rotation.from_rotvec(phi.T).as_matrix(), atol=1e-14)
    # the left Jacobian: R(phi + delta) = R(J_l delta) R(phi) to first order
    d = 1e-6 * rng.normal(size=(3, 50))
    moved = Rotation.from_rotvec(phi.T + d.T) * Rotation.from_rotvec(phi.T).inv()
    np.testing.assert_allclose(moved.as_rotvec().T, np.einsum("ijm,jm->im", Jl, d), atol=1e-12)
