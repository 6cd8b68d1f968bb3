"""Reading load tests and reading files (CSV): the input side of ``mst calibrate`` and ``mst read``.

Format (docs: README, "From a load test to a force stream"):

* one header row, then one row per sample; comma, semicolon or tab separated (the header
  decides); lines starting with ``#`` and blank lines are skipped; UTF-8 (a BOM is fine);
* the field as ``Bx_uT,By_uT,Bz_uT`` (microtesla, as the Adafruit and SparkFun MLX90393
  libraries report it), or as the chip's raw output codes ``Bx_code_lsb,By_code_lsb,Bz_code_lsb``
  with its GAIN_SEL and RES given (options, or ``gain_sel,res`` columns);
* a load test also has ``force_N`` (newtons; any other force unit is refused, not guessed);
* extra columns are kept in ``mst read``'s output, so each is checked as it is read: a cell of
  ``time_s``, ``cycle`` or ``T_C`` (EXTRA_NUMBER_COLUMNS) must be a finite number, a cell of
  any other extra column that reads as a number must be a finite one (no ``nan``, ``inf``);
* a rig's columns (issue 38): ``time_s`` never decreases (else row order is time order),
  ``cycle`` is a whole number, ``branch`` one of loading/unloading/hold, ``T_C`` the chip's
  temperature within the MLX90393's operating range (-40..125 degC); any other column is named
  by :func:`unknown_columns` (the commands print one note);
* a cell holds at most MAX_CELL_CHARS characters (:mod:`mst_cli.io.csv_table`).

Every problem raises :class:`~mst_cli.errors.InputError` naming the file, the line and the
column: the CLI turns it into one line and exit code 2.
"""

from __future__ import annotations

import functools
import math
import re
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from mst_cli.calibration.chip_columns import extra_chip_columns, is_chip_column
from mst_cli.calibration.missing_force import check_force_sentinel, is_missing
from mst_cli.errors import InputError
from mst_cli.io.csv_table import csv_rows
from mst_cli.io.files import read_input_text
from mst_cli.model import chip as mlx

MAX_INPUT_BYTES = 20_000_000
MAX_ROWS = 200_000
FORCE_COLUMN = "force_N"
UT_COLUMNS = ("Bx_uT", "By_uT", "Bz_uT")
CODE_COLUMNS = ("Bx_code_lsb", "By_code_lsb", "Bz_code_lsb")
SETTING_COLUMNS = ("gain_sel", "res")
OFFSET_COLUMNS = ("x_mm", "y_mm")  # where a load-test row was pressed (optional, both or neither)
# extra columns with a meaning (time, load cycle, temperature): numbers, checked where they are read
EXTRA_NUMBER_COLUMNS = ("time_s", "cycle", "T_C")
BRANCH_COLUMN = "branch"  # the rig's own loading / unloading / hold label of a row (issue 38)
BRANCH_VALUES = ("loading", "unloading", "hold")
RIG_COLUMNS = (*EXTRA_NUMBER_COLUMNS, BRANCH_COLUMN)
T_C_RANGE = (-40.0, 125.0)  # the MLX90393's operating temperature range, degC
MAX_CYCLE = 1_000_000  # load cycles of one test (a cycle is seconds: a million is weeks of rig time)
MAX_TIME_S = 1e9  # 30 years
MIN_TIME_STEP_S = 1e-6  # finer than any logger stamps (the chip gives at most about 717 samples a second)
# a column that looks like a force or a field in another unit: refused with the conversion
FORCE_LIKE = re.compile(r"^(force|load|f|weight|mass)(_.*|\s*\[.*\]|\s*\(.*\))?$", re.IGNORECASE)
FIELD_LIKE = re.compile(r"^(b|mag)_?[xyz](_.+|\s*\[.*\]|\s*\(.*\))$", re.IGNORECASE)
FORCE_CONVERSIONS = {
    "kn": "x 1000",
    "mn": "x 0.001",
    "g": "x 0.00980665",
    "gf": "x 0.00980665",
    "kg": "x 9.80665",
    "kgf": "x 9.80665",
    "lbf": "x 4.44822",
    "lb": "x 4.44822",
    "n": "(rename it)",
}


