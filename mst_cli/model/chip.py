"""MLX90393 magnetometer: gain/resolution choice, quantisation and force resolution.

Resolution table: Melexis MLX90393 datasheet Rev 011, Table 17 (HALLCONF 0xC), shipped as
``data/mlx90393.csv``. Output code ranges: RES 0 and 1 signed +-2^15 LSB, RES 2 +-22000 LSB,
RES 3 +-11000 LSB. The Hall plates saturate physically from 50 mT.

The noise is given only as plots in the datasheet (tens of mG RMS at short conversion
times); it is a parameter here, default 2 uT RMS (20 mG).
"""

from __future__ import annotations

import csv
from dataclasses import dataclass
from functools import lru_cache
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

if TYPE_CHECKING:
    from numpy.typing import ArrayLike

SATURATION_T = 50e-3
CODE_RANGE_LSB = {0: 32768, 1: 32768, 2: 22000, 3: 11000}
DEFAULT_NOISE_uT = 2.0
# beside the model's other data, read as they are (importlib.resources would import zipfile for it)
SETTINGS_CSV = Path(__file__).resolve().parent / "data" / "mlx90393.csv"


@dataclass(frozen=True)
class ChipSetting:
    gain_sel: int
    res: int
    xy_uT_per_lsb: float
    z_uT_per_lsb: float

    @property
    def z_range_T(self) -> float:
        return min(CODE_RANGE_LSB[self.res] * self.z_uT_per_lsb * 1e-6, SATURATION_T)

    @property
    def xy_range_T(self) -> float:
        return min(CODE_RANGE_LSB[self.res] * self.xy_uT_per_lsb * 1e-6, SATURATION_T)


@lru_cache(maxsize=1)
def settings_table() -> tuple[ChipSetting, ...]:
    """Every GAIN_SEL x RES setting, finest z resolution first."""
    text = SETTINGS_CSV.read_text()
    rows = [r for r in csv.DictReader(line for line in text.splitlines() if not line.startswith("#"))]
    table = [
        ChipSetting(int(r["gain_sel"]), int(r["res"]), float(r["xy_uT_per_lsb"]), float(r["z_uT_per_lsb"]))
        for r in rows
    ]
    return tuple(sorted(table, key=lambda s: (s.z_uT_per_lsb, s.xy_uT_per_lsb)))


def choose_setting(max_abs_xy_T: float, max_abs_z_T: float, margin: float = 1.1) -> ChipSetting | None:
    """The finest setting whose range holds the largest field with ``margin``; None if none does
    (the field saturates the chip)."""
    for s in settings_table():
        if margin * max_abs_z_T <= s.z_range_T and margin * max_abs_xy_T <= s.xy_range_T:
            return s
    return None


def quantise_lsb(B_T: ArrayLike, uT_per_lsb: float) -> np.ndarray:
    """Output code of a field component (round to nearest LSB)."""
    return np.rint(np.asarray(B_T) * 1e6 / uT_per_lsb).astype(np.int64)


def field_resolution_T(setting: ChipSetting, noise_uT_rms: float = DEFAULT_NOISE_uT) -> float:
    """Smallest field change the chip resolves along z: the larger of noise and one LSB."""
    return 1e-6 * max(noise_uT_rms, setting.z_uT_per_lsb)
