"""Elastic material of the printed body."""

from __future__ import annotations

from dataclasses import dataclass

# A plane-strain neo-Hookean half-space's free face creases at a compressive stretch of about
# 0.65 (Hong, Zhao and Suo, Appl. Phys. Lett. 95, 111901 (2009)). A steep wall's outer root is
# squeezed past it before the lock; L2's default mesh cannot form the crease, so there its lock
# force is an upper bound by a few per cent (docs/design.md section 4; studies/design_crease.py)
CREASE_ONSET_STRETCH = 0.65


@dataclass(frozen=True)
class Material:
    """Small-strain isotropic elastic constants.

    Default TPU Shore 85A: E = 12 MPa (NinjaTek NinjaFlex technical data sheet, tensile
    modulus), nu = 0.45 (typical of thermoplastic polyurethane elastomers).
    """

    name: str = "TPU Shore 85A"
    youngs_modulus_MPa: float = 12.0
    poisson_ratio: float = 0.45

    @property
    def shear_modulus_MPa(self) -> float:
        return self.youngs_modulus_MPa / (2.0 * (1.0 + self.poisson_ratio))
