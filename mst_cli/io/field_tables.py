"""The key tables of docs/file-format.md, generated from the declarations of the keys (each a
dataclass field made with :func:`mst_cli.model.file_keys.spec`), so the docs cannot drift from the
code. :mod:`mst_cli.sensor.document` binds them to its sections: ``python -m mst_cli.sensor.document
docs/file-format.md`` rewrites the tables in place.
"""

from __future__ import annotations

import re
from collections.abc import Callable, Iterable
from dataclasses import Field, fields
from pathlib import Path

from mst_cli.io.rules import Rule, default_of, number_text

FIELD_TABLE = re.compile(r"(<!-- fields:(\w+) -->\n).*?(<!-- /fields -->)", re.S)


def _default_markdown(f: Field, rule: Rule) -> str:
    value = default_of(f)
    if value is None:
        return "null" if rule.nullable else "—"  # — : no default (a layer gives a group or none)
    if isinstance(value, str):
        return f"`{value}`"
    if isinstance(value, dict):
        return "`{" + ", ".join(f"{k}: {number_text(v)}" for k, v in value.items()) + "}`"
    if isinstance(value, tuple):
        return "[" + ", ".join(map(number_text, value)) + "]"
    return number_text(value)


def table_markdown(declared: type, prefix: str) -> str:
    """The Markdown table of the keys ``declared`` (a section or layer dataclass) declares, each
    named ``prefix.key``: what it allows, its unit, default and meaning."""
    rows = ["| key | allowed | unit | default | meaning |", "|---|---|---|---|---|"]
    for f in fields(declared):
        rule = Rule.of(f)
        cells = (
            f"`{prefix}.{f.name}`",
            rule.allowed_markdown(),
            rule.unit or "–",
            _default_markdown(f, rule),
            f.metadata["meaning"],
        )
        rows.append("| " + " | ".join(c.replace("|", "\\|") for c in cells) + " |")
    return "\n".join(rows)


def with_tables(text: str, table: Callable[[str], str]) -> str:
    """``text`` with every table between ``<!-- fields:SECTION -->`` and ``<!-- /fields -->``
    replaced by ``table(SECTION)``."""
    return FIELD_TABLE.sub(lambda m: m.group(1) + table(m.group(2)) + "\n" + m.group(3), text)


def rewrite(paths: Iterable[str | Path], table: Callable[[str], str]) -> None:
    """Regenerate the tables of the Markdown files ``paths`` in place."""
    for doc_path in map(Path, paths):
        doc_path.write_text(with_tables(doc_path.read_text(), table))
