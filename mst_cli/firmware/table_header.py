"""``offset_table.h`` and ``shear_table.h``: a one-chip table reader and its direct inverse as a
C99 single-file header (float, no dynamic memory; defined in the one .c file that defines
``MST_OFF_IMPLEMENTATION`` / ``MST_SHR_IMPLEMENTATION``), for a microcontroller that reads the MLX90393's three axes:
raw codes -> the three estimates of the table's kind (offset: force, press x, y; shear: Fz, Fx,
Fy of a centred press), their Cramer-Rao 1-sigma and the reader's flag.

The C text is one template in package data (``data/table_reader.h.in``), its names prefixed per
kind (``mst_offset_*``/``MST_OFF_*``, ``mst_shear_*``/``MST_SHR_*``: both headers can be included
in one program); this module fills it from an
:class:`~mst_cli.estimation.inverse_table.InverseTable` and the model's
:class:`~mst_cli.estimation.inverse_map.InverseMap` (the range flags), and gives the Python side
of the same reading (:func:`read_codes`), which the headers' test compares with the compiled C.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np

from mst_cli.estimation import inverse_table as it
from mst_cli.estimation import table_start as ts
from mst_cli.estimation.inverse_map import InverseMap
from mst_cli.estimation.load_readings import LoadReadings
from mst_cli.estimation.table_reader import OffsetTableReader, ShearTableReader
from mst_cli.estimation.trilinear import RIDGE
from mst_cli.firmware.header import c_float, fill_template
from mst_cli.model.chip import CODE_RANGE_LSB, SATURATION_T, ChipSetting

OFFSET_HEADER_FILE = "offset_table.h"
SHEAR_HEADER_FILE = "shear_table.h"
TEMPLATE = "table_reader.h.in"
# what differs between the kinds: names, what is estimated, the verdict after the inverse
KIND_TEXT = {
    "offset": {
        "file": OFFSET_HEADER_FILE,
        "what": "force and press position",
        "returns": "The force (N) and press (mm)",
        "option": "--offset-table",
        "P": "MST_OFF",
        "p": "mst_off",
        "p_long": "mst_offset",
        "guard": "MST_OFFSET_TABLE_H",
        "fields": "force_N, x_mm, y_mm, sigma_force_N, sigma_x_mm, sigma_y_mm",
        "nodes_about": "force N, press x0 mm, press y0 mm",
        "model_lines": " * the tilt model's field (Bx, By, Bz) tabulated at MST_OFF_NF forces x MST_OFF_NU x\n"
        " * MST_OFF_NV press positions,",
        "verdict": "return (best_s[1] > MST_OFF_MAX_SIGMA_MM || best_s[2] > MST_OFF_MAX_SIGMA_MM) ? "
        "MST_OFF_NOT_IDENTIFIABLE : MST_OFF_OK;",
        "ratio_nodes": 0,
    },
    "shear": {
        "file": SHEAR_HEADER_FILE,
        "what": "normal and tangential force of a centred press",
        "returns": "The normal and tangential force (N)",
        "option": "--shear-table",
        "P": "MST_SHR",
        "p": "mst_shr",
        "p_long": "mst_shear",
        "guard": "MST_SHEAR_TABLE_H",
        "fields": "force_N, shear_x_N, shear_y_N, sigma_force_N, sigma_shear_x_N, sigma_shear_y_N",
        "nodes_about": "normal force N, Fx / Fz, Fy / Fz (a friction cone)",
        "model_lines": " * the general-load model's field (Bx, By, Bz) of a centred press tabulated at\n"
        " * MST_SHR_NF normal forces x MST_SHR_NU x MST_SHR_NV ratios of the tangential force to it\n"
        " * (Fx / Fz, Fy / Fz),",
        "verdict": "return MST_SHR_OK; /* no bound on the sigmas: they say how well */",
        "ratio_nodes": 1,
    },
}
C_FLAGS = (
    "ok",
    "not_identifiable",
    "ambiguous",
    "no_fit",
    "below_range",
    "above_range",
    "saturated",
    "above_calibrated",
    "bad_code",
)


def _c_floats(cname: str, values: np.ndarray, per_line: int = 8) -> str:
    """``static const float cname[n] = {...};`` (const: a Cortex-M keeps it in flash)."""
    vals = [c_float(float(v), 8) for v in np.ravel(values)]
    lines = ["    " + ", ".join(vals[i : i + per_line]) for i in range(0, len(vals), per_line)]
    return f"static const float {cname}[{len(vals)}] = {{\n" + ",\n".join(lines) + "\n};\n"


def start_arrays(table: it.InverseTable, p: str) -> dict[str, str]:
    """The C arrays of the direct inverse's starts: each force slab's |B| range (uT), the middle
    of (u, v) and its mean node spacing, as :func:`~mst_cli.estimation.inverse_table.solve_starts`
    takes them, and the start search's integer field in its index's order
    (:func:`~mst_cli.estimation.table_start.start_index`) with each entry's node and force node."""
    lo, hi = ts.slab_babs_uT(table)
    quantum = ts.start_quantum_uT(table)
    axis, order = ts.start_index(table)  # the field's nodes in the search's order
    per_slab = table.grid.shape[1] * table.grid.shape[2]

    def ints(cname: str, ctype: str, values: np.ndarray, per_line: int = 12) -> str:
        v = [str(int(x)) for x in np.ravel(values)]
        rows = [", ".join(v[i : i + per_line]) for i in range(0, len(v), per_line)]
        return f"static const {ctype} {cname}[{len(v)}] = {{\n    " + ",\n    ".join(rows) + "\n};\n"

    node_type = "uint16_t" if len(order) <= 0xFFFF else "uint32_t"
    return {
        "start_quantum_uT": c_float(quantum, 9),
        "start_levels": str(ts.START_LEVELS),
        "start_axis": str(axis),
        "start_nodes": str(len(order)),
        "start_field": ints(f"{p}_B_start", "int16_t", ts.start_field(1e6 * table.B_T, quantum).reshape(-1, 3)[order])
        + ints(f"{p}_start_node", node_type, order)
        + ints(f"{p}_start_force", "uint8_t" if table.grid.shape[0] <= 0xFF else "uint16_t", order // per_slab),
        "slab_babs": _c_floats(f"{p}_slab_babs_lo_uT", lo) + _c_floats(f"{p}_slab_babs_hi_uT", hi),
        "middle": _c_floats(f"{p}_middle_uv", np.ravel(ts.middle_uv(table.grid))),
    }


# the Gauss-Newton descents' constants, as Python's (inverse_table.py) takes them
DESCENT: dict[str, object] = {
    "steps": it.STEPS,
    "second_steps": it.SECOND_STEPS,
    "step_cells": c_float(it.STEP_CELLS),
    "converged": c_float(it.CONVERGED),
    "min_gain": c_float(it.MIN_GAIN),
    "halvings": it.HALVINGS,
    "stop_sigmas": c_float(it.STOP_SIGMAS),
    "stop_gain": c_float(it.STOP_GAIN),
    "probe": c_float(it.PROBE),
    "ridge": c_float(RIDGE),
}


def range_bounds_uT(imap: InverseMap) -> tuple[float, float, float]:
    """|B| (uT) below which a reading is below_range, above which above_range, and above which
    above_calibrated (1e30 without a load test's top): the inverse map's own bounds."""
    tol = imap.tolerance_T
    top = (
        math.inf if imap.calibrated_to_N is None else float(np.interp(imap.calibrated_to_N, imap.force_N, imap.B_abs_T))
    )
    return 1e6 * (imap.B_abs_T[0] - tol), 1e6 * (imap.B_abs_T[-1] + tol), min(1e30, 1e6 * (top + tol))


def table_header(
    reader: OffsetTableReader | ShearTableReader,
    imap: InverseMap,
    setting: ChipSetting,
    name: str,
    sources: str,
    limitations: Sequence[str],
) -> str:
    """The header of ``reader``'s table (offset_table.h or shear_table.h, by its kind) at
    ``setting``."""
    table = reader.table
    kind = KIND_TEXT[table.grid.kind]
    below, above, calibrated = range_bounds_uT(imap)
    nf, nx, ny = table.grid.shape
    p = kind["p"]
    f = str(kind["fields"]).split(", ")
    assign = (
        f"out->{f[0]} = p[0]; out->{f[1]} = p[1]; out->{f[2]} = p[2];\n"
        f"        out->{f[3]} = s[0]; out->{f[4]} = s[1]; out->{f[5]} = s[2];"
    )
    max_sigma_mm = getattr(reader, "max_sigma_mm", math.inf)
    return fill_template(
        TEMPLATE,
        setting,
        name,
        sources,
        limitations,
        **kind,
        kind=table.grid.kind,
        assign=assign,
        xy_uT_per_lsb=setting.xy_uT_per_lsb,
        xy_uT_per_lsb_c=c_float(setting.xy_uT_per_lsb, 8),
        z_uT_per_lsb_c=c_float(setting.z_uT_per_lsb, 8),
        saturated_lsb=min(CODE_RANGE_LSB[setting.res] - 1, int(SATURATION_T * 1e6 / setting.z_uT_per_lsb)),
        table_bytes=table.size_bytes_float32 + 4 * (3 * (nf - 1) + 4 + nf + nx + ny - 3) + 3 * table.B_T.size,
        nf=nf,
        nx=nx,
        ny=ny,
        sigma_uT=c_float(1e6 * reader.sigma_T, 8),
        fit_sigmas=c_float(it.FIT_SIGMAS),
        max_sigma_mm=c_float(min(max_sigma_mm, 1e30), 8),
        babs_below_uT=c_float(below, 9),
        babs_above_uT=c_float(above, 9),
        babs_calibrated_uT=c_float(calibrated, 9),
        **DESCENT,
        code_range=CODE_RANGE_LSB[setting.res],
        slab_sigma=_c_floats(f"{p}_slab_sigma_uT", np.hypot(1e6 * reader.sigma_T, table.slab_error_uT())),
        **start_arrays(table, str(p)),
        force_nodes=_c_floats(f"{p}_force_N_nodes", table.grid.force_N),
        x_nodes=_c_floats(f"{p}_u_nodes", table.grid.u),
        y_nodes=_c_floats(f"{p}_v_nodes", table.grid.v),
        inv_widths="".join(
            _c_floats(f"{p}_{name}_inv_widths", 1.0 / np.diff(nodes))
            for name, nodes in (("force_N", table.grid.force_N), ("u", table.grid.u), ("v", table.grid.v))
        ),
        field=_c_floats(f"{p}_B_uT", 1e6 * table.B_T, per_line=6),
    )


def read_codes(
    reader: OffsetTableReader | ShearTableReader, imap: InverseMap, setting: ChipSetting, codes: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """What ``mst read --estimate offset`` (``shear``) gives raw codes (n, 3) at ``setting`` on
    this table: (flag (n,) of :data:`C_FLAGS`; ``bad_code`` for a code beyond the chip's range, such
    as a 16-bit word not sign-extended, (n, 6) the three estimates and their 1-sigma, NaN
    unless ok: force N, x0, y0 mm; or Fz, Fx, Fy N). The range flags are the inverse map's, on
    |B| (saturated: a code at the chip's end)."""
    codes = np.asarray(codes, dtype=np.int64)
    lsb = np.array([setting.xy_uT_per_lsb, setting.xy_uT_per_lsb, setting.z_uT_per_lsb])
    B_T = codes * lsb * 1e-6
    saturated = np.any(np.abs(codes) >= CODE_RANGE_LSB[setting.res] - 1, axis=1)
    saturated |= np.any(np.abs(codes * lsb) >= SATURATION_T * 1e6, axis=1)
    F, _, flag = imap.force(np.linalg.norm(B_T, axis=1), saturated)
    est = reader.estimate_all(B_T, np.where(flag == "ok", F, np.nan))
    flag = np.where(flag == "ok", est.flag, flag)
    flag[np.any(np.abs(codes) > CODE_RANGE_LSB[setting.res], axis=1)] = "bad_code"  # not sign-extended
    ok = flag == "ok"
    if isinstance(est, LoadReadings):
        values = np.column_stack([est.force_N, est.shear_x_N, est.shear_y_N, est.sigma[:, :3]])
    else:
        values = np.column_stack([est.force_N, est.x_mm, est.y_mm, est.sigma_force_N, est.sigma_x_mm, est.sigma_y_mm])
    return flag, np.where(ok[:, None], values, np.nan)
