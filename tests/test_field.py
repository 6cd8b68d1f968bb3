"""Field models against magpylib (an independent library) and the reference table."""

import magpylib as magpy
import numpy as np
import pytest

from mst_cli.model.assembly import Magnet
from mst_cli.model.magnet_field import axial_Bz_T, axial_dBz_dz_T_per_mm, choose_field_model, field_at_chip_T

MAG = Magnet(6.0, 2.0, 1.3)


def magpylib_on_axis_T(z_mm):
    """magpylib's object API: magnet centred at the origin, observers below the lower face."""
    cyl = magpy.magnet.Cylinder(polarization=(0, 0, 1.3), dimension=(6e-3, 2e-3))
    obs = np.column_stack([np.zeros_like(z_mm), np.zeros_like(z_mm), -(z_mm + 1.0)]) * 1e-3
    return cyl.getB(obs)[:, 2]


def test_axial_equals_magpylib_on_axis():
    z = np.geomspace(0.05, 60, 200)
    assert np.allclose(axial_Bz_T(z, 3.0, 2.0, 1.3), magpylib_on_axis_T(z), rtol=1e-9, atol=0)


def test_reference_table_is_reproduced():
    # docs/design.md section 8: Bz of a 6 x 2 mm disc, Br 1.3 T, on the axis
    z = [1, 2, 3, 4, 5, 6, 8, 10, 12, 15, 20]
    table_mT = [254.07, 159.44, 97.75, 61.38, 40.07, 27.24, 13.97, 8.006, 4.979, 2.732, 1.231]
    got = axial_Bz_T(np.array(z, float), 3.0, 2.0, 1.3) * 1e3
    assert np.allclose(got, table_mT, rtol=6e-4)


def test_axial_gradient_is_the_derivative():
    z = np.linspace(2, 20, 37)
    fd = (axial_Bz_T(z + 1e-5, 3, 2, 1.3) - axial_Bz_T(z - 1e-5, 3, 2, 1.3)) / 2e-5
    assert np.allclose(axial_dBz_dz_T_per_mm(z, 3, 2, 1.3), fd, rtol=1e-6)


@pytest.mark.parametrize("gap_mm,excess", [(4, 0.52), (6, 0.25), (10, 0.10), (15, 0.05)])
def test_dipole_overestimates_by_the_documented_amount(gap_mm, excess):
    # docs/design.md section 4: +52 % at 4 mm, +25 % at 6, +10 % at 10, +5 % at 15 from the face
    dip = field_at_chip_T(np.array([gap_mm]), MAG, "dipole")[0, 2]
    exact = field_at_chip_T(np.array([gap_mm]), MAG, "axial")[0, 2]
    assert dip / exact - 1 == pytest.approx(excess, abs=0.01)


def test_dipole_converges_to_exact_models_far_away():
    """The multipole correction to a dipole falls like (size / distance)^2."""
    gaps = np.array([20.0, 50.0, 200.0, 800.0])
    r = gaps + 1.0  # distance from the magnet's centre
    for off, tilt in [((0, 0), 0), ((2.0, -1.0), 0), ((1.5, 0.5), 7.0)]:
        dip = field_at_chip_T(gaps, MAG, "dipole", off, tilt)
        cyl = field_at_chip_T(gaps, MAG, "cylinder", off, tilt)
        err = np.linalg.norm(dip - cyl, axis=1) / np.linalg.norm(cyl, axis=1)
        assert np.all(np.diff(err) < 0)
        assert err[3] * r[3] ** 2 == pytest.approx(err[2] * r[2] ** 2, rel=0.02)


def test_cylinder_off_axis_and_tilted_equals_magpylib_objects():
    cyl = magpy.magnet.Cylinder(polarization=(0, 0, 1.3), dimension=(6e-3, 2e-3))
    cyl.rotate_from_angax(9.0, "y", anchor=None)
    gaps = np.array([5.0, 9.0])
    obs = np.column_stack([np.full(2, 1.2), np.full(2, -0.7), -(gaps + 1.0)]) * 1e-3
    ref = cyl.getB(obs)
    got = field_at_chip_T(gaps, MAG, "cylinder", (1.2, -0.7), 9.0)
    assert np.allclose(got, ref, rtol=1e-12)


def test_model_choice_is_the_cheapest_exact_one():
    assert choose_field_model((0, 0), 0) == "axial"
    assert choose_field_model((0.5, 0), 0) == "cylinder"
    assert choose_field_model((0, 0), 2.0) == "cylinder"
    assert choose_field_model((0, 0), 0, requested="dipole") == "dipole"
    with pytest.raises(ValueError):
        field_at_chip_T(np.array([5.0]), MAG, "axial", (1.0, 0.0))
