"""What the walls as sliced do to the sensor: the design export.json carries, simulated with the
wall thicknesses the G-code lays down in place of the drawn ones, beside the design itself.

Both runs are :func:`mst_cli.sensor.as_printed.simulate_as_printed` (what ``mst simulate`` runs: the
file's mechanics and field model, the printer section's corrections), so the only difference between
the two columns is each layer's wall thickness t. The thickness comes from
:func:`mst_cli.cad.print_check.walls_as_sliced`; the design (export.json's ``design``) is read
with the design-file rules before anything is sliced (:mod:`mst_cli.cad.manifest`).
"""

from __future__ import annotations

from mst_cli.errors import InputError
from mst_cli.sensor.as_printed import simulate_as_printed, with_walls
from mst_cli.sensor.document import Document, design_geometry


def _change(new: float | None, old: float | None) -> float | None:
    return (new - old) / old if new is not None and old else None


def predict(doc: Document, sliced_t_mm: list[float]) -> dict:
    """S_i and R_i of ``doc`` as designed and with layer i's wall ``sliced_t_mm[i]`` (a row per
    regime, relative changes), or ``{"error": why}`` when the sliced walls make no sensor the
    model can run (a wall missing, a cavity closed)."""
    designed = simulate_as_printed(doc)
    if min(sliced_t_mm) <= 0:
        return {"error": "a wall is missing from the G-code (sliced width 0): nothing to simulate"}
    try:
        walls = with_walls(doc, sliced_t_mm)
        design_geometry(walls)  # the cell rules a working cell keeps (lock stroke)
        sliced = simulate_as_printed(walls)
    except InputError as exc:
        return {"error": f"the walls as sliced make no working cell: {exc}"}
    rows = []
    for i in range(max(len(designed.regimes), len(sliced.regimes))):
        d = designed.regimes[i] if i < len(designed.regimes) else None
        s = sliced.regimes[i] if i < len(sliced.regimes) else None
        row = {
            "regime": i + 1,
            "locking_layer_designed": d.layer if d else None,
            "locking_layer_sliced": s.layer if s else None,
            "S_designed_per_N": d.sensitivity_secant_per_N if d else None,
            "S_sliced_per_N": s.sensitivity_secant_per_N if s else None,
            "R_designed_N": d.force_to_N if d else None,
            "R_sliced_N": s.force_to_N if s else None,
        }
        row["S_change_rel"] = _change(row["S_sliced_per_N"], row["S_designed_per_N"]) if d and s else None
        row["R_change_rel"] = _change(row["R_sliced_N"], row["R_designed_N"]) if d and s else None
        rows.append(row)
    return {
        "mechanics": designed.mechanics,
        "field_model": designed.field_model,
        "printer_wall_offset_mm": doc.printer.wall_offset_mm,
        "regimes": rows,
    }