@dataclass
class Readings:
    """Parsed rows of a load test or a readings file."""

    source: str
    header: list[str]
    rows: list[list[str]]  # the cells as written (for echoing the input columns)
    lines: list[int]  # line number of each row in the file (from 1)
    B_T: np.ndarray  # (n, 3) field in tesla
    saturated: np.ndarray  # (n,) bool
    force_N: np.ndarray | None  # the load cell's force (load tests; readings with a force_N column)
    raw: bool  # the file held raw codes
    setting: mlx.ChipSetting | None  # the one chip setting of every row, when known
    offset_mm: np.ndarray | None = None  # (n, 2) where each row was pressed (x_mm, y_mm columns)
    B_chips_T: np.ndarray | None = None  # (n, k, 3) every chip's field, chip 1 first (files of k >= 2 chips)

    @property
    def chips(self) -> int:
        """How many chips' fields the file holds."""
        return 1 if self.B_chips_T is None else self.B_chips_T.shape[1]

    def subset(self, keep: np.ndarray) -> Readings:
        """The rows where ``keep`` (a boolean mask) holds, as a Readings of their own."""
        idx = np.flatnonzero(keep)
        return Readings(
            source=self.source,
            header=self.header,
            rows=[self.rows[i] for i in idx],
            lines=[self.lines[i] for i in idx],
            B_T=self.B_T[idx],
            saturated=self.saturated[idx],
            force_N=None if self.force_N is None else self.force_N[idx],
            raw=self.raw,
            setting=self.setting,
            offset_mm=None if self.offset_mm is None else self.offset_mm[idx],
            B_chips_T=None if self.B_chips_T is None else self.B_chips_T[idx],
        )

    @functools.cached_property
    def B_abs_T(self) -> np.ndarray:
        """|B| of every row, computed once (a per-row call would cost O(rows) each)."""
        return np.linalg.norm(self.B_T, axis=1)

    def __len__(self) -> int:
        return len(self.rows)

    @property
    def load_N(self) -> np.ndarray:
        """(n,) the load cell's force in N: ``force_N`` of a file that has one (a load test, read
        with ``need_force``); ValueError for readings without it."""
        if self.force_N is None:
            raise ValueError(f"{self.source} has no {FORCE_COLUMN} column")
        return self.force_N


def setting_of(gain_sel: int, res: int) -> mlx.ChipSetting:
    for s in mlx.settings_table():
        if (s.gain_sel, s.res) == (gain_sel, res):
            return s
    raise InputError("--gain-sel/--res", f"{gain_sel}/{res}", "GAIN_SEL must be 0-7 and RES 0-3")


def read_text(path: str | Path, what: str = "CSV file") -> str:
    """The text of a load test or readings file: a regular file (a FIFO or a device is refused
    before it is opened, so nothing blocks) of at most MAX_INPUT_BYTES, UTF-8 (a BOM is fine)."""
    return read_input_text(path, MAX_INPUT_BYTES, what=what, encoding="utf-8-sig")


def _delimiter(header_line: str) -> str:
    counts = {d: header_line.count(d) for d in (",", ";", "\t")}
    best = max(counts, key=lambda d: counts[d])
    return best if counts[best] else ","


def _number(source, line, column, text) -> float:
    try:
        v = float(text)
    except (TypeError, ValueError):
        raise InputError(f"{source} line {line} {column}", text, "must be a number") from None
    if not math.isfinite(v):
        raise InputError(f"{source} line {line} {column}", text, "must be a finite number")
    return v


def _force(source: str, line: int, cell: str, missing_force: float | None) -> float:
    """A force cell: a finite number, or NaN for a row without a force (:func:`is_missing`)."""
    missing = is_missing(f"{source} line {line} {FORCE_COLUMN}", cell, missing_force)
    return math.nan if missing else _number(source, line, FORCE_COLUMN, cell)


