"""The CSV tables of a calibration and of a reading: ``lookup.csv`` (|B| -> force on the
calibrated curve), ``residuals.csv`` (the load test against the fit) and ``forces.csv``
(``mst read``'s readings with their forces). Units are in the column names; an empty cell is
a value that does not exist (a flagged reading has no force)."""

from __future__ import annotations

import io
import math
from collections.abc import Sequence

import numpy as np

from mst_cli.calibration.fit import FitResult
from mst_cli.calibration.loadtest import Readings
from mst_cli.estimation.inverse_map import InverseMap
from mst_cli.model.chip import ChipSetting, quantise_lsb

FORCES_COLUMNS = ("force_N", "regime", "flag", "force_resolution_N")


def cell(value: float | None, spec: str = ".9g") -> str:
    """A number's cell: empty for None and for non-finite values."""
    return "" if value is None or (isinstance(value, float) and not math.isfinite(value)) else format(value, spec)


def quoted(text: str) -> str:
    """A text cell as RFC 4180 writes it: in double quotes (doubled inside) when it holds a comma
    or a quote, as written otherwise."""
    return text if "," not in text and '"' not in text else '"' + text.replace('"', '""') + '"'


def lookup_csv(imap: InverseMap, setting: ChipSetting | None, n: int) -> str:
    """``n`` entries evenly spaced in |B| from no load to the last lock, with the raw Z code at
    ``setting`` (column left out without one); ``calibrated`` = 0 above the load test's force."""
    B, Bz, F, regime, res = imap.table(n)
    buf = io.StringIO()
    code_col = setting is not None
    top = imap.calibrated_to_N if imap.calibrated_to_N is not None else float("inf")
    buf.write(
        "B_abs_uT,Bz_uT,"
        + ("Bz_code_lsb," if code_col else "")
        + "force_N,force_mN,regime,force_resolution_N,calibrated\n"
    )
    codes = quantise_lsb(Bz, setting.z_uT_per_lsb) if setting is not None else None
    for i in range(len(B)):
        buf.write(
            f"{B[i] * 1e6:.6f},{Bz[i] * 1e6:.6f},"
            + (f"{int(codes[i])}," if codes is not None else "")
            + f"{F[i]:.9g},{F[i] * 1e3:.6g},{int(regime[i])},{res[i]:.6g},{int(F[i] <= top * (1 + 1e-9))}\n"
        )
    return buf.getvalue()


def residuals_csv(lt: Readings, fit: FitResult, F_fit: np.ndarray, flag_fit: Sequence[str] | np.ndarray) -> str:
    """Every load-test sample: measured and fitted |B|, their difference, and the force the
    calibrated inverse map reads from the measured field (empty when flagged)."""
    buf = io.StringIO()
    buf.write("line,force_N,B_abs_measured_uT,B_abs_model_uT,residual_uT,force_model_N,flag\n")
    B_model = fit.model.field_abs_T(lt.load_N, fit.values)
    for i in range(len(lt)):
        f = "" if not math.isfinite(F_fit[i]) else f"{F_fit[i]:.9g}"
        buf.write(
            f"{lt.lines[i]},{lt.load_N[i]:.9g},{lt.B_abs_T[i] * 1e6:.6f},{B_model[i] * 1e6:.6f},"
            f"{fit.residual_T[i] * 1e6:.6f},{f},{flag_fit[i]}\n"
        )
    return buf.getvalue()


def reference_names(header: Sequence[str], written: Sequence[str]) -> list[str]:
    """``header`` with every name that mst read writes itself (``written``) renamed
    ``<name>_reference`` (force_N_reference: the load cell's; x_mm_reference: where it was
    pressed), so that no name appears twice in forces.csv."""
    taken = {*header, *written}
    out = []
    for h in header:
        if h in written:
            new = f"{h}_reference"
            while new in taken:  # the file has that name too
                new += "_"
            taken.add(new)
            h = new
        out.append(h)
    return out


def forces_csv(
    rd: Readings,
    F: np.ndarray,
    regime: np.ndarray,
    flag: Sequence[str] | np.ndarray,
    res: np.ndarray,
    appended: Sequence[str] = (),
) -> str:
    """The readings file's columns as written (a name among FORCES_COLUMNS or ``appended``, the
    columns the caller adds, renamed :func:`reference_names`) and FORCES_COLUMNS; a flagged
    reading's force, regime and resolution are empty."""
    header = reference_names(rd.header, (*FORCES_COLUMNS, *appended))
    buf = io.StringIO()
    buf.write(",".join([quoted(h) for h in header] + list(FORCES_COLUMNS)) + "\n")
    for i, row in enumerate(rd.rows):
        ok = bool(np.isfinite(F[i]))
        buf.write(
            ",".join(
                [quoted(c) for c in row]
                + [
                    cell(float(F[i])),
                    str(int(regime[i])) if ok else "",
                    flag[i],
                    cell(float(res[i]), ".6g") if ok else "",
                ]
            )
            + "\n"
        )
    return buf.getvalue()
