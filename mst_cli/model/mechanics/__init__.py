"""Layer mechanics: a ladder of models of one collapsible layer (docs/design.md section 4).

Every model turns a :class:`~mst_cli.model.cell.HexCell` and a material into a *layer law*,
an object with

* ``displacement_mm(force_N)``: compression for forces >= 0, vectorised, monotone, and
  piecewise linear between the law's knots (a tabulated curve is linear between samples);
* ``knots_N``: ascending forces > 0 where the slope changes (the lock force among them);
* ``k_N_per_mm``: small-load stiffness; ``d_lock_mm``, ``lock_force_N``: where the cavity
  closes; ``k_locked_N_per_mm``: stiffness past the last knot (the locked branch).

The stack solver (:mod:`mst_cli.model.stack`) needs nothing else, so it is exact for every rung.

Every rung is plane strain; :func:`layer_law` and :func:`layer_laws` give the layer of the web
as printed, D deep with free faces, by handing the rung the modulus of
:func:`mst_cli.model.mechanics.depth.in_web` (every rung is linear in E). The rungs' own
functions, and :func:`uncached_layer_law` (the fits and the ladder benchmark, which compare
rungs with each other), stay plane strain.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import TYPE_CHECKING

from mst_cli.model.mechanics.depth import in_web
from mst_cli.model.mechanics.spring import spring_layer, spring_layers

if TYPE_CHECKING:
    from mst_cli.model.cell import HexCell
    from mst_cli.model.material import Material
    from mst_cli.model.mechanics.frame import TabulatedLockingLayer
    from mst_cli.model.mechanics.spring import LinearLockingLayer

MODELS = ("spring", "frame", "continuum")  # cheapest first


def layer_law(cell: HexCell, material: Material, model: str = "spring") -> LinearLockingLayer | TabulatedLockingLayer:
    """The force-displacement law of one layer with the named mechanics model.

    ``frame`` and ``continuum`` laws are cached per (cell, material): both are frozen.
    """
    return _plane_strain_law(cell, in_web(cell, material), model)


def _plane_strain_law(cell: HexCell, material: Material, model: str) -> LinearLockingLayer | TabulatedLockingLayer:
    if model == "spring":
        return spring_layer(cell, material)
    if model == "frame":
        from mst_cli.model.mechanics.frame import frame_layer  # deferred: L1 and its path follower, 6 ms

        return frame_layer(cell, material)
    if model == "continuum":
        from mst_cli.model.mechanics.continuum import continuum_layer  # deferred: L2 (scikit-fem) loads when asked

        return continuum_layer(cell, material)
    raise ValueError(f"unknown mechanics model {model!r}; choose from {', '.join(MODELS)}")


def layer_laws(
    cells: Sequence[HexCell], material: Material, model: str = "spring"
) -> tuple[LinearLockingLayer | TabulatedLockingLayer, ...]:
    """:func:`layer_law` of every cell of a stack; the spring rung's in one kernel call, the
    continuum rung's missing laws in parallel (:mod:`mst_cli.model.mechanics.law_cache`)."""
    if model == "spring":
        return spring_layers(cells, material, modulus_MPa=[in_web(c, material).youngs_modulus_MPa for c in cells])
    if model == "continuum":  # a third of a second a law: the missing ones side by side
        from mst_cli.model.mechanics.continuum import continuum_layer  # deferred: L2 (scikit-fem) loads when asked

        continuum_layer.solve_many((c, in_web(c, material)) for c in cells)
    return tuple(layer_law(c, material, model) for c in cells)


def uncached_layer_law(
    cell: HexCell, material: Material, model: str = "spring"
) -> LinearLockingLayer | TabulatedLockingLayer:
    """The rung's plane-strain law without the per-cell caches (for timing and for the fits,
    which compare plane-strain rungs)."""
    if model == "frame":
        from mst_cli.model.mechanics.frame import frame_layer  # deferred: as in _plane_strain_law

        return frame_layer.__wrapped__(cell, material)
    if model == "continuum":
        from mst_cli.model.mechanics.continuum import continuum_layer  # deferred: L2 (scikit-fem) loads when asked

        return continuum_layer.__wrapped__(cell, material)
    return _plane_strain_law(cell, material, model)
