"""``mst read --estimate offset`` and ``--estimate shear`` at stream speed: the one-chip readers
on the model's :class:`~mst_cli.estimation.inverse_table.InverseTable` of that kind, and the
two-chip reader of all five unknowns (:mod:`~mst_cli.estimation.two_chip_table`), each polished
by the exact solve where asked.

The tables come from :mod:`~mst_cli.estimation.table_store` (beside the model, else the cache,
else built once and kept).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from mst_cli.errors import InputError
from mst_cli.estimation.inverse_map import InverseMap
from mst_cli.estimation.inverse_table import (
    FIT_SIGMAS,
    InverseTable,
    TableEstimates,
)
from mst_cli.estimation.load_readings import LoadReadings, from_estimates
from mst_cli.estimation.offset_reading import DEFAULT_MAX_SIGMA_MM, OffsetEstimator, OffsetReadings
from mst_cli.estimation.shear_reading import CHI2_FLAG, ShearReader
from mst_cli.estimation.table_store import build_beside, table_beside, table_edges_N, two_chip_layer_tables
from mst_cli.model.general_load import loaded_stack
from mst_cli.model.load_bound import crb_sigma
from mst_cli.model.offcentre import section_members_pose
from mst_cli.sensor.document import Document

if TYPE_CHECKING:  # the two-chip reader's compiled kernels load numba: only a two-chip read imports it
    from mst_cli.estimation.two_chip_table import TwoChipReader


@dataclass
class OffsetTableReader:
    """(force, x0, y0) of readings from a table, with the chip's noise ``sigma_T``; ``exact``
    (the model's Gauss-Newton) polishes the best root the direct inverse found when given."""

    table: InverseTable
    sigma_T: float
    max_sigma_mm: float
    exact: OffsetEstimator | None = None
    chips = 1  # the readings it takes: chip 1's

    def estimate_table(self, B_T: np.ndarray) -> TableEstimates:
        """The direct inverse's estimates of readings (n, 3) in T, polished when ``exact`` is set."""
        est = self.table.estimate(B_T, self.sigma_T, self.max_sigma_mm)
        if self.exact is not None:
            self._polish(B_T, est)
        return est

    def _polish(self, B_T: np.ndarray, est: TableEstimates) -> None:
        """The exact solve from each reading's best root; its root, its Cramer-Rao sigmas and its
        identifiability replace the table's (the table's ambiguity stands). A solve that ends on
        the box's edge (a force past the range's end, a press off the face) further off the
        reading than the noise allows found no root: ``no_fit``, which the table's coarser slab
        error had let pass (a force no sensor can give, issue 46)."""
        assert self.exact is not None
        for i in np.flatnonzero(np.isin(est.flag, ("ok", "not_identifiable"))):
            s = self.exact._solve_from(B_T[i], est.best[i].copy())
            if s.misfit_T > FIT_SIGMAS * self.sigma_T and self.exact.on_box_edge(s.p):
                est.flag[i] = "no_fit"
                est.force_N[i] = est.x_mm[i] = est.y_mm[i] = np.nan
                est.sigma_force_N[i] = est.sigma_x_mm[i] = est.sigma_y_mm[i] = np.nan
                continue
            if not (s.converged and s.misfit_T <= FIT_SIGMAS * self.sigma_T):
                continue  # the table's root stands (the exact solve stalled)
            sig = self.exact._sigmas(s.J)
            est.best[i] = s.p
            ok = bool(np.all(np.isfinite(sig)) and max(sig[1], sig[2]) <= self.max_sigma_mm)
            est.flag[i] = "ok" if ok else "not_identifiable"
            values = (*s.p, *sig) if ok else (np.nan,) * 6
            est.force_N[i], est.x_mm[i], est.y_mm[i] = values[:3]
            est.sigma_force_N[i], est.sigma_x_mm[i], est.sigma_y_mm[i] = values[3:]

    def estimate_all(self, B_T: np.ndarray, force_axial_N: np.ndarray) -> OffsetReadings:
        """Every reading with a finite centred force (the others keep their own flag, and "" here);
        a reading not ``ok`` keeps its centred force."""
        n = len(B_T)
        use = np.isfinite(force_axial_N)
        cols = np.full((6, n), np.nan)
        flag = np.full(n, "", dtype=object)
        if use.any():
            est = self.estimate_table(np.asarray(B_T, dtype=float)[use])
            cols[:, use] = [est.force_N, est.x_mm, est.y_mm, est.sigma_x_mm, est.sigma_y_mm, est.sigma_force_N]
            flag[use] = est.flag
        ok = flag == "ok"
        F = np.where(ok, cols[0], force_axial_N)
        return OffsetReadings(F, cols[1], cols[2], cols[3], cols[4], cols[5], flag)


@dataclass
class ShearTableReader:
    """(Fz, Fx, Fy) of centred presses from the shear table, with the chip's noise ``sigma_T``;
    ``exact`` (the general load's Gauss-Newton, :class:`ShearReader`) polishes each reading's best
    root when given."""

    table: InverseTable
    sigma_T: float
    exact: ShearReader | None = None
    chips = 1  # the readings it takes: chip 1's

    def estimate_all(self, B_T: np.ndarray, force_axial_N: np.ndarray) -> LoadReadings:
        """Every reading with a finite centred force (the others keep their own flag, and "" here);
        a reading not ``ok`` keeps its centred force."""
        use = np.isfinite(force_axial_N)
        B = np.asarray(B_T, dtype=float)[use]
        est = self.table.estimate(B, self.sigma_T, np.inf)
        if self.exact is not None:
            self._polish(B, est)
        zeros = np.zeros((len(B), 2))
        five = np.column_stack([est.p, np.where(est.flag[:, None] == "ok", zeros, np.nan)])
        sig = np.column_stack([est.sigma, np.full((len(B), 2), np.nan)])
        return from_estimates(five, sig, est.flag, np.asarray(force_axial_N, dtype=float), "centred")

    def _polish(self, B_T: np.ndarray, est: TableEstimates) -> None:
        """The exact fit from each ok reading's root; it replaces the table's where it stays within
        the noise (the table's flags stand)."""
        assert self.exact is not None
        ok = np.flatnonzero(est.flag == "ok")
        theta = np.column_stack([est.best[ok], np.zeros((len(ok), 2))])
        p, sig, chi2 = self.exact.fit(B_T[ok], self.sigma_T, theta)
        kept = chi2 <= CHI2_FLAG[0]
        est.p[ok[kept]], est.sigma[ok[kept]] = p[kept, :3], sig[kept]


@dataclass
class TwoChipLoadReader:
    """All five unknowns (Fz, Fx, Fy, x, y) of readings of every chip (the fast two-chip reader,
    :mod:`~mst_cli.estimation.two_chip_table`), polished by the exact fit when ``polish``."""

    reader: TwoChipReader
    polish: bool = False

    @property
    def chips(self) -> int:
        return len(self.reader.model.chips_mm)

    def estimate_all(self, B_T: np.ndarray, force_axial_N: np.ndarray) -> LoadReadings:
        """Readings (n, k, 3) in T with a finite centred force (from chip 1; the others keep their
        own flag, and "" here); a reading not ``ok`` keeps its centred force."""
        use = np.isfinite(force_axial_N)
        B = np.asarray(B_T, dtype=float)[use]
        if not len(B):  # every reading flagged before the estimate
            return from_estimates(np.empty((0, 5)), np.empty((0, 5)), np.empty(0, dtype=object), force_axial_N, "none")
        est = self.reader.estimate(B)
        if self.polish and len(B):
            est = self.reader.polish(B, est)
        return from_estimates(est.theta, est.sigma, est.flag, np.asarray(force_axial_N, dtype=float), "none")


def two_chip_reader(
    doc: Document,
    imap: InverseMap,
    lever: float,
    mechanics: str,
    polish: bool,
    say: Callable[[str], None] | None = None,
) -> TwoChipLoadReader:
    """The two-chip reader of the model ``doc`` (its chips, the inverse map's field resolution as
    the noise, ``lever``: its calibration's factor): its layer tables from the cache, else built now
    (``say`` told first: seconds) and kept (:func:`~mst_cli.estimation.table_store.two_chip_layer_tables`)."""
    # deferred: the two-chip reader's compiled kernels load numba, which no one-chip read needs
    from mst_cli.estimation.two_chip_table import RATIO_MAX, TwoChipModel, TwoChipReader

    g, m = doc.geometry(), doc.material
    members = section_members_pose(g, m, mechanics, doc.section_rung)
    stack = loaded_stack(g, m, mechanics, lever, doc.whole_part, members)
    chips = [(float(c[0]), float(c[1])) for c in doc.chips_mm]
    model = TwoChipModel(stack, chips, two_chip_layer_tables(stack, say), RATIO_MAX)
    return TwoChipLoadReader(TwoChipReader(stack, doc.chips_mm, imap.field_resolution_T, model=model), polish)


def offset_table_reader(
    doc: Document, imap: InverseMap, lever: float, model_file: Path, mechanics: str, max_sigma_mm: float, polish: bool
) -> tuple[OffsetTableReader, str | None]:
    """The table reader of the model ``doc`` in ``model_file`` (noise: the inverse map's field
    resolution; range: to the last lock; ``lever``: its calibration's factor), and the note of
    :func:`table_beside`. InputError when no press of the table is identifiable at that noise."""
    force_max_N = float(imap.force_N[-1])
    edges = table_edges_N(doc, imap, mechanics, lever)
    table, note = table_beside(model_file, doc, mechanics, lever, force_max_N, edges_N=edges)
    sigma_T = imap.field_resolution_T
    best = best_offset_sigma_mm(table, sigma_T)
    if not best <= max_sigma_mm:
        raise InputError(
            "--estimate offset",
            doc.name,
            f"this layout cannot tell where a press was: the offset's 1-sigma is at best {best:.3g} mm "
            f"at {1e6 * sigma_T:.3g} uT noise, over the --max-offset-sigma-mm bound {max_sigma_mm:g} mm",
        )
    exact = None
    if polish:
        g, m = doc.geometry(), doc.material
        members = section_members_pose(g, m, mechanics, doc.section_rung)
        exact = OffsetEstimator(g, m, mechanics, sigma_T, force_max_N, max_sigma_mm, lever, doc.whole_part, members)
    return OffsetTableReader(table, sigma_T, max_sigma_mm, exact), note


def best_offset_sigma_mm(table: InverseTable, sigma_T: float) -> float:
    """The least Cramer-Rao 1-sigma of the offset (the worse of x0 and y0) over the table's nodes,
    from the table's field differences (inf: nowhere identifiable)."""
    g, B = table.grid, 1e6 * table.B_T
    J = np.stack([np.gradient(B, g.force_N, axis=0), np.gradient(B, g.u, axis=1), np.gradient(B, g.v, axis=2)], -1)
    sig = crb_sigma(J[1:].reshape(-1, 3, 3), 1e6 * sigma_T)
    worst = np.fmax(sig[:, 1], sig[:, 2])
    return float(np.min(worst)) if len(worst) else float("inf")


def shear_table_reader(
    doc: Document, imap: InverseMap, lever: float, model_file: Path, mechanics: str, polish: bool
) -> tuple[ShearTableReader, str | None]:
    """The shear table reader of the model ``doc`` in ``model_file`` (noise: the inverse map's
    field resolution; range: to the last lock; ``lever``: its calibration's factor), and the note
    of :func:`table_beside`."""
    edges = table_edges_N(doc, imap, mechanics, lever)
    table, note = table_beside(model_file, doc, mechanics, lever, float(imap.force_N[-1]), "shear", edges)
    exact = None
    if polish:
        g, m = doc.geometry(), doc.material
        members = section_members_pose(g, m, mechanics, doc.section_rung)
        exact = ShearReader(loaded_stack(g, m, mechanics, lever, doc.whole_part, members))
    return ShearTableReader(table, imap.field_resolution_T, exact), note


def tables_for(
    model_file: Path, doc: Document, imap: InverseMap, lever: float, mechanics: str, kind: str = "offset"
) -> tuple[InverseTable, OffsetTableReader | ShearTableReader]:
    """What ``mst calibrate --offset-table`` (``--shear-table``) writes for the model in
    ``model_file``: its table of ``kind`` (the default grid, current beside it) and the reader of
    every other node of it (the C header's coarse table: with the reference part's 7 bands between
    kinks the offset's 29 x 31 x 21 nodes give 15 x 16 x 11, the shear's 29 x 21 x 21 give 15 x 11
    x 11), at the inverse map's noise (and the default bound on the offset's 1-sigma)."""
    edges = table_edges_N(doc, imap, mechanics, lever)
    table = build_beside(model_file, doc, mechanics, lever, float(imap.force_N[-1]), kind=kind, edges_N=edges)
    if kind == "shear":
        return table, ShearTableReader(table.every_other(), imap.field_resolution_T)
    return table, OffsetTableReader(table.every_other(), imap.field_resolution_T, DEFAULT_MAX_SIGMA_MM)
