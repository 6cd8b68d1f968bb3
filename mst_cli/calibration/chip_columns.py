"""The other chips' columns of a readings file, for a sensor with more than one MLX90393
(``magnetometer.positions_mm``): chip 1 keeps the plain names (Bx_uT, By_uT, Bz_uT or the raw
Bx_code_lsb, ...), chip k of 2 to 4 has the same names with k after the axis (Bx2_uT, By2_uT,
Bz2_uT; Bx2_code_lsb, ...), in the same unit as chip 1's and in the order positions_mm lists
the chips.
"""

from __future__ import annotations

import re

from mst_cli.errors import InputError

MAX_CHIPS = 4  # as magnetometer.positions_mm allows
CHIP_COLUMN = re.compile(r"^B([xyz])([0-9]+)_(uT|code_lsb)$")  # matched, then its number checked as written


def chip_column_names(chip: int, raw: bool) -> tuple[str, str, str]:
    """Chip ``chip``'s (from 2) three column names."""
    unit = "code_lsb" if raw else "uT"
    return tuple(f"B{axis}{chip}_{unit}" for axis in "xyz")  # type: ignore[return-value]


def is_chip_column(name: str) -> bool:
    return CHIP_COLUMN.match(name) is not None


def extra_chip_columns(source: str, header: list[str], raw: bool) -> list[tuple[str, str, str]]:
    """The column names of chips 2.. of ``header`` (chip 1's unit: ``raw`` codes or uT), in chip
    order; InputError for a chip number out of 2..MAX_CHIPS, a chip missing an axis, a chip
    skipped, or a unit other than chip 1's."""
    chips: dict[int, set[str]] = {}
    for name in header:
        m = CHIP_COLUMN.match(name)
        if m is None:
            continue
        axis, chip, unit = m.group(1), int(m.group(2)), m.group(3)
        if not 2 <= chip <= MAX_CHIPS or m.group(2) != str(chip):  # Bx02_uT is not Bx2_uT: names match exactly
            raise InputError(
                f"{source} column {name!r}",
                name,
                f"chips are numbered 2 to {MAX_CHIPS} after chip 1's Bx_uT, as written in Bx2_uT (no leading zero)",
            )
        if (unit == "code_lsb") != raw:
            first = "raw codes" if raw else "uT"
            raise InputError(f"{source} column {name!r}", name, f"chip 1's field is in {first}: give every chip's so")
        chips.setdefault(chip, set()).add(axis)
    for k in range(2, max(chips, default=1) + 1):
        missing = [c for c, axis in zip(chip_column_names(k, raw), "xyz") if axis not in chips.get(k, set())]
        if missing:
            raise InputError(f"{source} header", ",".join(header), f"missing column(s) {', '.join(missing)}")
    return [chip_column_names(k, raw) for k in sorted(chips)]


def check_chips_match(source: str, readings_chips: int, model_chips: int, estimate: str) -> None:
    """InputError when a file's chips and the model's differ: a file with more chips than the model
    places, or a model of several chips read for the shear without every chip's columns."""
    if readings_chips > model_chips:
        raise InputError(
            f"{source} header",
            ", ".join(chip_column_names(model_chips + 1, False)),
            f"the model places {model_chips} chip(s) (magnetometer.positions_mm): columns of more chips are not read",
        )
    if estimate == "shear" and readings_chips < model_chips:
        raise InputError(
            f"{source} header",
            f"{readings_chips} chip(s)",
            f"the model places {model_chips} chips (magnetometer.positions_mm): --estimate shear reads every "
            f"chip's columns ({', '.join(chip_column_names(readings_chips + 1, False))} ...)",
        )
