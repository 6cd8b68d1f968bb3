"""The shape of the package, read from its source (issues 23, 37): short functions and modules, a thin command
line, imports at module top unless deferred on purpose (and saying why), and a type checker
that passes. Complexity (ruff's C901, at 15) is part of the lint configuration test_style runs."""

from __future__ import annotations

import ast
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
PACKAGE = ROOT / "mst_cli"
MODULES = sorted(PACKAGE.rglob("*.py"))
MAX_FUNCTION_LINES = 60
MAX_MODULE_LINES = 600
MAX_CLI_MODULE_LINES = 150
DEFERRED = "# deferred:"


def _functions(tree: ast.AST) -> list[ast.FunctionDef | ast.AsyncFunctionDef]:
    return [n for n in ast.walk(tree) if isinstance(n, (ast.FunctionDef, ast.AsyncFunctionDef))]


def _name(path: Path) -> str:
    return str(path.relative_to(ROOT))


def test_the_package_is_read_whole():
    # a guard for the checks below: they walk every module of the package, not an empty list
    assert len(MODULES) > 60 and PACKAGE / "cli" / "app.py" in MODULES


def test_no_function_is_longer_than_60_lines():
    long = [
        f"{_name(path)}:{fn.lineno} {fn.name} ({fn.end_lineno - fn.lineno + 1} lines)"
        for path in MODULES
        for fn in _functions(ast.parse(path.read_text(), str(path)))
        if fn.end_lineno - fn.lineno + 1 > MAX_FUNCTION_LINES
    ]
    assert long == []


def test_no_module_is_longer_than_600_lines():
    # a module this long holds more than one concept: split it by concept, not by line count
    lines = {_name(p): len(p.read_text().splitlines()) for p in MODULES}
    assert {name: n for name, n in lines.items() if n > MAX_MODULE_LINES} == {}


def test_every_cli_module_is_short():
    lines = {_name(p): len(p.read_text().splitlines()) for p in (PACKAGE / "cli").glob("*.py")}
    assert {name: n for name, n in lines.items() if n > MAX_CLI_MODULE_LINES} == {}


def _says_why(lines: list[str], lineno: int) -> bool:
    """The import on ``lineno`` (from 1), or the run of imports and comments right above it,
    carries a '# deferred:' reason."""
    if DEFERRED in lines[lineno - 1]:
        return True
    i = lineno - 2
    while i >= 0 and lines[i].strip().startswith(("import ", "from ", "#")):
        if DEFERRED in lines[i]:
            return True
        i -= 1
    return False


def test_an_import_inside_a_function_says_why_it_is_deferred():
    unexplained = []
    for path in MODULES:
        lines = path.read_text().splitlines()
        for fn in _functions(ast.parse("\n".join(lines))):
            for node in ast.walk(fn):
                if isinstance(node, (ast.Import, ast.ImportFrom)) and not _says_why(lines, node.lineno):
                    unexplained.append(f"{_name(path)}:{node.lineno} {lines[node.lineno - 1].strip()}")
    assert unexplained == []


def test_the_import_check_catches_a_bare_deferred_import():
    # the rule above, on a made-up module: a reason covers its own block of imports, not an
    # import after other code
    src = "def f():\n    # deferred: why\n    import json\n    import re\n    x = 1\n    import csv\n"
    lines = src.splitlines()
    found = [n.lineno for fn in _functions(ast.parse(src)) for n in ast.walk(fn) if isinstance(n, ast.Import)]
    assert [_says_why(lines, k) for k in found] == [True, True, False]


@pytest.mark.slow
def test_mypy_finds_no_error():
    # [tool.mypy] in pyproject.toml sets the level; mypy is part of the test extra
    done = subprocess.run([sys.executable, "-m", "mypy"], capture_output=True, text=True, cwd=ROOT)
    assert done.returncode == 0, done.stdout[-3000:] + done.stderr[-1000:]
    assert "Success: no issues found" in done.stdout
