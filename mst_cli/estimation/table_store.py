"""Where a model's inverse table is found, built and kept: beside the calibrated model (``mst
calibrate --offset-table`` writes ``inverse_table.npz``, ``--shear-table`` ``shear_table.npz`` beside
calibrated.yaml), else in the user's cache keyed by its hash, else built now and kept there (issue
45 item 5: a table is built once per model, whatever ``--out`` says). A table is current when its
hash is that of the model file, its calibration.json, the mechanics, the grid and the physics
modules' source (:func:`~mst_cli.estimation.inverse_table.source_hash`).

The readers on the tables are :mod:`mst_cli.estimation.table_reader`'s; this module is their
file side.
"""

from __future__ import annotations

import time
import zipfile
from collections.abc import Callable
from pathlib import Path
from typing import Any, BinaryIO

import numpy as np

from mst_cli.errors import CalibrationFailed, InputError
from mst_cli.estimation.inverse_map import InverseMap
from mst_cli.estimation.inverse_table import (
    GRID_DEFAULT,
    SHEAR_GRID_DEFAULT,
    SHEAR_TABLE_FILE,
    SHEAR_TABLE_RATIO,
    TABLE_FILE,
    Edges,
    InverseTable,
    TableGrid,
    build_table,
    kink_edges_N,
    source_hash,
)
from mst_cli.io.cache import cached_path, keep, touch
from mst_cli.io.files import read_input_text
from mst_cli.io.yaml_io import MAX_INPUT_BYTES
from mst_cli.model.general_load import LoadedStack
from mst_cli.model.offcentre import section_members_pose
from mst_cli.model.stack_pose import tilt_laws
from mst_cli.sensor.as_printed import CALIBRATION_JSON
from mst_cli.sensor.document import Document


def table_edges_N(doc: Document, imap: InverseMap, mechanics: str, lever: float) -> np.ndarray:
    """The edges the force nodes of the model's tables follow: the inverse map's regimes and the
    kinks of the laws the tables are built from (:func:`kink_edges_N`)."""
    laws = tilt_laws(doc.geometry(), doc.material, mechanics, lever, doc.whole_part)
    return kink_edges_N(laws, imap.edges_N, float(imap.force_N[-1]))


def table_hash(model_file: Path, mechanics: str, grid: TableGrid) -> str:
    """The hash a current table of ``grid`` beside ``model_file`` carries."""
    return source_hash(_text(model_file) or "", _text(model_file.parent / CALIBRATION_JSON), mechanics, grid)


def _text(path: Path) -> str | None:
    """A file's text read as every input file is (None: none to read there)."""
    try:
        return read_input_text(path, MAX_INPUT_BYTES, field=str(path))
    except InputError:
        return None


def grid_of(
    kind: str, doc: Document, force_max_N: float, grid: tuple[int, float] | None = None, edges_N: Edges = None
) -> TableGrid:
    """The table grid of ``kind`` (offset: forces, mm between offsets; shear: forces, the step of
    the ratios up to SHEAR_TABLE_RATIO; the default when ``grid`` is None), its force nodes
    following the regimes ``edges_N`` (the inverse map's) when given."""
    if kind == "shear":
        n, step = grid or SHEAR_GRID_DEFAULT
        return TableGrid.cone(force_max_N, n, SHEAR_TABLE_RATIO, step, edges_N)
    return TableGrid.over(doc.geometry(), force_max_N, *(grid or GRID_DEFAULT), edges_N=edges_N)


def build_beside(
    model_file: Path,
    doc: Document,
    mechanics: str,
    lever_factor: float,
    force_max_N: float,
    grid: tuple[int, float] | None = None,
    kind: str = "offset",
    edges_N: Edges = None,
) -> InverseTable:
    """The table of ``kind`` and ``grid`` (:func:`grid_of`, its forces following the regimes
    ``edges_N``) for the model in ``model_file``, hashed as current beside it."""
    g = grid_of(kind, doc, force_max_N, grid, edges_N)
    source = table_hash(model_file, mechanics, g)
    geometry, material = doc.geometry(), doc.material
    members = section_members_pose(geometry, material, mechanics, doc.section_rung)
    return build_table(geometry, material, mechanics, g, lever_factor, source, doc.whole_part, members)


