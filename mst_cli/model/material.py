"""Elastic material of the printed body."""

from __future__ import annotations

from dataclasses import dataclass


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
