"""``offset_table.h``: the offset reader's table and census as a C99 header (float, no dynamic
memory), for a microcontroller that reads the MLX90393's three axes: raw codes -> force, press
position, their Cramer-Rao 1-sigma and the reader's flag.

The C text is a template in package data (``data/offset_table.h.in``); this module fills it from
an :class:`~mst_cli.calibrate.inverse_table.InverseTable` and the model's
:class:`~mst_cli.calibrate.inverse_map.InverseMap` (the range flags), and gives the Python side
of the same reading (:func:`read_codes`), which the header's test compares with the compiled C.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np

from mst_cli.calibrate import inverse_table as it
from mst_cli.calibrate.header import c_float, fill_template
from mst_cli.calibrate.inverse_map import InverseMap
from mst_cli.calibrate.table_reader import OffsetTableReader
from mst_cli.model.chip import CODE_RANGE_LSB, SATURATION_T, ChipSetting

OFFSET_HEADER_FILE = "offset_table.h"
TEMPLATE = "offset_table.h.in"
# the header's flags, in the order of its enum mst_offset_flag
C_FLAGS = (
    "ok",
    "not_identifiable",
    "ambiguous",
    "no_fit",
    "below_range",
    "above_range",
    "saturated",
    "above_calibrated",
)


def _c_floats(cname: str, values: np.ndarray, per_line: int = 8) -> str:
    vals = [c_float(float(v), 8) for v in np.ravel(values)]
    lines = ["    " + ", ".join(vals[i : i + per_line]) for i in range(0, len(vals), per_line)]
    return f"static const float {cname}[{len(vals)}] = {{\n" + ",\n".join(lines) + "\n};\n"


def range_bounds_uT(imap: InverseMap) -> tuple[float, float, float]:
    """|B| (uT) below which a reading is below_range, above which above_range, and above which
    above_calibrated (1e30 without a load test's top): the inverse map's own bounds."""
    tol = imap.tolerance_T
    top = (
        math.inf if imap.calibrated_to_N is None else float(np.interp(imap.calibrated_to_N, imap.force_N, imap.B_abs_T))
    )
    return 1e6 * (imap.B_abs_T[0] - tol), 1e6 * (imap.B_abs_T[-1] + tol), min(1e30, 1e6 * (top + tol))


def offset_header(
    reader: OffsetTableReader,
    imap: InverseMap,
    setting: ChipSetting,
    name: str,
    sources: str,
    limitations: Sequence[str],
) -> str:
    """The header of ``reader``'s table at ``setting``."""
    table = reader.table
    below, above, calibrated = range_bounds_uT(imap)
    nf, nx, ny = table.grid.shape
    return fill_template(
        TEMPLATE,
        setting,
        name,
        sources,
        limitations,
        xy_uT_per_lsb=setting.xy_uT_per_lsb,
        xy_uT_per_lsb_c=c_float(setting.xy_uT_per_lsb, 8),
        z_uT_per_lsb_c=c_float(setting.z_uT_per_lsb, 8),
        saturated_lsb=min(CODE_RANGE_LSB[setting.res] - 1, int(SATURATION_T * 1e6 / setting.z_uT_per_lsb)),
        table_bytes=table.size_bytes_float32,
        nf=nf,
        nx=nx,
        ny=ny,
        sigma_uT=c_float(1e6 * reader.sigma_T, 8),
        fit_sigmas=c_float(it.FIT_SIGMAS),
        max_sigma_mm=c_float(reader.max_sigma_mm, 8),
        babs_below_uT=c_float(below, 9),
        babs_above_uT=c_float(above, 9),
        babs_calibrated_uT=c_float(calibrated, 9),
        newton_steps=it.NEWTON_STEPS,
        prune_after=it.PRUNE_AFTER,
        outside=c_float(it.OUTSIDE),
        inside_tol=c_float(it.INSIDE_TOL),
        ridge=c_float(it.RIDGE),
        force_nodes=_c_floats("mst_force_N_nodes", table.grid.force_N),
        x_nodes=_c_floats("mst_x_nodes", table.grid.u),
        y_nodes=_c_floats("mst_y_nodes", table.grid.v),
        field=_c_floats("mst_B_uT", 1e6 * table.B_T, per_line=6),
    )


def read_codes(
    reader: OffsetTableReader, imap: InverseMap, setting: ChipSetting, codes: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """What ``mst read --estimate offset`` gives raw codes (n, 3) at ``setting`` on this table:
    (flag (n,) of :data:`C_FLAGS`, (n, 6) force N, x0, y0 mm and their 1-sigma, NaN unless ok).
    The range flags are the inverse map's, on |B| (saturated: a code at the chip's end)."""
    codes = np.asarray(codes, dtype=np.int64)
    lsb = np.array([setting.xy_uT_per_lsb, setting.xy_uT_per_lsb, setting.z_uT_per_lsb])
    B_T = codes * lsb * 1e-6
    saturated = np.any(np.abs(codes) >= CODE_RANGE_LSB[setting.res] - 1, axis=1)
    saturated |= np.any(np.abs(codes * lsb) >= SATURATION_T * 1e6, axis=1)
    F, _, flag = imap.force(np.linalg.norm(B_T, axis=1), saturated)
    est = reader.estimate_all(B_T, np.where(flag == "ok", F, np.nan))
    flag = np.where(flag == "ok", est.flag, flag)
    ok = flag == "ok"
    values = np.column_stack([est.force_N, est.x_mm, est.y_mm, est.sigma_force_N, est.sigma_x_mm, est.sigma_y_mm])
    return flag, np.where(ok[:, None], values, np.nan)
