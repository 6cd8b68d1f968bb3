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