def _check_extra_columns(
    source: str, header: list[str], rows: list[list[str]], lines: list[int], used: tuple[str, ...]
) -> None:
    """Every cell of the extra columns (those the reading does not use, besides ``used``: the
    force and the offsets, and ``mst read`` copies them into forces.csv), checked by
    :func:`_extra_cell`, row by row."""
    extras = [c for c in header if c not in {*used, FORCE_COLUMN, *OFFSET_COLUMNS}]
    at = [header.index(c) for c in extras]
    for row, line in zip(rows, lines):
        for c, j in zip(extras, at):
            _extra_cell(source, line, c, row[j])
    _check_time_order(source, header, rows, lines)


def _extra_cell(source, line, column, text) -> None:
    """A cell of a column the reading does not use, copied as written into ``mst read``'s
    forces.csv: one of EXTRA_NUMBER_COLUMNS must be a finite number; any other may be text, but
    not a number that is not finite."""
    if column in EXTRA_NUMBER_COLUMNS:
        _rig_number(source, line, column, _number(source, line, column, text))
        return
    if column == BRANCH_COLUMN:
        if text.strip().lower() not in BRANCH_VALUES:
            raise InputError(f"{source} line {line} {column}", text, "one of " + ", ".join(BRANCH_VALUES))
        return
    try:
        v = float(text)
    except ValueError:
        return
    if not math.isfinite(v):
        raise InputError(
            f"{source} line {line} {column}",
            text,
            "must be a finite number or text (an extra column is copied into forces.csv)",
        )


def _rig_number(source, line, column, v: float) -> None:
    """A cycle is a whole number; T_C (the chip's temperature) lies in the MLX90393's operating range."""
    if column == "cycle" and (v != round(v) or not 0 <= v <= MAX_CYCLE):
        raise InputError(f"{source} line {line} {column}", v, f"a whole number 0..{MAX_CYCLE} (the load cycle)")
    if column == "time_s" and not abs(v) <= MAX_TIME_S:
        raise InputError(f"{source} line {line} {column}", v, f"seconds within +-{MAX_TIME_S:g}")
    lo, hi = T_C_RANGE
    if column == "T_C" and not lo <= v <= hi:
        raise InputError(
            f"{source} line {line} {column}", v, f"the chip's temperature in degC, within the MLX90393's {lo:g}..{hi:g}"
        )


def _check_time_order(source: str, header: list[str], rows: list[list[str]], lines: list[int]) -> None:
    """time_s never decreases from row to row (rows are in time order)."""
    if "time_s" not in header:
        return
    j = header.index("time_s")
    before = -math.inf
    for row, line in zip(rows, lines):
        t = float(row[j])
        if t < before:
            raise InputError(
                f"{source} line {line} time_s", row[j], f"times that never decrease (the row before has {before:g})"
            )
        if 0 < t - before < MIN_TIME_STEP_S:
            raise InputError(
                f"{source} line {line} time_s",
                row[j],
                f"a step of 0 or at least {MIN_TIME_STEP_S:g} s from the row before",
            )
        before = t


def unknown_columns(rd: Readings) -> list[str]:
    """The columns of ``rd`` no part of mst reads (copied into forces.csv by mst read, no more)."""
    known = {FORCE_COLUMN, *UT_COLUMNS, *CODE_COLUMNS, *SETTING_COLUMNS, *OFFSET_COLUMNS, *RIG_COLUMNS}
    return [c for c in rd.header if c not in known and not is_chip_column(c)]


def rig_column(rd: Readings, column: str) -> np.ndarray | None:
    """The values of a rig column (time_s, cycle, T_C as floats; branch as lower-case labels),
    None when the file has no such column."""
    if column not in rd.header:
        return None
    j = rd.header.index(column)
    if column == BRANCH_COLUMN:
        return np.array([row[j].strip().lower() for row in rd.rows], dtype=object)
    return np.array([float(row[j]) for row in rd.rows], dtype=float)


def _wrong_unit_force(source, header):
    for name in header:
        if name != FORCE_COLUMN and FORCE_LIKE.match(name):
            after_name = re.split(r"[_\[\(\s]", name, maxsplit=1)[1:] or [""]
            unit = after_name[0].strip("[]() ").lower()
            how = FORCE_CONVERSIONS.get(unit)
            hint = f" (convert: {how})" if how else ""
            raise InputError(
                f"{source} column {name!r}",
                name,
                f"the force column must be {FORCE_COLUMN}, in newtons{hint}: no other unit is guessed",
            )


