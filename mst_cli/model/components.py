"""Bought components: the board and connector types and their catalogue (magnet grades,
magnetometer boards).

Facts only, each with its source; the one law here is the remanence's linear, reversible
temperature dependence its coefficient is quoted for (:func:`remanence_at_T`).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from mst_cli.model.temperature import REFERENCE_TEMPERATURE_C, remanence_scale


@dataclass(frozen=True)
class Connector:
    """A part on the board's top face that the housing must clear, mm from the board's
    lower-left corner. ``facing`` is the side its mouth opens to ("-x" or "+x"): the housing
    leaves a window there for the cable."""

    x0_mm: float
    x1_mm: float
    y0_mm: float
    y1_mm: float
    height_mm: float
    facing: str


@dataclass(frozen=True)
class Board:
    """A magnetometer carrier board (the catalogue is :data:`BOARDS` below)."""

    key: str
    name: str
    length_mm: float  # along x (the cell width direction)
    width_mm: float  # along y
    thickness_mm: float
    chip_x_mm: float  # chip centre from the board's lower-left corner
    chip_y_mm: float
    holes_xy_mm: tuple[tuple[float, float], ...] = ()
    hole_diameter_mm: float = 2.5
    chip_size_mm: float = 3.0  # QFN-16, 3 x 3 x 1 mm, Hall plates at its centre
    chip_height_mm: float = 1.0
    connectors: tuple[Connector, ...] = ()

    @property
    def headroom_mm(self) -> float:
        """Height of the tallest part on the board's top face (the chip or a connector)."""
        return max([self.chip_height_mm] + [c.height_mm for c in self.connectors])


# NdFeB remanence Br (T), typical range per grade; the tool uses the mid value.
# Source: manufacturers' grade tables, as collected in docs/design.md section 8.
MAGNET_GRADES_T: dict[str, tuple[float, float]] = {
    "N35": (1.17, 1.22),
    "N38": (1.22, 1.26),
    "N40": (1.25, 1.29),
    "N42": (1.28, 1.32),
    "N45": (1.32, 1.37),
    "N48": (1.37, 1.42),
    "N50": (1.40, 1.45),
    "N52": (1.43, 1.48),
}


# Sintered NdFeB's elastic constants, any grade: E 150-160 GPa, nu 0.24 (magnet makers' physical
# property tables, e.g. Arnold Magnetic Technologies' NdFeB data: Young's modulus 160 GPa).
NDFEB_ELASTIC = {"youngs_modulus_MPa": 160e3, "poisson_ratio": 0.24}


def grade_remanence_T(grade: str) -> float:
    lo, hi = MAGNET_GRADES_T[grade]
    return round(0.5 * (lo + hi), 4)


# Reversible temperature coefficient of the remanence, alpha(Br) in %/K, per grade (20..100 degC):
# -0.12 %/K, typical of sintered NdFeB N-grades (the standard, no-suffix N35..N52), the figure
# magnet makers' grade datasheets and temperature tables give for the family. Not checked here
# against one named sheet: a typical value, measure the batch when it matters.
MAGNET_REMANENCE_COEFF_PCT_PER_K: dict[str, float] = dict.fromkeys(MAGNET_GRADES_T, -0.12)
NDFEB_REMANENCE_COEFF_PCT_PER_K = -0.12  # a remanence given as a number (no grade): the family's


def remanence_at_T(
    grade_or_Br: str | float,
    T_C: float | np.ndarray,
    T_ref_C: float = REFERENCE_TEMPERATURE_C,
    coeff_pct_per_K: float | None = None,
) -> float | np.ndarray:
    """Remanence (T) at ``T_C``: Br(T_ref) (1 + alpha (T - T_ref)), with Br(T_ref) a grade's mid
    value or the number given and alpha the grade's reversible coefficient (or ``coeff_pct_per_K``;
    NdFeB's for a bare number). The reversible, linear part only: above the grade's maximum
    working temperature (80 degC for the plain N grades) the loss is partly irreversible."""
    if isinstance(grade_or_Br, str):
        Br = grade_remanence_T(grade_or_Br)
        alpha = MAGNET_REMANENCE_COEFF_PCT_PER_K[grade_or_Br] if coeff_pct_per_K is None else coeff_pct_per_K
    else:
        Br = float(grade_or_Br)
        alpha = NDFEB_REMANENCE_COEFF_PCT_PER_K if coeff_pct_per_K is None else coeff_pct_per_K
    out = Br * remanence_scale(T_C, alpha, T_ref_C)
    return float(out) if np.ndim(out) == 0 else out


