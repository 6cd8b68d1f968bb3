"""The rule of one key of a design or spec file: what it accepts (kind, bounds or choices, null)
and the one-line InputError naming the field, the value and what is allowed when a value breaks
it. Each rule is read from a dataclass field declared with :func:`mst_cli.model.file_keys.spec`
(:meth:`Rule.of`); :mod:`mst_cli.sensor.document` builds the document from them.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import MISSING, Field, dataclass, fields
from typing import Any

from mst_cli.errors import InputError
from mst_cli.model.file_keys import spec

RULE_KEYS = ("lo", "hi", "lo_open", "hi_open", "choices", "nullable", "unit")  # spec() metadata a Rule reads
MAX_PAIRS = 4  # a "pairs" key's longest list


def default_of(f: Field) -> Any:
    """The declared default of a dataclass field (MISSING when it has none)."""
    return f.default_factory() if f.default_factory is not MISSING else f.default


def adopt(owner: type, name: str, **changes: Any) -> Any:
    """Field ``name`` of the dataclass ``owner`` exposed under the same key by a section class:
    its default and metadata as declared there, with ``changes`` on top (bounds and meaning for
    a class that declares none, such as Material; a different default)."""
    f = next(f for f in fields(owner) if f.name == name)
    meta = {**f.metadata, **changes}
    default = meta.pop("default", f.default)
    return spec(default, **meta)


@dataclass(frozen=True)
class Rule:
    """What one key accepts: a kind and optional bounds (open or closed) or choices."""

    kind: str  # "float", "int", "str", "bool", "pair", "pairs", "bounds", "weights"
    lo: float | None = None
    hi: float | None = None
    lo_open: bool = False
    hi_open: bool = False
    choices: tuple = ()
    nullable: bool = False
    unit: str = ""

    @classmethod
    def of(cls, f: Field) -> Rule:
        """The rule a :func:`spec` field declares; its kind is the annotation's unless given
        (``float | None`` is a float: whether null is allowed is ``nullable``'s to say)."""
        kind = f.metadata["kind"] or str(f.type).split(" | ")[0]
        return cls(kind, **{k: f.metadata[k] for k in RULE_KEYS})

    def describe(self) -> str:
        unit = f" {self.unit}" if self.unit else ""
        if self.kind == "weights":
            return (
                f"must be a mapping of weights >= {self.lo:g} (at least one > 0) with keys from "
                f"{', '.join(self.choices)}"
            )
        if self.kind == "bounds":
            return (
                f"must be [low, high] with {self.lo:g} <= low < high {'<' if self.hi_open else '<='} {self.hi:g}{unit}"
            )
        if self.choices:
            return "one of " + ", ".join(map(str, self.choices))
        if self.kind == "pairs":
            return f"must be a list of 1 to {MAX_PAIRS} [x, y] pairs, each number {self.lo:g} to {self.hi:g}{unit}" + (
                " (or null)" if self.nullable else ""
            )
        kind = {
            "float": "a number",
            "int": "an integer",
            "str": "a string",
            "bool": "true or false",
            "pair": "a list of two numbers",
        }[self.kind]
        parts = []
        if self.lo is not None:
            parts.append(f"{'>' if self.lo_open else '>='} {self.lo:g}")
        if self.hi is not None:
            parts.append(f"{'<' if self.hi_open else '<='} {self.hi:g}")
        null = " (or null)" if self.nullable else ""
        return f"must be {kind}{' ' + ' and '.join(parts) if parts else ''}{unit}{null}"

    def check(self, path: str, value: Any) -> Any:
        """The value as the rule reads it (float, int, str, bool, a pair, a weights dict), or an
        InputError naming ``path``, the value and what is allowed."""
        if value is None:
            if self.nullable:
                return None
            raise InputError(path, value, self.describe())
        if self.kind == "weights":
            return self._weights(path, value)
        if self.kind == "pairs":
            if not isinstance(value, (list, tuple)) or not 1 <= len(value) <= MAX_PAIRS:
                raise InputError(path, value, self.describe())
            return tuple(Rule("pair", self.lo, self.hi).check(f"{path}[{i}]", v) for i, v in enumerate(value))
        if self.kind in ("pair", "bounds"):
            if not isinstance(value, (list, tuple)) or len(value) != 2:
                raise InputError(path, value, self.describe())
            # a [low, high] pair's bounds are checked by ordered() once its section is read
            return tuple(self._number(f"{path}[{i}]", v, bounded=self.kind == "pair") for i, v in enumerate(value))
        if self.kind == "str":
            if not isinstance(value, str) or (self.choices and value not in self.choices):
                raise InputError(path, value, self.describe())
            return value
        if self.kind == "bool":
            if not isinstance(value, bool):
                raise InputError(path, value, self.describe())
            return value
        if self.kind == "int":
            if isinstance(value, bool) or not isinstance(value, int):
                raise InputError(path, value, self.describe())
            return int(self._bounded(path, value))
        return self._number(path, value)

    def _weights(self, path: str, value: Any) -> dict:
        """A non-empty {term: weight} of known terms, not all zero."""
        if not isinstance(value, dict) or not value:
            raise InputError(path, value, self.describe())
        out = {}
        weight = Rule("float", lo=self.lo, hi=self.hi)
        for key, w in value.items():
            if key not in self.choices:
                raise InputError(f"{path}.{key}", w, "unknown term; allowed: " + ", ".join(self.choices))
            out[key] = weight.check(f"{path}.{key}", w)
        if not any(out.values()):
            raise InputError(path, value, self.describe())
        return out

    def ordered(self, path: str, pair: Sequence[float]) -> tuple[float, float]:
        """A "bounds" pair: low < high, both inside the rule's bounds."""
        a, b = pair
        lo, hi = self.lo, self.hi
        assert lo is not None and hi is not None  # a "bounds" rule declares both
        if not (lo <= a < b and (b < hi if self.hi_open else b <= hi)):
            raise InputError(path, list(pair), self.describe())
        return (a, b)

    def _number(self, path, value, bounded=True):
        if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
            raise InputError(path, value, self.describe())
        return float(self._bounded(path, value) if bounded else value)

    def _bounded(self, path, value):
        if self.lo is not None and (value <= self.lo if self.lo_open else value < self.lo):
            raise InputError(path, value, self.describe())
        if self.hi is not None and (value >= self.hi if self.hi_open else value > self.hi):
            raise InputError(path, value, self.describe())
        return value

    def allowed_markdown(self) -> str:
        """What the key accepts, as the tables of docs/file-format.md write it."""
        choices = ", ".join(f"`{c}`" for c in self.choices)
        if self.kind in ("str", "bool"):
            if self.choices:
                return ("one of " if len(self.choices) > 1 else "") + choices
            return {"str": "any text", "bool": "true or false"}[self.kind]
        lo, hi = number_text(self.lo), number_text(self.hi)  # every number is bounded both ways
        below, above = ("<" if self.lo_open else "≤"), ("<" if self.hi_open else "≤")
        if self.kind == "weights":
            return f"weights {lo} {below} w {above} {hi} (at least one > 0) for any of {choices}"
        if self.kind == "bounds":
            return f"[low, high], {lo} {below} low < high {above} {hi}"
        span = f"{lo} {below} {'value' if self.kind in ('float', 'int') else 'each'} {above} {hi}"
        return (
            {"pair": "two numbers, ", "int": "integer, ", "pairs": f"1 to {MAX_PAIRS} [x, y] pairs, "}.get(
                self.kind, ""
            )
            + span
            + (", or null" if self.nullable else "")
        )


def number_text(value: float | None) -> str:
    """A bound or default as the docs write it: an int as it is, a float in ``g`` format."""
    return str(value) if isinstance(value, int) else f"{value:g}"
