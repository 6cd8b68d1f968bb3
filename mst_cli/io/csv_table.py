"""The rows of a CSV table a user gives (a load test, a readings file): one row per line, each
cell at most :data:`MAX_CELL_CHARS` long, so that no cell reaches the csv module's own field
limit (131072 characters, a ``_csv.Error`` otherwise) and a refusal names the file, the line
and the column. Every CSV the tool reads from a user goes through :func:`csv_rows`.
"""

from __future__ import annotations

import csv
from collections.abc import Sequence

from mst_cli.errors import InputError

MAX_CELL_CHARS = 10_000  # a number needs a few dozen; a note a few hundred


def _cell_lengths(line: str, delimiter: str) -> list[int]:
    """The length of each cell of ``line``, quotes not counted: what the csv module would read,
    without reading it (a cell beyond its field limit is an exception there)."""
    lengths, n, quoted = [], 0, False
    for ch in line:
        if ch == '"':
            quoted = not quoted
        elif ch == delimiter and not quoted:
            lengths.append(n)
            n = 0
        else:
            n += 1
    return [*lengths, n]


def _column(header: Sequence[str], j: int) -> str:
    name = header[j].strip() if j < len(header) else ""
    return f"column {name!r}" if name else f"column {j + 1}"


def _too_long(source: str, line_no: int, header: Sequence[str], j: int, n: int) -> InputError:
    return InputError(
        f"{source} line {line_no} {_column(header, j)}",
        f"a cell of {n} characters",
        f"a cell holds at most {MAX_CELL_CHARS} characters",
    )


def csv_rows(numbered: Sequence[tuple[int, str]], delimiter: str, source: str) -> list[list[str]]:
    """The cells of each of the ``numbered`` lines ((line number from 1, text) each; the first
    is the header), one row per line. InputError naming the file, the line and the column for a
    cell longer than MAX_CELL_CHARS; naming the line for one the csv module cannot read."""
    rows: list[list[str]] = []
    header: Sequence[str] = ()
    for line_no, line in numbered:
        if len(line) > MAX_CELL_CHARS:  # only a line this long can hold a cell this long
            for j, n in enumerate(_cell_lengths(line, delimiter)):
                if n > MAX_CELL_CHARS:
                    raise _too_long(source, line_no, header, j, n)
        try:
            row = next(csv.reader([line], delimiter=delimiter), [])
        except csv.Error as exc:
            raise InputError(f"{source} line {line_no}", line, f"is not a CSV row ({exc})") from None
        if len(line) > MAX_CELL_CHARS:  # the exact cells, quotes read
            for j, cell in enumerate(row):
                if len(cell) > MAX_CELL_CHARS:
                    raise _too_long(source, line_no, header, j, len(cell))
        rows.append(row)
        if len(rows) == 1:
            header = row
    return rows
