"""What every verb shares: the choices and output-folder checks, loading a design.

Part of the api's one door, :mod:`mst_cli.api`."""

from __future__ import annotations

from collections.abc import Callable, Sequence
from pathlib import Path
from typing import TYPE_CHECKING

from mst_cli.errors import InputError
from mst_cli.io.files import is_machine_fault as is_machine_fault
from mst_cli.io.files import os_error_text as os_error_text
from mst_cli.io.outputs import Interrupted as Interrupted
from mst_cli.io.outputs import check_out_dir
from mst_cli.model.board_slots import slot_violations
from mst_cli.model.file_keys import SEED_RANGE as SEED_RANGE
from mst_cli.model.mechanics import rung_keep
from mst_cli.sensor import rung_store
from mst_cli.sensor.document import Document, design_geometry, load_design_document, load_document

if TYPE_CHECKING:
    pass


rung_store.install()  # the whole-part rung's solves kept in mst's cache folder, for every verb

# also here for the command line, which imports nothing else of the package: Interrupted (a
# signal ended a run), SEED_RANGE (--seed's bounds), is_machine_fault and os_error_text
FIELD_MODELS = ("auto", "dipole", "axial", "cylinder")


def _one_of(option: str, value: str | None, allowed: Sequence[str]) -> None:
    """InputError unless ``value`` is None or one of ``allowed`` (click's Choice, for scripts)."""
    if value is not None and value not in allowed:
        raise InputError(option, value, "must be one of " + ", ".join(allowed))


def _check_out(out: str | Path | None) -> None:
    """InputError when ``out`` (unless None) cannot be an output folder."""
    if out is not None:
        check_out_dir(Path(out))


def load(path: str | Path) -> Document:
    """A design or spec file (docs/file-format.md), validated field by field.

    Parameters
    ----------
    path : str or Path
        YAML file: a design (every layer's theta_deg, t_mm, h_mm) or a spec (targets).

    Returns
    -------
    Document
        ``.is_design`` / ``.is_spec`` say which; ``.geometry()`` builds a design's sensor.

    Raises
    ------
    InputError
        The file is unreadable or a field breaks its rule (named, with what is allowed).

    Examples
    --------
    >>> doc = mst.load("configs/mohammadi2021-forward.yaml")  # doctest: +SKIP
    >>> doc.is_design  # doctest: +SKIP
    True
    """
    return load_document(path)


def load_design(path: str | Path | Document) -> Document:
    """A design file whose every cell is printable and works; a Document is checked the same way.

    Parameters
    ----------
    path : str, Path or Document
        A design file, or a Document loaded earlier.

    Returns
    -------
    Document
        The design, its cells checked.

    Raises
    ------
    InputError
        Naming the first layer that breaks a rule.

    Examples
    --------
    >>> mst.load_design("configs/mohammadi2021-forward.yaml").name  # doctest: +SKIP
    """
    return _design_and_geometry(path)[0]


def _design_and_geometry(design):
    """(a valid design's Document, its sensor as drawn), the file read once. In section mode the
    model meshes the part's housing, so its boards must fit as ``mst export`` needs them to."""
    doc, geometry = (
        load_design_document(design) if isinstance(design, (str, Path)) else (design, design_geometry(design))
    )
    if doc.section_rung:
        refuse_unhoused_chips(doc)
    return doc, geometry


def tell_rung_solves(say: Callable[[str], None] | None) -> None:
    """Tell ``say`` before the whole-part rung solves what mst's cache has not kept
    (``model.load_path: section``: seconds a solve); None: tell no one."""
    rung_keep.set_listener(say)


def refuse_unhoused_chips(doc: Document) -> Document:
    """``doc``, or InputError (the chips' field) when a chip's board slot does not fit the face
    (the footprint is the spec's) or the boards cannot lie side by side in the base: ``mst design``
    and ``mst export`` refuse it before any work. The rule reads no layer, so a probe cell stands
    in for a spec's."""
    for v in slot_violations(doc.geometry([doc.family.cell(45.0, 1.0, 3.0)])):
        raise v.input_error()
    return doc