def _wrong_unit_field(source, header):
    for name in header:
        if name not in UT_COLUMNS + CODE_COLUMNS and FIELD_LIKE.match(name):
            raise InputError(
                f"{source} column {name!r}",
                name,
                "the field columns must be Bx_uT, By_uT, Bz_uT (microtesla) or the raw "
                "codes Bx_code_lsb, By_code_lsb, Bz_code_lsb: no other unit is guessed",
            )


def parse_readings(
    text: str,
    source: str,
    *,
    need_force: bool,
    gain_sel: int | None = None,
    res: int | None = None,
    one_setting: bool = False,
    missing_force: float | None = None,
) -> Readings:
    """Parse and validate a load test (``need_force``) or a readings file.

    ``gain_sel``/``res``: the chip setting the readings were taken at (needed for raw codes;
    checked against ``gain_sel,res`` columns when both are given). ``one_setting``: every row
    must come from one setting (a load test: its table is for one setting). ``missing_force``:
    the logger's sentinel for a row without a force (NaN: only empty and ``nan`` cells); such
    rows get a NaN force (:mod:`~mst_cli.calibration.missing_force`), without it they are refused.
    """
    if (gain_sel is None) != (res is None):
        raise InputError("--gain-sel/--res", f"{gain_sel}/{res}", "give both GAIN_SEL and RES, or neither")
    flag_setting = setting_of(gain_sel, res) if gain_sel is not None and res is not None else None
    numbered, delim, header, data_rows = _table(text, source, need_force)
    raw, cols = _field_columns(source, header, need_force)
    others = extra_chip_columns(source, header, raw)
    idx = {c: header.index(c) for c in header}
    settings = (
        _RowSettings(source, idx, flag_setting, one_setting) if all(c in header for c in SETTING_COLUMNS) else None
    )
    B = np.empty((len(data_rows), 3))
    offsets = _offset_columns(source, header)
    off = np.empty((len(data_rows), 2)) if offsets else None
    with_force = need_force or FORCE_COLUMN in header  # a readings file may carry the reference
    F = np.empty(len(data_rows)) if with_force else None
    sat = np.zeros(len(data_rows), dtype=bool)
    B_chips = np.empty((len(data_rows), 1 + len(others), 3)) if others else None
    rows, lines = [], []
    for r, (row, (line, _)) in enumerate(zip(data_rows, numbered[1:])):
        if len(row) != len(header):
            raise InputError(
                f"{source} line {line}", delim.join(row), f"has {len(row)} fields, the header {len(header)}"
            )
        row = [c.strip() for c in row]
        setting = settings.of_row(line, row) if settings is not None else flag_setting
        values = [_number(source, line, c, row[idx[c]]) for c in cols]
        B[r], sat[r] = field_of(values, raw, setting, f"{source} line {line}")
        if B_chips is not None:
            B_chips[r], chips_saturated = _chip_fields(source, line, row, idx, others, raw, setting)
            B_chips[r, 0] = B[r]
            sat[r] |= chips_saturated
        if F is not None:
            F[r] = _force(source, line, row[idx[FORCE_COLUMN]], missing_force)
        if off is not None:
            off[r] = [_number(source, line, c, row[idx[c]]) for c in OFFSET_COLUMNS]
        rows.append(row)
        lines.append(line)
    used = (*cols, *(c for names in others for c in names), *(SETTING_COLUMNS if settings is not None else ()))
    _check_extra_columns(source, header, rows, lines, used)
    one = flag_setting if settings is None or flag_setting is not None else settings.the_one(rows)
    return Readings(source, header, rows, lines, B, sat, F, raw, one, off, B_chips)  # the fields' order


def _chip_fields(
    source: str, line: int, row: list[str], idx: dict[str, int], others: list[tuple[str, str, str]], raw: bool, setting
) -> tuple[np.ndarray, bool]:
    """(every chip's field (k, 3) in T, chip 1's left to the caller; whether one is saturated) of
    a row, from the columns ``others`` of chips 2.."""
    out, saturated = np.zeros((1 + len(others), 3)), False
    for k, names in enumerate(others, start=1):
        values = [_number(source, line, c, row[idx[c]]) for c in names]
        out[k], sat = field_of(values, raw, setting, f"{source} line {line}", names)
        saturated |= sat
    return out, saturated


