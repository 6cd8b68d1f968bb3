"""The known printed sensor of the calibration tests and of docs/examples/loadtest.csv (issue 11).

The bundled forward design (configs/mohammadi2021-forward.yaml) printed with known errors
(:data:`TRUTH`): walls 0.05 mm thicker, the TPU's modulus 15 % low, the board 0.3 mm further from
the magnet, a magnet 5 % weak. They are written into the design file's keys by hand, not through
the code under test (mst_cli.sensor.as_printed), and the part is simulated with ``mst simulate``'s
model (the file's ``model.load_path``: by default the whole part, its cap, insert, plates and
cover in series with the layers). Its readings get the MLX90393's noise (2 uT RMS per axis, the
design's ``noise_uT_rms``) and are rounded to the chip's LSB.

The bundled load test is :func:`loadtest_csv` (60 samples, seed 11); ``python
tools/make_examples.py`` writes it.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import yaml

from mst_cli.model import chip as mlx
from mst_cli.model.assembly import Housing
from mst_cli.model.components import grade_remanence_T
from mst_cli.model.response import simulate
from mst_cli.sensor.document import parse_document

ROOT = Path(__file__).resolve().parents[1]
DESIGN = ROOT / "configs" / "mohammadi2021-forward.yaml"
TRUTH = {"modulus_factor": 0.85, "wall_offset_mm": 0.05, "gap_offset_mm": 0.30, "remanence_factor": 0.95}
NOISE_uT = 2.0
LOADTEST_SEED = 11
LOADTEST_SAMPLES = 60


class PrintedSensor:
    """The design with the print errors of TRUTH written into its keys by hand."""

    def __init__(self):
        raw = yaml.safe_load(DESIGN.read_text())
        raw["material"]["youngs_modulus_MPa"] *= TRUTH["modulus_factor"]
        for layer in raw["layers"]:
            layer["t_mm"] += TRUTH["wall_offset_mm"]
        housing = raw.get("housing") or {}  # the design's own air, else the default's
        air_mm = housing.get("chip_clearance_mm", Housing().chip_clearance_mm)
        raw["housing"] = {**housing, "chip_clearance_mm": air_mm + TRUTH["gap_offset_mm"]}
        raw["magnet"]["remanence_T"] = TRUTH["remanence_factor"] * grade_remanence_T(raw["magnet"]["grade"])
        self.doc = parse_document(raw)
        self.resp = simulate(
            self.doc.geometry(), self.doc.material, noise_uT_rms=NOISE_uT, whole_part=self.doc.whole_part
        )
        self.range_N = self.resp.max_force_N
        self.setting = self.resp.chip_setting

    def codes(self, force_N, rng):
        """Raw x, y, z codes at these forces: the model's field + chip noise, rounded to LSB."""
        B = np.stack([np.interp(force_N, self.resp.force_N, self.resp.B_T[:, i]) for i in range(3)], -1)
        B = B + rng.normal(0.0, NOISE_uT * 1e-6, B.shape)
        s = self.setting
        return np.stack(
            [
                mlx.quantise_lsb(B[:, 0], s.xy_uT_per_lsb),
                mlx.quantise_lsb(B[:, 1], s.xy_uT_per_lsb),
                mlx.quantise_lsb(B[:, 2], s.z_uT_per_lsb),
            ],
            -1,
        )

    def csv_uT(self, force_N, codes, with_force=True):
        s = self.setting
        lines = [("force_N," if with_force else "") + "Bx_uT,By_uT,Bz_uT"]
        for f, (x, y, z) in zip(force_N, codes):
            lines.append(
                (f"{f:.4f}," if with_force else "")
                + f"{x * s.xy_uT_per_lsb:.4f},{y * s.xy_uT_per_lsb:.4f},{z * s.z_uT_per_lsb:.4f}"
            )
        return "\n".join(lines) + "\n"

    def load_test(self, seed: int = LOADTEST_SEED, samples: int = LOADTEST_SAMPLES) -> tuple[np.ndarray, np.ndarray]:
        """(forces N, raw codes) of a load test: ``samples`` forces spread over the range, sorted."""
        rng = np.random.default_rng(seed)
        F = np.sort(rng.uniform(0.0, self.range_N, samples))
        return F, self.codes(F, rng)


def loadtest_csv(sensor: PrintedSensor | None = None) -> str:
    """docs/examples/loadtest.csv: the load test of seed 11 in microtesla."""
    sensor = sensor or PrintedSensor()
    return sensor.csv_uT(*sensor.load_test())
