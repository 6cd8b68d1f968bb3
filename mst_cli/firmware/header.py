"""``force_table.h``: the calibrated sensor's raw Z code -> force table as a C99 header, for a
microcontroller that reads the MLX90393 and has no room for the model: a single-file header (its
tables and function defined in the one .c file that defines ``MST_FORCE_IMPLEMENTATION``, declared
for every other).

The C text is a template in package data (``data/force_table.h.in``, ``string.Template``
placeholders) so it reads as C; this module computes what fills it from an
:class:`~mst_cli.estimation.inverse_map.InverseMap`.
"""

from __future__ import annotations

import math
import textwrap
from collections.abc import Callable, Iterable, Sequence
from importlib import resources
from string import Template

import numpy as np

from mst_cli.estimation.inverse_map import InverseMap
from mst_cli.model.chip import CODE_RANGE_LSB, SATURATION_T, ChipSetting

HEADER_FILE = "force_table.h"
TEMPLATE = "force_table.h.in"


def fill_template(
    template_name: str, setting: ChipSetting, name: str, sources: str, limitations: Sequence[str], **fields: object
) -> str:
    """A C header template of ``firmware/data/`` filled in: the fields every header carries
    (the design's name, its sources, the chip setting, the model's limitations), then ``fields``."""
    text = resources.files(__package__).joinpath("data", template_name).read_text(encoding="utf-8")
    return Template(text).substitute(
        name=name,
        sources=sources,
        gain_sel=setting.gain_sel,
        res=setting.res,
        z_uT_per_lsb=setting.z_uT_per_lsb,
        limitations="\n".join(f" *   - {line}" for line in limitations),
        **fields,
    )


def c_float(value: float, digits: int = 4) -> str:
    """A C float literal (always with a point or an exponent before the f suffix)."""
    text = f"{value:.{digits}g}"
    return text + ("f" if any(c in text for c in ".en") else ".0f")


def c_array(ctype: str, cname: str, values: Iterable, fmt: Callable[[float], str], per_line: int = 10) -> str:
    """``const ctype cname[MST_TABLE_LEN] = {...};`` (defined once, where MST_FORCE_IMPLEMENTATION
    is; declared extern for every file), ``per_line`` values a line."""
    values = list(values)
    lines = ["    " + ", ".join(fmt(v) for v in values[i : i + per_line]) for i in range(0, len(values), per_line)]
    return f"const {ctype} {cname}[MST_TABLE_LEN] = {{\n" + ",\n".join(lines) + "\n};\n"


def c_header(
    imap: InverseMap,
    setting: ChipSetting,
    name: str,
    sources: str,
    limitations: Sequence[str],
    setting_note: str = "",
) -> str:
    """The header for ``setting``: |Z code| -> force in mN with the regime and resolution of each
    entry, and a lookup function that flags out-of-range and saturated codes; ``setting_note``
    (which setting and why, :mod:`~mst_cli.calibration.chip_choice`) goes into its comment.
    CalibrationFailed (from :meth:`InverseMap.z_code_table`) when no Z-only table exists."""
    codes, F, regime, res = imap.z_code_table(setting)
    lsb_T = setting.z_uT_per_lsb * 1e-6
    top_N = imap.calibrated_to_N if imap.calibrated_to_N is not None else float(imap.force_N[-1])
    return fill_template(
        TEMPLATE,
        setting,
        name,
        sources,
        limitations,
        z_uT_per_lsb_c=c_float(setting.z_uT_per_lsb, 6),
        setting_note="".join(f"\n * {line}" for line in textwrap.wrap(setting_note, 92)),
        table_len=len(codes),
        tolerance_lsb=max(1, int(math.ceil(imap.tolerance_T / lsb_T))),
        saturated_lsb=min(CODE_RANGE_LSB[setting.res] - 1, int(SATURATION_T / lsb_T)),
        force_full_mN=int(round(F[-1] * 1e3)),
        calibrated_lsb=int(math.floor(abs(float(np.interp(top_N, imap.force_N, imap.Bz_T))) / lsb_T)),
        force_calibrated_mN=int(round(top_N * 1e3)),
        n_regimes=imap.n_regimes,
        z_code=c_array("int32_t", "mst_z_code", codes, lambda v: str(int(v))),
        force_mN=c_array("int32_t", "mst_force_mN", F, lambda v: str(int(round(v * 1e3)))),
        regime=c_array("uint8_t", "mst_regime", regime, lambda v: str(int(v)), per_line=20),
        resolution_mN=c_array("float", "mst_resolution_mN", res, lambda v: c_float(v * 1e3), per_line=8),
    )