def _table(text: str, source: str, need_force: bool) -> tuple[list[tuple[int, str]], str, list[str], list[list[str]]]:
    """(the numbered lines that are not comments or blank, the delimiter, the header, the data
    rows split) of a CSV text; InputError without a header or with too many rows."""
    numbered = [
        (i + 1, line) for i, line in enumerate(text.splitlines()) if line.strip() and not line.lstrip().startswith("#")
    ]
    if not numbered:
        raise InputError(
            source,
            "(empty)",
            "has no header row: expected columns " + (f"{FORCE_COLUMN}," if need_force else "") + ",".join(UT_COLUMNS),
        )
    delim = _delimiter(numbered[0][1])
    parsed = csv_rows(numbered, delim, source)
    data_rows = parsed[1:]
    if len(data_rows) > MAX_ROWS:
        raise InputError(source, f"{len(data_rows)} rows", f"at most {MAX_ROWS} rows")
    return numbered, delim, [h.strip() for h in parsed[0]], data_rows


def _offset_columns(source: str, header: list[str]) -> bool:
    """Whether the file says where each row was pressed: both x_mm and y_mm, or neither."""
    present = [c in header for c in OFFSET_COLUMNS]
    if any(present) and not all(present):
        missing = OFFSET_COLUMNS[present.index(False)]
        raise InputError(
            f"{source} header",
            ",".join(header),
            f"has {OFFSET_COLUMNS[present.index(True)]} without {missing}: give both or neither",
        )
    return all(present)


def _field_columns(source: str, header: list[str], need_force: bool) -> tuple[bool, tuple[str, ...]]:
    """(raw, the field columns) of a header: microtesla or raw codes; InputError for a repeated
    column, a missing force column (``need_force``) or field columns, or a unit that is not ours."""
    if len(set(header)) != len(header):
        dup = next(h for h in header if header.count(h) > 1)
        raise InputError(f"{source} header", dup, "a column name appears twice")
    if need_force and FORCE_COLUMN not in header:
        _wrong_unit_force(source, header)
        raise InputError(
            f"{source} header", ",".join(header), f"missing column {FORCE_COLUMN} (the load cell's force in newtons)"
        )
    if all(c in header for c in UT_COLUMNS):
        return False, UT_COLUMNS
    if all(c in header for c in CODE_COLUMNS):
        return True, CODE_COLUMNS
    _wrong_unit_field(source, header)
    missing = [c for c in UT_COLUMNS if c not in header]
    raise InputError(
        f"{source} header",
        ",".join(header),
        f"missing column(s) {', '.join(missing)} (or the raw codes {', '.join(CODE_COLUMNS)} with --gain-sel/--res)",
    )


class _RowSettings:
    """The chip setting of each row of a file with gain_sel and res columns, checked against
    --gain-sel/--res and (``one_setting``) against the first row's."""

    def __init__(self, source: str, idx: dict[str, int], flag_setting: mlx.ChipSetting | None, one_setting: bool):
        self.source, self.idx = source, idx
        self.flag_setting, self.one_setting = flag_setting, one_setting
        self.first: mlx.ChipSetting | None = None

    def of_row(self, line: int, row: list[str]) -> mlx.ChipSetting:
        source, idx = self.source, self.idx
        g = _number(source, line, "gain_sel", row[idx["gain_sel"]])
        s = _number(source, line, "res", row[idx["res"]])
        if g != int(g) or s != int(s) or not (0 <= g <= 7 and 0 <= s <= 3):
            raise InputError(
                f"{source} line {line} gain_sel/res",
                f"{row[idx['gain_sel']]}/{row[idx['res']]}",
                "GAIN_SEL must be an integer 0-7 and RES 0-3",
            )
        row_setting = setting_of(int(g), int(s))
        flag = self.flag_setting
        if flag is not None and row_setting != flag:
            raise InputError(
                f"{source} line {line} gain_sel/res",
                f"{int(g)}/{int(s)}",
                f"differs from --gain-sel {flag.gain_sel} --res {flag.res}: "
                "the readings come from another chip setting",
            )
        if self.one_setting and self.first is not None and row_setting != self.first:
            raise InputError(
                f"{source} line {line} gain_sel/res",
                f"{int(g)}/{int(s)}",
                f"a load test must come from one chip setting (earlier rows: {self.first.gain_sel}/{self.first.res})",
            )
        self.first = self.first or row_setting
        return row_setting

    def the_one(self, rows: list[list[str]]) -> mlx.ChipSetting | None:
        """The setting of every row when they share one, else None."""
        settings = {(float(row[self.idx["gain_sel"]]), float(row[self.idx["res"]])) for row in rows}
        return self.first if len(settings) == 1 else None


