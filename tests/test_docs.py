"""The README's quick start stays true: CI runs exactly its test command, the example exists."""

import re
import shlex
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def quick_start_commands():
    text = (ROOT / "README.md").read_text()
    section = text.split("## Quick start", 1)[1].split("\n## ", 1)[0]
    return re.findall(r"```bash\n(.+?)\n```", section)


def test_quick_start_is_exactly_two_commands():
    assert len(quick_start_commands()) == 2


def test_ci_runs_the_readme_test_command():
    test_cmd = quick_start_commands()[1]
    assert "pytest" in test_cmd
    ci_lines = [l.strip() for l in (ROOT / ".ci" / "run").read_text().splitlines()]
    assert test_cmd in ci_lines


def test_first_command_runs_a_bundled_example():
    words = shlex.split(quick_start_commands()[0].split("&&")[-1])
    assert words[0].endswith("mst") and (ROOT / words[-1]).is_file()


def test_file_format_tables_are_generated_from_the_declarations():
    """docs/file-format.md's field tables are what mst_cli.sensor.document generates from the one
    declaration of each key: they cannot drift (python -m mst_cli.sensor.document docs/file-format.md
    rewrites them after a change)."""
    from mst_cli.sensor.document import FIELD_TABLE, field_table_markdown, with_field_tables
    from mst_cli.sensor.sections import SECTION_TYPES

    text = (ROOT / "docs" / "file-format.md").read_text()
    blocks = {m.group(2): m.group(0) for m in FIELD_TABLE.finditer(text)}
    assert sorted(blocks) == sorted(["layers", *SECTION_TYPES]), "one marked table per section"
    assert len(FIELD_TABLE.findall(text)) == len(blocks), "a section's table is marked twice"
    for section, block in blocks.items():
        assert field_table_markdown(section) in block, f"docs/file-format.md: the {section} table is stale"
    assert with_field_tables(text) == text


def test_the_layer_count_in_the_docs_is_the_schema_cap():
    from mst_cli.sensor.sections import MAX_LAYERS

    text = (ROOT / "docs" / "file-format.md").read_text()
    assert f"## `layers` (required, 1 to {MAX_LAYERS} entries," in text


def test_mst_help_lists_every_command():
    # the summary block of `mst --help` (cli/app.py's docstring) names every registered command
    from click.testing import CliRunner

    from mst_cli.cli.app import COMMANDS, load_command, main

    text = CliRunner().invoke(main, ["--help"]).output
    summary = text.split("Exit codes")[0]
    assert all(load_command(name) is not None for name in COMMANDS)
    assert [name for name in COMMANDS if f"mst {name} " not in summary] == []
