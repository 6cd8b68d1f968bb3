"""Which number of a serial line is which: ``mst read --serial --columns``.

A sketch prints the numbers of a sample in its own order. A *column map* says, for each number
of a line, the chip and the quantity it is (``x``, ``y``, ``z``: the field; ``t``: the chip's
temperature in degC; ``-``: a number not read), or a *group* of roles that repeats once per
chip. Presets are named after the sketches that print them:

* ``xyz``: x y z (Adafruit's plotter form, a bare CSV);
* ``xyzt``: x y z t per chip (the MLX90393 library of T. Yapo's examples; ReSkin's one- and
  five-chip ``5X_burst_stream`` prints x, y, z, t of each chip, tab-separated) -- ``reskin`` is
  the same;
* ``txyz`` (``anyskin``): t x y z per chip, the temperature first (AnySkin's ``5X_burst_stream``).

A map of plain roles (``x,y,z,t``) is a group; roles with chip numbers (``x1,y1,z1,-,x2,y2,z2``)
place each number once. A group on a line of more chips than the model has reads the first
ones (five-chip boards read by a one-chip model read chip 1). Without ``--columns`` the line's
count decides: 3 or 4 numbers per chip of the model (x y z, or x y z t), or every chip's x y z
then one t (a readings file's row), or a header line (``X,Y,Z,T``) said before the numbers.

Pure: no I/O.
"""

from __future__ import annotations

import re
from dataclasses import dataclass

from mst_cli.errors import InputError

ROLES = ("x", "y", "z", "t", "-")
PRESETS = {
    "xyz": ("x", "y", "z"),
    "xyzt": ("x", "y", "z", "t"),
    "reskin": ("x", "y", "z", "t"),
    "txyz": ("t", "x", "y", "z"),
    "anyskin": ("t", "x", "y", "z"),
}
ROLE = re.compile(r"^([xyzt]|-)([0-9]?)$")
# a header line's names: X, Bx, magX, Bx_uT, X[uT], x2, T, T_C, temp, temperature(C) ...
HEADER_NAME = re.compile(
    r"^(?:(?:b|mag)?_?([xyz])([0-9]?)|(t|temp|temperature)([0-9]?))(?:[_\s]*(?:\(.*\)|\[.*\]|[a-zµμ]+))?$",
    re.IGNORECASE,
)
HEADER_TIME = re.compile(r"^(?:t_?(?:ms|s|us)|time.*|millis.*|ms|s|us|n|i|index|sample.*)$", re.IGNORECASE)


@dataclass(frozen=True)
class ColumnMap:
    """Roles of a line's numbers: ``group`` (repeated per chip) or ``fixed`` (one role per
    number, (chip from 0, role) or None)."""

    group: tuple[str, ...] | None = None
    fixed: tuple[tuple[int, str] | None, ...] | None = None

    def place(self, n_numbers: int, chips: int) -> tuple[tuple[int, ...], int | None] | None:
        """(the indexes of x, y, z of chips 1..``chips`` among a line's ``n_numbers`` numbers, the
        index of chip 1's temperature or None), or None when the line cannot hold them."""
        if self.group is not None:
            g = len(self.group)
            if n_numbers % g or n_numbers // g < chips:
                return None
            xyz = tuple(k * g + self.group.index(a) for k in range(chips) for a in "xyz")
            return xyz, (self.group.index("t") if "t" in self.group else None)
        assert self.fixed is not None
        if n_numbers != len(self.fixed):
            return None
        where = {role: i for i, role in enumerate(self.fixed) if role is not None}
        if any((k, a) not in where for k in range(chips) for a in "xyz"):
            return None
        return tuple(where[(k, a)] for k in range(chips) for a in "xyz"), where.get((0, "t"))


def column_map(spec: str | None) -> ColumnMap | None:
    """The map of ``--columns`` (a preset or roles; None: decide by the line). InputError naming
    the option for an unknown preset or role, a role twice, or a chip without all of x, y, z."""
    if spec is None or spec == "auto":
        return None
    text = spec.strip().lower()
    if text in PRESETS:
        return ColumnMap(group=PRESETS[text])
    allowed = f"a preset ({', '.join(PRESETS)}) or roles such as x,y,z,t or t1,x1,y1,z1,x2,y2,z2 (- skips a number)"
    parts = [p.strip() for p in re.split(r"[,\s]+", text) if p.strip()]
    matches = [ROLE.match(p) for p in parts]
    if not parts or any(m is None for m in matches):
        raise InputError("--columns", spec, allowed)
    numbered = any(m.group(2) for m in matches if m is not None)
    roles: list[tuple[int, str] | None] = []
    for m in matches:
        assert m is not None
        if m.group(1) == "-":
            roles.append(None)
            continue
        if numbered and not m.group(2):
            raise InputError("--columns", spec, "number every role (x1, ..., x2) or none: " + allowed)
        roles.append((int(m.group(2) or 1) - 1, m.group(1)))
    placed = [r for r in roles if r is not None]
    if len(set(placed)) != len(placed) or any(k < 0 for k, _ in placed):
        raise InputError("--columns", spec, "each role once per chip, chips numbered from 1")
    chips = {k for k, _ in placed}
    if not chips or any((k, a) not in placed for k in chips for a in "xyz") or chips != set(range(len(chips))):
        raise InputError("--columns", spec, "x, y and z of every chip from chip 1: " + allowed)
    if numbered:
        return ColumnMap(fixed=tuple(roles))
    return ColumnMap(group=tuple("-" if r is None else r[1] for r in roles))


def default_map(n_numbers: int, chips: int) -> ColumnMap | None:
    """The map of a line of ``n_numbers`` bare numbers without ``--columns``: x y z, or x y z t,
    per chip of the model, or every chip's x y z and then t; None for any other count (a header
    line or --columns says it)."""
    if n_numbers == 3 * chips:
        return ColumnMap(group=PRESETS["xyz"])
    if n_numbers == 4 * chips:
        return ColumnMap(group=PRESETS["xyzt"])
    if n_numbers == 3 * chips + 1:  # every chip's x y z, then one temperature (a readings file's row)
        return ColumnMap(fixed=(*((k, a) for k in range(chips) for a in "xyz"), (0, "t")))
    return None


def header_map(names: list[str]) -> ColumnMap | None:
    """The map a header line (``X,Y,Z,T``; ``time,Bx,By,Bz``) says, or None when it is not one:
    every name a field axis, a temperature or a count/time, and x, y, z of chip 1 among them."""
    roles: list[tuple[int, str] | None] = []
    for name in names:
        m = HEADER_NAME.match(name.strip())
        if m is None:
            if HEADER_TIME.match(name.strip()) is None:
                return None
            roles.append(None)
            continue
        axis, chip = (m.group(1), m.group(2)) if m.group(1) else ("t", m.group(4))
        roles.append((max(int(chip or 1), 1) - 1, axis.lower()))
    placed = [r for r in roles if r is not None]
    if len(set(placed)) != len(placed) or any((0, a) not in placed for a in "xyz"):
        return None
    return ColumnMap(fixed=tuple(roles))