def fields_of(
    values: np.ndarray, raw: bool, setting: mlx.ChipSetting | None
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(fields (m, 3) in T, saturated (m,), beyond (m, 3): a value no chip at ``setting`` gives)
    of samples ``values`` (m, 3): x, y, z in microtesla, or raw codes (``setting`` given).

    A raw code must be an integer within the codes the chip outputs at its RES; a field within
    what the chip reads at its setting (unchecked without one). Saturated: a code within one of
    the end, a field within 1.5 LSB of the range's end, or past the Hall plates' saturation."""
    v = np.asarray(values, dtype=float).reshape(-1, 3)
    if raw:
        assert setting is not None
        limit = mlx.CODE_RANGE_LSB[setting.res]
        beyond = (v != np.trunc(v)) | (np.abs(v) > limit)
        B_uT = v * np.array([setting.xy_uT_per_lsb, setting.xy_uT_per_lsb, setting.z_uT_per_lsb])
        saturated = np.any(np.abs(v) >= limit - 1, axis=1)
    else:
        B_uT = v
        beyond = np.zeros(v.shape, dtype=bool)
        saturated = np.zeros(len(v), dtype=bool)
        if setting is not None:
            ranges = np.array([setting.xy_range_T, setting.xy_range_T, setting.z_range_T])
            lsbs = np.array([setting.xy_uT_per_lsb, setting.xy_uT_per_lsb, setting.z_uT_per_lsb])
            beyond = np.abs(v) * 1e-6 > ranges + 1.5e-6 * lsbs
            saturated = np.any(np.abs(v) * 1e-6 >= ranges - 1.5e-6 * lsbs, axis=1)
    # compared in microtesla, as read: 50000 uT x 1e-6 is 0.049999999999999996 T, below 50 mT
    saturated |= np.any(np.abs(B_uT) >= mlx.SATURATION_T * 1e6, axis=1)
    return B_uT * 1e-6, saturated, beyond


def field_of(
    values: Sequence[float],
    raw: bool,
    setting: mlx.ChipSetting | None,
    where: str,
    columns: Sequence[str] | None = None,
) -> tuple[np.ndarray, bool]:
    """(field vector in T, saturated) of one sample: x, y, z in microtesla, or raw codes
    (:func:`fields_of`).

    InputError when the sample cannot come from ``setting`` (a code or a field beyond what the
    chip outputs there), or raw codes arrive without a setting."""
    if raw and setting is None:
        raise InputError(
            "--gain-sel/--res",
            None,
            "raw codes need the chip setting they were read at: give --gain-sel and --res (or gain_sel,res columns)",
        )
    B, saturated, beyond = fields_of(np.asarray(values, dtype=float), raw, setting)
    if beyond.any():
        raise beyond_error(values, raw, setting, where, columns)
    return B[0], bool(saturated[0])


def beyond_error(
    values: Sequence[float], raw: bool, setting: mlx.ChipSetting | None, where: str, columns: Sequence[str] | None
) -> InputError:
    """The error of a sample with a value :func:`fields_of` finds beyond the chip, naming the first."""
    assert setting is not None  # unchecked without a setting
    cols = columns or (CODE_COLUMNS if raw else UT_COLUMNS)
    beyond = fields_of(np.asarray(values, dtype=float), raw, setting)[2][0]
    k = int(np.argmax(beyond))
    c, v = cols[k], values[k]
    if raw and v != int(v):
        return InputError(f"{where} {c}", v, "a raw code must be an integer")
    rng = setting.z_range_T if k == 2 else setting.xy_range_T
    what = (
        f"outside the +-{mlx.CODE_RANGE_LSB[setting.res]} codes the chip outputs at RES {setting.res}"
        if raw
        else f"beyond the {rng * 1e6:.6g} uT the chip reads at GAIN_SEL {setting.gain_sel}, RES {setting.res}"
    )
    return InputError(f"{where} {c}", v, f"{what}: the readings come from another chip setting")


def check_field_unit(rd: Readings, B_unloaded_T: float, B_full_T: float) -> None:
    """Field columns in microtesla that hold millitesla: every |B| is under 1 % of the design's
    unloaded field, yet 1000 x it lies within a factor of 3 of the design's field range. Raw
    codes carry no unit to mistake."""
    if rd.raw or not len(rd) or not (B_unloaded_T > 0):
        return
    top = float(np.max(rd.B_abs_T))
    if 0 < top < 0.01 * B_unloaded_T and B_unloaded_T / 3 <= 1000 * top <= 3 * B_full_T:
        i = int(np.argmax(rd.B_abs_T))
        raise InputError(
            f"{rd.source} line {rd.lines[i]} {','.join(UT_COLUMNS)}",
            ",".join(rd.rows[i][rd.header.index(c)] for c in UT_COLUMNS),
            f"|B| up to {top * 1e6:.4g} uT, yet the design's field at the chip is {B_unloaded_T * 1e6:.4g}-"
            f"{B_full_T * 1e6:.4g} uT: are the values in mT? The columns must be microtesla (convert: x 1000)",
        )


def check_load_test(
    lt: Readings, n_parameters: int, design_range_N: float, min_per_parameter: int, min_points: int
) -> None:
    """What a load test needs before a fit: enough samples, no saturated sample, forces that
    are plausibly newtons for this design."""
    n = len(lt)
    need = max(min_points, min_per_parameter * n_parameters)
    if n < need:
        raise InputError(
            lt.source,
            f"{n} samples",
            f"needs at least {need} samples to fit {n_parameters} parameter(s) "
            f"({min_per_parameter} per parameter, {min_points} at least)",
        )
    distinct = len(np.unique(np.round(lt.load_N, 9)))
    if distinct < n_parameters + 2:
        raise InputError(
            f"{lt.source} {FORCE_COLUMN}",
            f"{distinct} distinct forces",
            f"needs at least {n_parameters + 2} distinct force levels to fit {n_parameters} parameter(s)",
        )
    if lt.saturated.any():
        i = int(np.flatnonzero(lt.saturated)[0])
        raise InputError(
            f"{lt.source} line {lt.lines[i]}",
            ",".join(lt.rows[i]),
            f"saturated sample ({int(lt.saturated.sum())} in all): the chip's output is at "
            "its limit, so the field is unknown; remove saturated rows or use a coarser "
            "GAIN_SEL/RES",
        )
    F = lt.load_N
    lo_tol = 0.02 * design_range_N
    if F.min() < -lo_tol:
        check_force_sentinel(lt.source, lt.lines, F, FORCE_COLUMN)
        i = int(np.argmin(F))
        raise InputError(
            f"{lt.source} line {lt.lines[i]} {FORCE_COLUMN}",
            float(F[i]),
            f"a pressing force is >= 0 N (tare noise down to -{lo_tol:.3g} N is accepted): "
            "is the load cell's sign reversed?",
        )
    if F.max() > 4.0 * design_range_N:
        i = int(np.argmax(F))
        raise InputError(
            f"{lt.source} line {lt.lines[i]} {FORCE_COLUMN}",
            float(F[i]),
            f"is {F.max() / design_range_N:.3g} x the design's whole range "
            f"({design_range_N:.4g} N): is the column in another unit (grams, mN)? "
            f"{FORCE_COLUMN} must be newtons",
        )
    if F.max() < 0.02 * design_range_N:
        raise InputError(
            f"{lt.source} {FORCE_COLUMN}",
            float(F.max()),
            f"the largest force is under 2 % of the design's range ({design_range_N:.4g} N): "
            f"is the column in another unit (kN)? {FORCE_COLUMN} must be newtons, and a load "
            "test should press through the layers",
        )
