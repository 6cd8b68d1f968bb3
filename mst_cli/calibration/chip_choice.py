"""The one MLX90393 setting of a calibration (issue 38): ``mst simulate`` recommends a
GAIN_SEL/RES for the design (the finest whose range holds the field up to the last lock),
``mst calibrate`` writes its tables and ``force_table.h`` for one setting. They are the same
setting unless the load test forces another:

* a load test of raw codes (or with ``gain_sel,res`` columns, ``--gain-sel/--res``) was read at
  its own setting: the tables are for that one, since the firmware reads codes at it;
* a load test in uT whose field, or the calibrated sensor's field at full load, does not fit the
  recommended setting's range (with the same 10 % margin): the finest setting that holds it.

:func:`choose_setting_for` says which and why; calibrate prints :meth:`ChipChoice.line`, writes
:meth:`ChipChoice.record` into calibration.json's ``chip_setting`` and
:meth:`ChipChoice.header_note` into the header's comment.

Pure: no file or terminal I/O.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from mst_cli.calibration.loadtest import Readings
from mst_cli.model import chip as mlx
from mst_cli.model.response import Response

MARGIN = 1.1  # as mst_cli.model.chip.choose_setting: the field must fit the range with 10 % to spare
FROM_LOAD_TEST = "the load test"  # calibration.json chip_setting.source of a setting the load test gave


def _name(s: mlx.ChipSetting | None) -> str:
    return "none (the field saturates the chip)" if s is None else f"GAIN_SEL {s.gain_sel}, RES {s.res}"


@dataclass(frozen=True)
class ChipChoice:
    """The setting the tables are for (None: the field saturates every setting), the design's
    recommended one (``mst simulate``'s) and why they differ, if they do."""

    setting: mlx.ChipSetting | None
    recommended: mlx.ChipSetting | None
    source: str
    why: str

    @property
    def differs(self) -> bool:
        return self.setting != self.recommended

    def line(self) -> str:
        """The terminal line of ``mst calibrate``."""
        return f"chip setting {_name(self.setting)}: {self.why}"

    def header_note(self) -> str:
        """One sentence for force_table.h's comment."""
        return f"Chip setting: {self.why}."

    def record(self) -> dict | None:
        """calibration.json's ``chip_setting``."""
        s, rec = self.setting, self.recommended
        if s is None:
            return None
        return {
            "gain_sel": s.gain_sel,
            "res": s.res,
            "z_uT_per_lsb": s.z_uT_per_lsb,
            "xy_uT_per_lsb": s.xy_uT_per_lsb,
            "source": self.source,
            "design_recommended": None if rec is None else {"gain_sel": rec.gain_sel, "res": rec.res},
            "same_as_recommended": not self.differs,
            "why": self.why,
        }


def _fits(s: mlx.ChipSetting, xy_T: float, z_T: float) -> bool:
    return MARGIN * z_T <= s.z_range_T and MARGIN * xy_T <= s.xy_range_T


def _largest(B_T: np.ndarray) -> tuple[float, float]:
    """(largest |Bx| or |By|, largest |Bz|) of (n, 3) fields."""
    a = np.abs(np.asarray(B_T, float)).max(axis=0) if len(B_T) else np.zeros(3)
    return float(max(a[0], a[1])), float(a[2])


def choose_setting_for(design_resp: Response, cal_resp: Response, lt: Readings) -> ChipChoice:
    """The one setting of the calibration (module doc)."""
    rec = design_resp.chip_setting
    if lt.setting is not None:
        if lt.setting == rec:
            why = "the load test's, the one mst simulate recommends for the design"
        else:
            why = (
                f"the load test's (its codes or gain_sel/res were read at {_name(lt.setting)}), not the "
                f"{_name(rec)} mst simulate recommends for the design: read the sensor at {_name(lt.setting)}, "
                "or repeat the load test at the recommended setting"
            )
        return ChipChoice(lt.setting, rec, FROM_LOAD_TEST, why)
    xy_lt, z_lt = _largest(lt.B_T)
    xy_cal, z_cal = _largest(cal_resp.B_T[cal_resp.in_range])
    xy, z = max(xy_lt, xy_cal), max(z_lt, z_cal)
    if rec is not None and _fits(rec, xy, z):
        return ChipChoice(
            rec, rec, "the design's recommended setting (mst simulate)", "the one mst simulate recommends"
        )
    chosen = mlx.choose_setting(xy, z, MARGIN)
    what = "the load test's field" if max(xy_lt, z_lt) >= max(xy_cal, z_cal) else "the calibrated field at full load"
    why = (
        f"{what} ({max(xy, z) * 1e3:.3g} mT) does not fit the range of the {_name(rec)} mst simulate recommends "
        "for the design: the finest setting that holds it"
    )
    return ChipChoice(chosen, rec, "the finest setting that holds the load test's and the calibrated field", why)
