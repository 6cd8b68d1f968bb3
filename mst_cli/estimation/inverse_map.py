"""The inverse map: from a reading |B| back to a force on one model's in-range branch (no load
to the last lock), strictly monotone, with the regime of each entry and the local force
resolution there; readings beyond the ends (by more than three field resolutions) are
flagged, never extrapolated. Pure: no file or terminal I/O.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from mst_cli.errors import CalibrationFailed
from mst_cli.model import chip as mlx
from mst_cli.model.response import Response
from mst_cli.model.response import simulate as run_simulation
from mst_cli.sensor.document import Document

if TYPE_CHECKING:
    from numpy.typing import ArrayLike


FLAGS = ("ok", "above_calibrated", "below_range", "above_range", "saturated")


# above_calibrated: inside the model's range but above the largest force of the load test (the
# force is given: the fitted physics carries it there, but no sample checked it)
END_TOLERANCE_SIGMA = 3.0  # readings within this many field resolutions of an end are clamped to it


@dataclass
class InverseMap:
    """Monotone |B| -> force on one model's in-range branch (no load to the last lock)."""

    force_N: np.ndarray  # ascending, 0 .. last lock force
    B_abs_T: np.ndarray  # strictly ascending
    Bz_T: np.ndarray  # the z component at the same forces (signed)
    edges_N: np.ndarray  # regime edges 0, R_1, ..., R_n
    field_resolution_T: float  # noise or LSB, the larger
    chip_setting: mlx.ChipSetting | None
    calibrated_to_N: float | None = None  # the load test's largest force (None: not calibrated)

    @property
    def n_regimes(self) -> int:
        return len(self.edges_N) - 1

    @property
    def tolerance_T(self) -> float:
        return END_TOLERANCE_SIGMA * self.field_resolution_T

    def regime_of(self, force_N: ArrayLike) -> np.ndarray:
        F = np.asarray(force_N, dtype=float)
        return np.clip(np.searchsorted(self.edges_N, F, side="right"), 1, self.n_regimes)

    def local_resolution_N(self, force_N: ArrayLike | None = None) -> np.ndarray:
        """Force resolution at each grid point (or at given forces): field resolution over the
        smaller of the two neighbouring secant slopes d|B|/dF (the worse side)."""
        dB = np.diff(self.B_abs_T) / np.maximum(np.diff(self.force_N), 1e-300)
        left = np.concatenate([[dB[0]], dB])
        right = np.concatenate([dB, [dB[-1]]])
        res = self.field_resolution_T / np.minimum(left, right)
        if force_N is None:
            return res
        return np.interp(np.asarray(force_N, dtype=float), self.force_N, res)

    def force(
        self, B_abs_T: ArrayLike, saturated: ArrayLike | None = None
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(force_N with NaN where flagged, regime (0 where flagged), flag strings)."""
        B = np.asarray(B_abs_T, dtype=float)
        F = np.interp(B, self.B_abs_T, self.force_N)
        flag = np.full(B.shape, "ok", dtype=object)
        tol = self.tolerance_T
        if self.calibrated_to_N is not None:
            B_cal = float(np.interp(self.calibrated_to_N, self.force_N, self.B_abs_T))
            flag[B > B_cal + tol] = "above_calibrated"
        flag[B < self.B_abs_T[0] - tol] = "below_range"
        flag[B > self.B_abs_T[-1] + tol] = "above_range"
        if saturated is not None:
            flag[np.asarray(saturated, dtype=bool)] = "saturated"
        bad = (flag != "ok") & (flag != "above_calibrated")
        F = np.where(bad, np.nan, F)
        regime = np.where(bad, 0, self.regime_of(np.where(bad, 0.0, F)))
        return F, regime, flag

    def table(self, n: int = 256) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """n entries evenly spaced in |B| from no load to the last lock: (|B|, Bz, F, regime,
        resolution)."""
        B = np.linspace(self.B_abs_T[0], self.B_abs_T[-1], n)
        F = np.interp(B, self.B_abs_T, self.force_N)
        F[0], F[-1] = self.force_N[0], self.force_N[-1]
        Bz = np.interp(F, self.force_N, self.Bz_T)
        return B, Bz, F, self.regime_of(np.minimum(F, self.edges_N[-1] * (1 - 1e-12))), self.local_resolution_N(F)

    def z_code_table(
        self, setting: mlx.ChipSetting, n_max: int = 256
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """Entries evenly spaced in |Z code| at ``setting``, from no load to the last lock:
        (codes, force_N, regime, resolution_N). CalibrationFailed if |Bz| is not monotone in
        force (an off-axis chip far from the axis): no Z-only table can then exist."""
        Bz = np.abs(self.Bz_T)
        if not np.all(np.diff(Bz) > 0):
            raise CalibrationFailed(
                "|Bz| is not strictly increasing with force on this model: a "
                "table indexed by the Z code alone cannot exist"
            )
        lsb = setting.z_uT_per_lsb * 1e-6
        c0 = int(math.ceil(Bz[0] / lsb))
        c1 = int(math.floor(Bz[-1] / lsb))
        if c1 - c0 < 2:
            raise CalibrationFailed(
                f"the field changes by only {c1 - c0} LSB over the whole range at "
                f"GAIN_SEL {setting.gain_sel}, RES {setting.res}"
            )
        codes = np.unique(np.rint(np.linspace(c0, c1, min(n_max, c1 - c0 + 1))).astype(np.int64))
        F = np.interp(codes * lsb, Bz, self.force_N)
        # resolution in force of one field resolution at the chip's z setting
        dBz = np.gradient(Bz, self.force_N)
        res_T = max(self.field_resolution_T, lsb)
        res = res_T / np.maximum(np.interp(F, self.force_N, dBz), 1e-300)
        res = np.maximum(res, self.local_resolution_N(F) * res_T / self.field_resolution_T)
        return codes, F, self.regime_of(np.minimum(F, self.edges_N[-1] * (1 - 1e-12))), res

    @classmethod
    def from_response(cls, resp: Response) -> InverseMap:
        """From a :class:`~mst_cli.model.response.Response` (the same model ``mst simulate`` runs)."""
        keep = resp.in_range
        F = resp.force_N[keep]
        B = resp.B_abs_T[keep]
        Bz = resp.B_T[keep, 2]
        # zero-width regimes and repeated edges: keep the first of equal forces
        F, idx = np.unique(F, return_index=True)
        B, Bz = B[idx], Bz[idx]
        if not np.all(np.diff(B) > 0):
            raise CalibrationFailed(
                "|B| is not strictly increasing with force on this model: no monotone map from reading to force exists"
            )
        edges = np.array([0.0] + [r.force_to_N for r in resp.regimes])
        return cls(
            F,
            B,
            Bz,
            edges,
            float(resp.field_resolution_T) if math.isfinite(resp.field_resolution_T) else 1e-6 * resp.noise_uT_rms,
            resp.chip_setting,
        )


def inverse_map(
    doc: Document, mechanics: str = "spring", field_model: str | None = None, points_per_regime: int = 600
) -> tuple[InverseMap, Response]:
    """The inverse map of a design document, and the response it came from."""
    resp = run_simulation(
        doc.geometry(),
        doc.material,
        mechanics=mechanics,
        field_model=None if field_model in (None, "auto") else field_model,
        noise_uT_rms=doc.noise_uT_rms,
        points_per_regime=points_per_regime,
        whole_part=doc.whole_part,
        section=doc.section_rung,  # model.load_path: section reads what mst simulate states
    )
    return InverseMap.from_response(resp), resp


def field_sigma_T(noise_uT_rms: float, setting: mlx.ChipSetting | None) -> float:
    """Per-sample standard deviation of a |B| reading: chip noise and LSB rounding."""
    lsb = setting.z_uT_per_lsb if setting is not None else 0.0
    return 1e-6 * math.sqrt(noise_uT_rms**2 + lsb**2 / 12.0) if (noise_uT_rms or lsb) else 1e-6


def reading_resolution_T(
    design_T: float, chip: mlx.ChipSetting | None, design_noise_uT: float, measured_uT: float | None
) -> float:
    """The field resolution a reader states its 1-sigma with (the plain read's uncertainty, the
    no-load band, the tables' and the two-chip estimator's noise): the chip's noise its load test
    logged at rest (``measured_uT``: calibration.json's ``zero.rest_noise_uT``) when it logged
    one, else the design's (``design_noise_uT``; the design's resolution ``design_T`` at least),
    and never below one LSB of ``chip``."""
    if measured_uT is not None:
        return mlx.field_resolution_T(chip, measured_uT) if chip is not None else 1e-6 * measured_uT
    return max(design_T, mlx.field_resolution_T(chip, design_noise_uT)) if chip is not None else design_T
