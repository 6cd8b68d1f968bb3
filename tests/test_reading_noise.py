"""The noise a reader states its 1-sigma with (issue 45, item 6): the chip's noise its load test
logged at rest (calibration.json's ``zero.rest_noise_uT``, the ``zero:`` line's) when the
calibration logged one, not the design's default; the stated 1-sigma scales with it and covers
the error it claims to (about 68 % of |error| within 1 sigma, for Gaussian noise)."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from mst_cli.calibration.calibration_json import sha256_text
from mst_cli.calibration.loadtest import parse_readings
from mst_cli.errors import InputError
from mst_cli.readout.reading import ForceReader
from mst_cli.sensor.as_printed import CALIBRATION_JSON
from mst_cli.sensor.document import load_design_document

FORWARD = Path(__file__).resolve().parents[1] / "configs" / "mohammadi2021-forward.yaml"


def calibrated(d: Path, zero: dict | None) -> ForceReader:
    """The forward design's reader with a matching calibration.json whose ``zero`` is ``zero``."""
    d.mkdir(parents=True, exist_ok=True)
    text = FORWARD.read_text()
    (d / "model.yaml").write_text(text)
    (d / CALIBRATION_JSON).write_text(json.dumps({"calibrated_yaml_sha256": sha256_text(text), "zero": zero}))
    doc, _ = load_design_document(d / "model.yaml")
    return ForceReader.open(doc, d / "model.yaml", "spring")


def centred_stream(reader: ForceReader, noise_uT: float, n: int, seed: int) -> tuple[np.ndarray, str]:
    """(the true forces, a readings file's text): centred presses over the middle of the range,
    each axis with Gaussian noise ``noise_uT``, the field the reader's own curve (so the error is
    the noise's alone)."""
    imap = reader.inverse_map
    rng = np.random.default_rng(seed)
    F = rng.uniform(0.1, 0.9, n) * float(imap.force_N[-1])
    Bz = np.interp(F, imap.force_N, imap.B_abs_T) * 1e6
    B = np.column_stack([np.zeros(n), np.zeros(n), Bz]) + rng.normal(0.0, noise_uT, (n, 3))
    return F, "Bx_uT,By_uT,Bz_uT\n" + "\n".join(f"{x:.5f},{y:.5f},{z:.5f}" for x, y, z in B) + "\n"


def test_the_reader_takes_the_noise_logged_at_rest_not_the_designs(tmp_path):
    design = calibrated(tmp_path / "none", None)
    lsb_uT = 0.242  # the forward design's chip setting (GAIN_SEL 7, RES 0): z's LSB
    assert design.inverse_map.field_resolution_T == pytest.approx(2e-6)  # the design's 2 uT
    for noise_uT in (0.6, 1.2, 5.0):
        got = calibrated(tmp_path / f"n{noise_uT}", {"rest_noise_uT": noise_uT})
        assert got.inverse_map.field_resolution_T == pytest.approx(1e-6 * noise_uT)
    # below one LSB the chip's resolution is its LSB, whatever the log says
    assert calibrated(tmp_path / "low", {"rest_noise_uT": 0.05}).inverse_map.field_resolution_T == pytest.approx(
        1e-6 * lsb_uT
    )


def test_the_stated_sigma_scales_with_the_noise_logged_at_rest(tmp_path):
    quiet = calibrated(tmp_path / "quiet", {"rest_noise_uT": 0.6})
    loud = calibrated(tmp_path / "loud", {"rest_noise_uT": 1.8})
    _, text = centred_stream(quiet, 0.6, 200, 1)
    a = quiet.read(parse_readings(text, "r.csv", need_force=False))
    b = loud.read(parse_readings(text, "r.csv", need_force=False))
    ok = (a.flag == "ok") & (b.flag == "ok")
    assert ok.sum() > 190
    # the same readings: the same forces, their 1-sigma three times as wide (linear in the noise)
    np.testing.assert_allclose(b.force_N[ok], a.force_N[ok])
    ratio = b.branches.uncertainty_N[ok] / a.branches.uncertainty_N[ok]
    np.testing.assert_allclose(ratio, 3.0, rtol=1e-9)


@pytest.mark.parametrize("noise_uT", [0.6, 2.5])
def test_the_stated_sigma_covers_its_share_of_the_error(tmp_path, noise_uT):
    reader = calibrated(tmp_path, {"rest_noise_uT": noise_uT})
    n = 4000
    F_true, text = centred_stream(reader, noise_uT, n, 7)
    got = reader.read(parse_readings(text, "r.csv", need_force=False))
    ok = got.flag == "ok"
    assert ok.sum() > 0.98 * n
    inside = np.abs(got.force_N[ok] - F_true[ok]) < got.branches.uncertainty_N[ok]
    # Gaussian noise: 68.3 % within 1 sigma; 4 binomial sigmas of 4,000 readings is 3 %
    assert abs(inside.mean() - 0.683) < 0.03, inside.mean()


def test_a_logged_noise_that_is_not_a_noise_is_refused_naming_the_key(tmp_path):
    with pytest.raises(InputError, match="zero.rest_noise_uT"):
        calibrated(tmp_path, {"rest_noise_uT": -1.0})
