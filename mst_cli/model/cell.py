"""The collapsible cell: the "hex" family's kernels and :class:`HexCell`.

Two layers of code, in the magpylib style:

* pure, vectorised kernels (``pad_half_width_mm`` ...) that take numpy arrays in mm / radians
  and return arrays, used by the design loop on thousands of candidate cells at once;
* the frozen dataclass :class:`HexCell` that wraps them for one concrete cell and adds the
  validity checks that name the violated rule.

The "hex" cell (docs/design.md section 3), profile in the x-z plane, x across the width W::

        (-p,h) ____________ (p,h)
              /            \\
    (-W/2,h/2)              (W/2,h/2)
              \\____________/
        (-p,0)              (p,0)

with p = W/2 - (h/2)/tan(theta). The inner boundary is that hexagon offset inward by the wall
thickness t. The profile is one continuous web through the whole depth D (y): the sensor prints
lying on its side, so every layer is a prism along the build direction and each print layer
draws the profile's walls and cavities as lines in the bed plane (docs/printing.md).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from mst_cli.model.arrays import stacked_terms
from mst_cli.model.file_keys import spec
from mst_cli.model.printer import Printer
from mst_cli.model.violation import Violation

if TYPE_CHECKING:
    from mst_cli.model.arrays import Floats

# Lengths are floored at this value inside the kernels so that every point of the design
# bounds -- valid or not -- gives finite numbers; the validity checks report the violation.
LENGTH_FLOOR_MM = 1e-6

# the printer a cell is judged by when none is named (0.4 mm nozzle, 0.2 mm layers)
DEFAULT_PRINTER = Printer()


# --------------------------------------------------------------------------- kernels
def pad_half_width_mm(theta_rad: Floats, h_mm: Floats, width_mm: Floats) -> np.ndarray:
    """Half width p of the outer top/bottom pad: p = W/2 - (h/2)/tan(theta)."""
    return 0.5 * width_mm - 0.5 * h_mm / np.tan(theta_rad)


def inner_pad_half_width_mm(theta_rad: Floats, t_mm: Floats, h_mm: Floats, width_mm: Floats) -> np.ndarray:
    """Half width of the inner (cavity-side) pad: the outer vertex offset inward by t.

    Offsetting the hexagon's edges by t moves the bottom vertex (p, 0) to
    (p - t tan(theta/2), t).
    """
    return pad_half_width_mm(theta_rad, h_mm, width_mm) - t_mm * np.tan(0.5 * theta_rad)


def inner_tip_half_width_mm(theta_rad: Floats, t_mm: Floats, width_mm: Floats) -> np.ndarray:
    """x of the inner hexagon's side vertex: the tip W/2 offset inward by t/sin(theta)."""
    return 0.5 * width_mm - t_mm / np.sin(theta_rad)


def wall_centreline_length_mm(theta_rad: Floats, t_mm: Floats, h_mm: Floats) -> np.ndarray:
    """Length of one inclined wall along its centre line (offset t/2 from the outside).

    The centre line rises (h - t)/2 at angle theta: L = (h - t) / (2 sin theta). Floored at
    LENGTH_FLOOR_MM so that degenerate cells (h <= t) still give finite stiffness.
    """
    return np.maximum(0.5 * (h_mm - t_mm) / np.sin(theta_rad), LENGTH_FLOOR_MM)


def cavity_height_mm(t_mm: Floats, h_mm: Floats) -> Floats:
    """Clear height of the cavity at the centre, h - 2t (negative for an invalid cell)."""
    return h_mm - 2.0 * t_mm


def lock_stroke_mm(t_mm: Floats, h_mm: Floats, contact_allowance_mm: Floats) -> np.ndarray:
    """Compression d_lock at which the cavity closes: h - 2t - allowance, floored > 0."""
    return np.maximum(cavity_height_mm(t_mm, h_mm) - contact_allowance_mm, LENGTH_FLOOR_MM)


def profile_area_mm2(theta_rad: Floats, t_mm: Floats, h_mm: Floats, width_mm: Floats) -> np.ndarray:
    """Area of the hex profile's material (outer hexagon minus inner hexagon), mm^2.

    A hexagon with pad half-width a, tip half-width c and height H has area (2a + 2c)/2 * H
    ... i.e. two trapezoids: H * (a + c). The inner hexagon has a_in, c_in = W/2 - t/sin(theta)
    and height h - 2t.
    """
    a_out = pad_half_width_mm(theta_rad, h_mm, width_mm)
    c_out = 0.5 * width_mm
    a_in = inner_pad_half_width_mm(theta_rad, t_mm, h_mm, width_mm)
    c_in = inner_tip_half_width_mm(theta_rad, t_mm, width_mm)
    h_in = np.maximum(cavity_height_mm(t_mm, h_mm), 0.0)
    return h_mm * (a_out + c_out) - h_in * (a_in + c_in)


# Names of the cell validity rules, in the order :func:`cell_margins_mm` stacks them.
CELL_RULES = ("wall", "cavity_gap", "lock_stroke", "pad_width")