# Carrier boards of the MLX90393. Dimensions read off the boards' published design files
# (docs/design.md section 8); measure a real board before relying on a tight fit.
# The SparkFun board is the Qwiic standard 1 x 1 inch with the chip at its centre (nominal; the
# reference data gives no dimensions for it). The bare QFN entry is a 10 x 10 mm custom carrier
# with the chip at its centre.
# STEMMA QT and Qwiic are JST SH 4-pin side-entry sockets (SM04B-SRSS-TB): 2.95 mm mounting
# height (JST SH catalogue), taken here as 6.0 mm along the board edge and 4.25 mm deep, mouth
# flush with the board's short edges, centred on them (nominal, from product photos: measure).
_JST_SH_H_MM, _JST_SH_W_MM, _JST_SH_D_MM = 2.95, 6.0, 4.25


def _edge_sockets(length_mm: float, width_mm: float) -> tuple[Connector, Connector]:
    y0, y1 = 0.5 * (width_mm - _JST_SH_W_MM), 0.5 * (width_mm + _JST_SH_W_MM)
    return (
        Connector(0.0, _JST_SH_D_MM, y0, y1, _JST_SH_H_MM, "-x"),
        Connector(length_mm - _JST_SH_D_MM, length_mm, y0, y1, _JST_SH_H_MM, "+x"),
    )


BOARDS: dict[str, Board] = {
    "adafruit-4022": Board(
        key="adafruit-4022",
        name="Adafruit 4022 MLX90393 (STEMMA QT)",
        length_mm=25.4,
        width_mm=17.78,
        thickness_mm=1.6,
        chip_x_mm=12.6,
        chip_y_mm=8.3,
        holes_xy_mm=((2.54, 2.54), (22.86, 2.54), (2.54, 15.24), (22.86, 15.24)),
        connectors=_edge_sockets(25.4, 17.78),
    ),
    "adafruit-4022-original": Board(
        key="adafruit-4022-original",
        name="Adafruit 4022 MLX90393 (original)",
        length_mm=22.86,
        width_mm=19.05,
        thickness_mm=1.6,
        chip_x_mm=11.43,
        chip_y_mm=9.525,
    ),
    "sparkfun-14571": Board(
        key="sparkfun-14571",
        name="SparkFun SEN-14571 MLX90393 (Qwiic)",
        length_mm=25.4,
        width_mm=25.4,
        thickness_mm=1.6,
        chip_x_mm=12.7,
        chip_y_mm=12.7,
        connectors=_edge_sockets(25.4, 25.4),
    ),
    "bare-qfn": Board(
        key="bare-qfn",
        name="bare MLX90393 QFN-16 on a 10 x 10 mm custom board",
        length_mm=10.0,
        width_mm=10.0,
        thickness_mm=1.0,
        chip_x_mm=5.0,
        chip_y_mm=5.0,
    ),
}

DEFAULT_BOARD = "adafruit-4022"


@dataclass(frozen=True)
class InsertMaterial:
    """A stiff plate's material (the spec's ``insert.material``): Young's modulus and Poisson's
    ratio at room temperature, and where the figures come from."""

    key: str
    name: str
    youngs_modulus_MPa: float
    poisson_ratio: float
    source: str

    @property
    def plane_strain_modulus_MPa(self) -> float:
        """E/(1 - nu^2): a plate bent across the face, held along the depth (docs/design.md 4.6)."""
        return self.youngs_modulus_MPa / (1.0 - self.poisson_ratio**2)


# Printed plates take the figure of a printed test bar in the bed plane (the plate prints flat),
# not the resin's (injection-moulded bars are 20-40 % stiffer): the load path errs soft.
INSERT_MATERIALS: dict[str, InsertMaterial] = {
    m.key: m
    for m in (
        InsertMaterial(
            "pla",
            "printed PLA plate",
            2539.0,
            0.36,
            "Stratasys FDM PLA data sheet: tensile modulus 2539 MPa (ASTM D638, printed XY); nu typical of PLA",
        ),
        InsertMaterial(
            "petg",
            "printed PETG plate",
            2100.0,
            0.38,
            "Eastman Eastar 6763 copolyester (PETG resin): tensile modulus 2100 MPa; printed XY bars 2-3 GPa",
        ),
        InsertMaterial(
            "steel",
            "steel shim",
            200e3,
            0.30,
            "carbon spring steel shim (AISI 1095 / 1.1274): E 200-210 GPa, nu 0.29-0.30 (handbook values)",
        ),
    )
}
NO_INSERT = "none"


def default_board() -> Board:
    return BOARDS[DEFAULT_BOARD]
