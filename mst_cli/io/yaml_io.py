"""Reading design and spec files with bounded work (issue 13).

A design file is a few kilobytes of plain mappings, lists and numbers. :func:`read_yaml_file`
refuses anything else before it costs time or memory:

* files larger than :data:`MAX_INPUT_BYTES` (read at most that many bytes plus one);
* more than :data:`MAX_NODES` nodes, counted while composing *with every alias expanded*, so
  an alias bomb (a few KB of ``&a`` / ``*a`` that expand into billions of nodes) stops at the
  first alias past the cap, and so does a long list; recursive aliases; merge keys (``<<``);
  nesting deeper than :data:`MAX_DEPTH`. (Plain anchors and aliases within the cap load as
  before: ``yaml.safe_dump`` writes them for repeated Python objects.)
* duplicate keys in any mapping (YAML would silently keep the last one);
* integers longer than :data:`MAX_INT_CHARS` characters (Python refuses to convert integers
  of more than 4300 digits; anything this long is no physical quantity): they load as a
  :class:`HugeNumber`, which every schema rule refuses as "not a number" naming the field.

Every refusal raises :class:`YAMLRefused` (a ``yaml.YAMLError``) with the key path and the line.
Only the safe constructors of ``yaml.SafeLoader`` are used.
"""

from __future__ import annotations

from typing import Any

import yaml

MAX_INPUT_BYTES = 1_000_000
MAX_NODES = 5_000
MAX_DEPTH = 32
MAX_INT_CHARS = 40


class YAMLRefused(yaml.YAMLError):
    """A structure the file format does not allow: ``path`` (dotted key path), ``line`` (from 1),
    ``value`` (short text) and ``reason``."""

    def __init__(self, path: str, line: int | None, value: object, reason: str):
        self.path, self.line, self.value, self.reason = path, line, value, reason
        where = f"line {line}: " if line is not None else ""
        super().__init__(f"{path} = {value!r}: {where}{reason}")


class HugeNumber(str):
    """An integer literal too long to be a physical quantity; never an ``int``, so every numeric
    rule refuses it. Its repr is short: the number of digits, not the digits."""

    def __repr__(self) -> str:
        return f"<integer of {len(self)} characters>"


def _line(node_or_event) -> int | None:
    mark = getattr(node_or_event, "start_mark", None)
    return mark.line + 1 if mark is not None else None


class StrictLoader(yaml.SafeLoader):
    """``yaml.SafeLoader`` without merge keys, duplicate keys or recursive aliases, and with caps
    on the number of nodes (aliases expanded) and on the nesting depth."""

    def __init__(self, stream: str | bytes) -> None:
        super().__init__(stream)
        self._expanded = 0  # nodes so far, every alias counted as its whole value
        self._depth = 0
        self._anchor_sizes: dict[str, int] = {}
        self._open_anchors: set[str] = set()

    def _count(self, n: int, event) -> None:
        self._expanded += n
        if self._expanded > MAX_NODES:
            what = f"*{event.anchor}" if isinstance(event, yaml.AliasEvent) else f"{MAX_NODES}+ values"
            raise YAMLRefused(
                "(file)",
                _line(event),
                what,
                f"more than {MAX_NODES} values (aliases expanded): a design file holds a few dozen",
            )

    # index: PyYAML passes a sequence position or a mapping's key node (its stubs say int only)
    def compose_node(self, parent: yaml.Node | None, index: Any) -> yaml.Node | None:
        event = self.peek_event()
        if isinstance(event, yaml.AliasEvent):
            if event.anchor in self._open_anchors:
                raise YAMLRefused(
                    "(file)",
                    _line(event),
                    f"*{event.anchor}",
                    "an alias inside the value it names (recursive): write the value out",
                )
            self._count(self._anchor_sizes.get(event.anchor or "", 1), event)  # an alias always names one
            return super().compose_node(parent, index)
        self._count(1, event)
        anchor = getattr(event, "anchor", None)
        before = self._expanded - 1
        if anchor is not None:
            self._open_anchors.add(anchor)
        self._depth += 1
        if self._depth > MAX_DEPTH:
            raise YAMLRefused(
                "(file)", _line(event), f"{MAX_DEPTH}+ levels", f"nested too deeply: at most {MAX_DEPTH} levels"
            )
        try:
            node = super().compose_node(parent, index)
        finally:
            self._depth -= 1
        if anchor is not None:
            self._open_anchors.discard(anchor)
            self._anchor_sizes[anchor] = self._expanded - before
        return node

    # a deliberate widening: an over-long integer becomes the HugeNumber every rule refuses
    def construct_yaml_int(self, node: yaml.ScalarNode) -> int | HugeNumber:  # type: ignore[override]
        text = self.construct_scalar(node)
        if len(text) > MAX_INT_CHARS:
            return HugeNumber(text)
        return super().construct_yaml_int(node)


StrictLoader.add_constructor("tag:yaml.org,2002:int", StrictLoader.construct_yaml_int)


def _key_text(node) -> str:
    return node.value if isinstance(node.value, str) else str(node.value)


def check_keys(node: yaml.Node, path: str = "") -> None:
    """Refuse duplicate, merge and non-scalar keys anywhere below ``node`` (a composed node)."""
    stack = [(node, path)]
    while stack:
        node, path = stack.pop()
        if isinstance(node, yaml.MappingNode):
            seen: dict[tuple, int | None] = {}
            for key, value in node.value:
                if not isinstance(key, yaml.ScalarNode):
                    raise YAMLRefused(
                        path or "(file)", _line(key), "a list or mapping as key", "keys must be plain names"
                    )
                name = _key_text(key)
                sub = f"{path}.{name}" if path else name
                if key.tag == "tag:yaml.org,2002:merge":
                    raise YAMLRefused(sub, _line(key), "<<", "merge keys are not accepted: write the keys out")
                ident = (key.tag, key.value)
                if ident in seen:
                    shown = value.value if isinstance(value, yaml.ScalarNode) else "..."
                    raise YAMLRefused(
                        sub, _line(key), shown, f"duplicate key, first given at line {seen[ident]}: give each key once"
                    )
                seen[ident] = _line(key)
                stack.append((value, sub))
        elif isinstance(node, yaml.SequenceNode):
            for i, item in enumerate(node.value):
                stack.append((item, f"{path}[{i}]" if path else f"[{i}]"))


def load_text(text: str) -> Any:
    """Parse one YAML document with :class:`StrictLoader`; YAMLRefused / yaml.YAMLError on bad
    input (``None`` for an empty document)."""
    loader = StrictLoader(text)
    try:
        node = loader.get_single_node()
        if node is None:
            return None
        check_keys(node)
        return loader.construct_document(node)
    finally:
        loader.dispose()
