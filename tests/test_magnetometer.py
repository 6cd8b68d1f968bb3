"""MLX90393 setting choice against the datasheet table (Melexis MLX90393 datasheet Rev 011, Table 17)."""

import csv
from pathlib import Path

import numpy as np
import pytest

from mst_cli.model import chip as mlx

SHARED = Path(__file__).resolve().parents[2] / "shared" / "reference" / "mlx90393.csv"


def test_packaged_table_is_the_reference_table():
    table = mlx.settings_table()
    assert len(table) == 32
    if SHARED.exists():
        rows = list(csv.DictReader(l for l in SHARED.read_text().splitlines() if not l.startswith("#")))
        ref = {(int(r["gain_sel"]), int(r["res"])): float(r["z_uT_per_lsb"]) for r in rows}
        assert {(s.gain_sel, s.res): s.z_uT_per_lsb for s in table} == ref


def test_small_field_gets_the_finest_setting():
    s = mlx.choose_setting(0.0, 1e-3)
    assert (s.gain_sel, s.res, s.z_uT_per_lsb) == (7, 0, 0.242)
    # range of RES 0 is +-2^15 LSB: 32768 * 0.242 uT = 7.93 mT
    assert s.z_range_T == pytest.approx(32768 * 0.242e-6)


def test_larger_field_gets_the_finest_setting_that_holds_it():
    B = 20e-3
    s = mlx.choose_setting(0.0, B, margin=1.0)
    assert s.z_range_T >= B
    finer = [t for t in mlx.settings_table() if t.z_uT_per_lsb < s.z_uT_per_lsb]
    assert all(t.z_range_T < B or t.xy_range_T < 0 for t in finer)


def test_saturation_is_refused():
    assert mlx.choose_setting(0.0, 55e-3) is None
    assert all(s.z_range_T <= mlx.SATURATION_T for s in mlx.settings_table())


def test_quantisation_and_resolution():
    s = mlx.choose_setting(0.0, 1e-3)
    assert mlx.quantise_lsb(np.array([0.242e-6 * 10.4]), s.z_uT_per_lsb)[0] == 10
    assert mlx.field_resolution_T(s, noise_uT_rms=2.0) == pytest.approx(2e-6)
    assert mlx.field_resolution_T(s, noise_uT_rms=0.0) == pytest.approx(0.242e-6)
