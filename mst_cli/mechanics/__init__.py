"""Layer mechanics: a ladder of models of one collapsible layer (DESIGN.md section 4).

Every model turns a :class:`~mst_cli.geometry.HexCell` and a material into a layer law with
``displacement_mm(force_N)`` (monotone), ``k_N_per_mm``, ``d_lock_mm`` and ``lock_force_N``;
the stack solver needs nothing else.
"""

from __future__ import annotations

MODELS = ("spring",)  # cheapest first; dearer rungs register here


def layer_law(cell, material, model: str = "spring"):
    """The force-displacement law of one layer with the named mechanics model."""
    if model == "spring":
        from .spring import spring_layer
        return spring_layer(cell, material)
    raise ValueError(f"unknown mechanics model {model!r}; choose from {', '.join(MODELS)}")
