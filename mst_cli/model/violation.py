"""One broken rule, in one shape, whoever judges it.

A cell rule (:meth:`HexCell.violations <mst_cli.model.cell.HexCell.violations>`) has a name and
a signed margin in mm; the assembly's rules (:meth:`SensorGeometry.housing_violations
<mst_cli.model.assembly.SensorGeometry.housing_violations>`, :func:`printer_violations
<mst_cli.model.assembly.printer_violations>`) concern a file field, its value and what is
allowed. A :class:`Violation` carries all of it: ``layer`` says which layer a cell rule broke
in a sensor, ``field`` and ``value`` what the user would change, and :meth:`input_error` is the
:class:`~mst_cli.errors.InputError` that names them.
"""

from __future__ import annotations

from dataclasses import dataclass
from dataclasses import field as dataclass_field
from typing import Any

from mst_cli.errors import InputError


@dataclass(frozen=True)
class Violation:
    """One broken rule.

    Attributes
    ----------
    rule : str
        The rule: a cell rule's name (:data:`~mst_cli.model.cell.CELL_RULES`) or the dotted
        field an assembly rule concerns (``family.depth_mm``).
    margin_mm : float or None
        Signed margin, mm (< 0 broken; :meth:`HexCell.margins` also lists kept rules, >= 0);
        None for a rule without a margin in mm.
    message : str
        What is allowed, as a sentence.
    layer : int, optional
        Index from 0 of the layer whose cell breaks the rule (set by
        :meth:`SensorGeometry.violations`).
    field : str, optional
        The field to change: ``layers[i]`` for a cell in a sensor, the dotted key otherwise.
    value : any
        Its value (a cell's ``{"theta_deg", "t_mm", "h_mm"}``).
    """

    rule: str
    margin_mm: float | None
    message: str
    layer: int | None = None
    field: str | None = None
    value: Any = dataclass_field(default=None, hash=False)

    @classmethod
    def of_field(cls, name: str, value: Any, allowed: str) -> Violation:
        """An assembly rule: the dotted field ``name`` has ``value``; ``allowed`` says what may be."""
        return cls(rule=name, margin_mm=None, message=allowed, field=name, value=value)

    @property
    def allowed(self) -> str:
        """What is allowed (the message), as :class:`~mst_cli.errors.InputError` names it."""
        return self.message

    def input_error(self, context: str | None = None) -> InputError:
        """The InputError naming the field, the value and what is allowed; ``context`` (``"invalid
        cell"``) prefixes a cell rule's message as ``context (rule): message``."""
        allowed = self.message if context is None else f"{context} ({self.rule}): {self.message}"
        return InputError(self.field if self.field is not None else self.rule, self.value, allowed)