def cell_margins_mm(
    theta_rad: Floats,
    t_mm: Floats,
    h_mm: Floats,
    width_mm: Floats,
    contact_allowance_mm: Floats,
    min_wall_mm: Floats,
    min_gap_mm: Floats,
    nozzle_mm: Floats,
) -> np.ndarray:
    """Signed margins (mm, >= 0 satisfied) of every cell rule, stacked on a last axis.

    Shape (..., len(CELL_RULES)), order :data:`CELL_RULES`. :meth:`HexCell.margins` reads this
    kernel; the design loop calls it on thousands of candidates at once.
    """
    cavity = cavity_height_mm(t_mm, h_mm)
    return stacked_terms(  # filled in place: np.stack's array, float, at a third less on small batches
        t_mm - min_wall_mm,
        cavity - min_gap_mm,
        cavity - contact_allowance_mm,
        inner_pad_half_width_mm(theta_rad, t_mm, h_mm, width_mm) - nozzle_mm,
    )


@dataclass(frozen=True)
class HexCell:
    """One collapsible layer of the "hex" family (docs/design.md section 3).

    Parameters are the design variables theta (deg), t (mm), h (mm) and the family constants.
    The profile runs as one continuous web through the whole depth D (the part prints on its
    side; discrete struts would start each as a mid-air island), so the web width b equals D.
    """

    theta_deg: float
    t_mm: float
    h_mm: float
    # the family constants (the file's `family` section)
    width_mm: float = spec(30.0, lo=1.0, hi=500.0, unit="mm", meaning="W, across the chevrons (x)")
    depth_mm: float = spec(
        20.0,
        lo=1.0,
        hi=500.0,
        unit="mm",
        meaning="D, along the chevrons (y): every layer is one continuous web this deep, and "
        "the part prints lying on its side, so D is also its printed height: a whole "
        "number of `printer.layer_height_mm`",
    )
    contact_allowance_mm: float = spec(
        0.1,
        lo=0.0,
        hi=10.0,
        unit="mm",
        meaning="clear gap left between the two printed pads when they touch "
        "(the roughness of their layer lines); with rigid pads a layer "
        "locks by h − 2t − a at the latest",
    )

    # -- derived quantities (all read the kernels above)
    @property
    def theta_rad(self) -> float:
        return math.radians(self.theta_deg)

    @property
    def b_mm(self) -> float:
        """Width of the web along y: the whole depth D (what the mechanics multiply by)."""
        return self.depth_mm

    @property
    def p_mm(self) -> float:
        return float(pad_half_width_mm(self.theta_rad, self.h_mm, self.width_mm))

    @property
    def p_inner_mm(self) -> float:
        return float(inner_pad_half_width_mm(self.theta_rad, self.t_mm, self.h_mm, self.width_mm))

    @property
    def wall_length_mm(self) -> float:
        return float(wall_centreline_length_mm(self.theta_rad, self.t_mm, self.h_mm))

    @property
    def cavity_height_mm(self) -> float:
        return float(cavity_height_mm(self.t_mm, self.h_mm))

    @property
    def d_lock_mm(self) -> float:
        return float(lock_stroke_mm(self.t_mm, self.h_mm, self.contact_allowance_mm))

    @property
    def profile_area_mm2(self) -> float:
        return float(profile_area_mm2(self.theta_rad, self.t_mm, self.h_mm, self.width_mm))

    def outer_profile_xz(self) -> list[tuple[float, float]]:
        """Outer hexagon, counter-clockwise from the bottom-right pad corner (mm)."""
        p, w2, h = self.p_mm, 0.5 * self.width_mm, self.h_mm
        return [(p, 0.0), (w2, 0.5 * h), (p, h), (-p, h), (-w2, 0.5 * h), (-p, 0.0)]

    def inner_profile_xz(self) -> list[tuple[float, float]]:
        """Inner (cavity) hexagon: the outer one offset inward by t, same vertex order."""
        t, h = self.t_mm, self.h_mm
        a = self.p_inner_mm
        c = float(inner_tip_half_width_mm(self.theta_rad, t, self.width_mm))
        return [(a, t), (c, 0.5 * h), (a, h - t), (-a, h - t), (-c, 0.5 * h), (-a, t)]

    def violations(self, printer: Printer = DEFAULT_PRINTER) -> list[Violation]:
        """Every broken validity rule (empty when the cell is printable and works)."""
        return [v for v in self.margins(printer) if v.margin_mm is not None and v.margin_mm < 0.0]

    def margins(self, printer: Printer = DEFAULT_PRINTER) -> list[Violation]:
        """Signed margin of every rule in mm (>= 0 satisfied); used as optimiser constraints.

        The margins come from :func:`cell_margins_mm` (one source of truth with the design loop).
        """
        margins = cell_margins_mm(
            self.theta_rad,
            self.t_mm,
            self.h_mm,
            self.width_mm,
            self.contact_allowance_mm,
            printer.min_wall_mm,
            printer.min_gap_mm,
            printer.nozzle_mm,
        )
        messages = {
            "wall": f"wall t = {self.t_mm:g} mm is thinner than the printable minimum {printer.min_wall_mm:g} mm",
            "cavity_gap": f"cavity h - 2t = {self.cavity_height_mm:g} mm is below the printable gap "
            f"{printer.min_gap_mm:g} mm",
            "lock_stroke": (
                f"cavity h - 2t = {self.cavity_height_mm:g} mm leaves no stroke after the "
                f"{self.contact_allowance_mm:g} mm contact allowance"
            ),
            "pad_width": (
                f"inner pad half-width {self.p_inner_mm:g} mm is below one nozzle "
                f"({printer.nozzle_mm:g} mm): theta too small for this h and W"
            ),
        }
        return [Violation(name, float(m), messages[name]) for name, m in zip(CELL_RULES, margins)]