def table_beside(
    model_file: Path,
    doc: Document,
    mechanics: str,
    lever_factor: float,
    force_max_N: float,
    kind: str = "offset",
    edges_N: Edges = None,
) -> tuple[InverseTable, str | None]:
    """The table of ``kind`` of the model in ``model_file``: the one beside it when it is current
    (of any grid: the one its maker chose), else the one an earlier call kept in the cache (of the
    default grid, found by its hash), else one built now and kept there for the next call; and a
    note saying what was built or passed over (None: a table beside it was current). Every file
    is read through :meth:`InverseTable.read`: one that is not a good table is passed over and
    named. CalibrationFailed naming the file when no table can be built."""
    path = model_file.parent / (SHEAR_TABLE_FILE if kind == "shear" else TABLE_FILE)
    table, why = InverseTable.read(path)
    if (
        table is not None
        and table.grid.kind == kind
        and table.source_hash == table_hash(model_file, mechanics, table.grid)
    ):
        return table, None
    passed = None if why == "file not found" else f"{path} is {why or 'stale'}"
    key = table_hash(model_file, mechanics, grid_of(kind, doc, force_max_N, edges_N=edges_N))
    kept = cached_path(f"{kind}-{key}.npz")
    found = InverseTable.read(kept)[0] if kept is not None else None
    if found is not None and found.grid.kind == kind and found.source_hash == key:
        touch(kept)  # type: ignore[arg-type]  # found: kept is a path
        return found, None if passed is None else f"{passed}: used the {kind} table kept in {kept}"
    t0 = time.perf_counter()
    try:
        table = build_beside(model_file, doc, mechanics, lever_factor, force_max_N, kind=kind, edges_N=edges_N)
    except (CalibrationFailed, ValueError, FloatingPointError) as exc:
        raise CalibrationFailed(
            f"{passed or f'{path} is missing'} and the {kind} table cannot be rebuilt: {exc}"
        ) from None
    stored, not_kept = keep(f"{kind}-{key}.npz", table.dump)
    where = f"kept it in {stored} for the next call" if stored else f"could not keep it for the next call: {not_kept}"
    note = (
        f"{passed or f'{path} is missing'}: built the {kind} table in {time.perf_counter() - t0:.0f} s, {where} "
        f"and wrote it with the results (mst calibrate --{kind}-table writes it beside the model)"
    )
    return table, note


def two_chip_layer_tables(stack: LoadedStack, say: Callable[[str], None] | None = None) -> list:
    """The two-chip reader's layer tables of ``stack`` at its default nodes
    (:func:`~mst_cli.estimation.layer_tables.layer_tables`): the ones an earlier call kept in the
    cache, found by the hash of everything they are built from, else built now (``say`` is told
    first: seconds) and kept there for the next call."""
    # deferred: the layer tables' compiled read loads numba, which no one-chip read needs
    from mst_cli.estimation.layer_tables import LayerTable, layer_tables, tables_key
    from mst_cli.estimation.two_chip_table import N_FORCE, RATIO_MAX, STEP_MM, table_top_N

    top = table_top_N(stack)
    key = tables_key(stack, top, RATIO_MAX, N_FORCE, STEP_MM)
    kept = cached_path(f"two-chip-{key}.npz")
    if kept is not None:
        found = _read_layer_tables(kept, key, len(stack.tilt), LayerTable)
        if found is not None:
            touch(kept)
            return found
    if say is not None:
        say(
            "building the two-chip reader's layer tables (about 10 s on one core, once per model: kept in the "
            "cache for the next call; the first two-chip read after an install also compiles its kernels, about 6 s)"
        )
    tables = layer_tables(stack, top, RATIO_MAX, N_FORCE, STEP_MM)
    _, not_kept = keep(f"two-chip-{key}.npz", lambda fh: _write_layer_tables(tables, key, fh))
    if not_kept is not None and say is not None:
        say(f"could not keep the two-chip reader's layer tables for the next call: {not_kept}")
    return tables


def _write_layer_tables(tables: list, key: str, fh: BinaryIO) -> None:
    arrays: dict[str, Any] = {"key": np.array(key)}
    for j, t in enumerate(tables):
        arrays.update({f"force_N_{j}": t.force_N, f"x_mm_{j}": t.x_mm, f"y_mm_{j}": t.y_mm, f"state_{j}": t.state})
    np.savez(fh, **arrays)


def _read_layer_tables(path: Path, key: str, layers: int, table_type) -> list | None:
    """The layer tables kept in ``path`` for ``key`` (None: missing, stale, or not such a file)."""
    try:
        with np.load(path, allow_pickle=False) as f:
            if str(f["key"]) != key:
                return None
            out = []
            for j in range(layers):
                F, x, y, state = (np.asarray(f[f"{n}_{j}"], dtype=float) for n in ("force_N", "x_mm", "y_mm", "state"))
                if state.shape != (len(F), len(x), len(y), 3) or not np.all(np.isfinite(state)):
                    return None
                out.append(table_type(F, x, y, np.ascontiguousarray(state)))
            return out
    except (OSError, KeyError, ValueError, EOFError, zipfile.BadZipFile):  # not a kept table: built anew
        return None
