"""The package's layering, read from the source: imports only go down, and nothing cycles.

Every ``import`` and ``from ... import`` of the package is counted, the ones inside functions
(lazy imports) included, so a cycle hidden behind a late import fails here too. Importing
``a.b.c`` also runs ``a`` and ``a.b``; those package edges count, except a module's own
ancestors (Python loads them first whatever the module does).
"""

from __future__ import annotations

import ast
import fnmatch
import re
import tomllib
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
PACKAGE = ROOT / "mst_cli"

# lowest first; a module may import from its own layer or any layer listed before it
LAYERS = (
    ("mst_cli.errors", "mst_cli.parallel", "mst_cli.version"),
    ("mst_cli.model",),  # physics kernels: no files, no command line
    ("mst_cli.io",),  # file plumbing: YAML, atomic outputs, serial lines, input rules
    ("mst_cli.sensor",),  # the domain: the sensor description, the part as printed
    ("mst_cli.estimation",),  # a reading to the load: the inverse map, the solves, the tables
    ("mst_cli.firmware",),  # the C headers of the estimation's maps and tables
    ("mst_cli.design", "mst_cli.calibration", "mst_cli.bench", "mst_cli.cad", "mst_cli.simulation"),
    ("mst_cli.readout",),  # mst read: files and streams to forces.csv, the one reading pipeline
    ("mst_cli", "mst_cli.api"),  # the one door; the package re-exports its verbs
    ("mst_cli.cli",),
)


def _modules() -> dict[str, tuple[Path, bool]]:
    out = {}
    for path in PACKAGE.rglob("*.py"):
        parts = list(path.relative_to(ROOT).with_suffix("").parts)
        is_package = parts[-1] == "__init__"
        if is_package:
            parts = parts[:-1]
        out[".".join(parts)] = (path, is_package)
    return out


MODULES = _modules()


def _absolute(name: str, module: str, is_package: bool, level: int) -> str:
    if not level:
        return name
    base = module.split(".") if is_package else module.split(".")[:-1]
    base = base[: len(base) - (level - 1)]
    return ".".join(base + ([name] if name else []))


def _nearest_module(dotted: str) -> str | None:
    while dotted and dotted not in MODULES:
        dotted = dotted.rpartition(".")[0]
    return dotted or None


def import_graph() -> dict[str, set[str]]:
    """module -> the package modules that importing it runs (lazy imports included)."""
    graph = {}
    for module, (path, is_package) in MODULES.items():
        targets = set()
        for node in ast.walk(ast.parse(path.read_text(), str(path))):
            if isinstance(node, ast.Import):
                names = [a.name for a in node.names]
            elif isinstance(node, ast.ImportFrom):
                base = _absolute(node.module or "", module, is_package, node.level)
                names = [base] + [f"{base}.{a.name}" for a in node.names]
            else:
                continue
            for name in names:
                found = _nearest_module(name) if name.startswith("mst_cli") else None
                if found is None:
                    continue
                parts = found.split(".")
                for i in range(1, len(parts) + 1):  # a.b.c runs a, a.b, a.b.c
                    target = ".".join(parts[:i])
                    if target != module and not module.startswith(target + "."):
                        targets.add(target)
        graph[module] = targets
    return graph


def _layer_of(module: str) -> int:
    best, best_len = None, -1
    for i, prefixes in enumerate(LAYERS):
        for prefix in prefixes:
            if (module == prefix or module.startswith(prefix + ".")) and len(prefix) > best_len:
                best, best_len = i, len(prefix)
    assert best is not None, f"{module} belongs to no layer: add it to LAYERS"
    return best


def _cycles(graph: dict[str, set[str]]) -> list[list[str]]:
    """Strongly connected components with more than one module (Tarjan)."""
    index, low, on_stack, stack, found = {}, {}, set(), [], []

    def visit(v):
        index[v] = low[v] = len(index)
        stack.append(v)
        on_stack.add(v)
        for w in graph[v]:
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on_stack:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            component = []
            while True:
                w = stack.pop()
                on_stack.discard(w)
                component.append(w)
                if w == v:
                    break
            if len(component) > 1:
                found.append(sorted(component))

    for v in sorted(graph):
        if v not in index:
            visit(v)
    return found


def test_the_graph_sees_lazy_imports():
    # the mechanics package picks a rung by importing the rung's module inside a function
    graph = import_graph()
    assert "mst_cli.model.mechanics.continuum" in graph["mst_cli.model.mechanics"]
    assert "mst_cli.cli.common" in graph["mst_cli.cli.design"]


def test_no_import_cycle_lazy_imports_included():
    assert _cycles(import_graph()) == []


def test_a_cycle_would_be_found():
    assert _cycles({"a": {"b"}, "b": {"c"}, "c": {"a"}, "d": {"a"}}) == [["a", "b", "c"]]


@pytest.mark.parametrize("module", sorted(MODULES))
def test_imports_only_go_down(module):
    own = _layer_of(module)
    upward = sorted(t for t in import_graph()[module] if _layer_of(t) > own)
    assert upward == [], f"{module} (layer {own}) imports from a higher layer: {upward}"


def test_no_top_level_module_but_the_errors_the_workers_the_version_and_the_api():
    # parallel.py (forked workers) sits at the bottom with the errors: the L2 laws (model/) and
    # the Pareto front (design/) both fork, and neither layer may import the other's
    top = sorted(p.name for p in PACKAGE.glob("*.py"))
    assert top == ["__init__.py", "errors.py", "parallel.py", "version.py"]
    assert (PACKAGE / "api" / "__init__.py").is_file()  # the one door, one module per verb family


def test_documentation_lives_in_the_repository():
    # no file points to a design document or reference data outside the clone
    outside = re.compile(r"\bDESIGN\.md|shared/reference|\.\./shared")
    hits = []
    for path in [
        *PACKAGE.rglob("*.py"),
        *(ROOT / "docs").rglob("*.md"),
        *(ROOT / "benchmarks").rglob("*.py"),
        *(ROOT / "studies").rglob("*.py"),
        *(ROOT / "tools").rglob("*.py"),
        *(ROOT / "configs").rglob("*.yaml"),
        ROOT / "README.md",
    ]:
        for n, line in enumerate(path.read_text().splitlines(), 1):
            if outside.search(line):
                hits.append(f"{path.relative_to(ROOT)}:{n}")
    assert hits == []
    assert (ROOT / "docs" / "design.md").is_file()


def test_every_data_file_ships_with_the_package():
    # a regular 'pip install .' copies only modules and the package-data globs: a data file the
    # globs miss is found in the source tree and nowhere else (.ci/run runs such an install)
    globs = tomllib.loads((ROOT / "pyproject.toml").read_text())["tool"]["setuptools"]["package-data"]["mst_cli"]
    data = [p.relative_to(PACKAGE).as_posix() for p in PACKAGE.rglob("data/*") if p.is_file()]
    assert data and [d for d in data if not any(fnmatch.fnmatch(d, g) for g in globs)] == []


def test_the_command_line_goes_through_the_api_only():
    # issue 37: the CLI imports mst_cli.api, mst_cli.errors and its own modules, nothing else of
    # the package (lazy and type-only imports included); the package root is how 'from mst_cli
    # import api' reads
    allowed = ("mst_cli", "mst_cli.api", "mst_cli.errors")
    graph = import_graph()
    cli = [m for m in graph if m == "mst_cli.cli" or m.startswith("mst_cli.cli.")]
    assert len(cli) > 5
    bad = {m: sorted(t for t in graph[m] if t not in allowed and not t.startswith("mst_cli.cli")) for m in cli}
    assert {m: t for m, t in bad.items() if t} == {}


# Libraries worth deferring, and why: each costs start-up time that most commands never need.
HEAVY_LIBRARIES = {
    "build123d": "the CAD kernel (OCP): seconds, --step only",
    "OCP": "the CAD kernel itself",
    "skfem": "scikit-fem, 0.2 s: the continuum rung and its checks",
    "matplotlib": "0.45 s: pictures only",
    "mpl_toolkits": "matplotlib's 3D axes",
    "PIL": "Pillow (via matplotlib): rasterising a sliced layer",
    "scipy": "scipy.optimize / sparse / spatial: fits, dear rungs, meshes",
    "nlopt": "the optimiser: a design search only",
    "magpylib": "the exact cylinder field: off the axis only",
    "trimesh": "mesh file formats other than binary STL",
    "manifold3d": "the mesh kernel's native library: meshing and measuring a body",
    "greenlet": "the batched polish of many weightings",
    "multiprocessing": "20 ms of process machinery: only where workers are forked",
    "concurrent": "as multiprocessing",
    "threadpoolctl": "BLAS introspection: only where a dear rung solves",
    "hashlib": "3 ms (OpenSSL): only the whole-part rung's kept solves and the tables' file hashes",
    "importlib.metadata": "10 ms (the email package): only a file that names the version",
    "numba": "0.15 s, and its kernels' compiled code: the two-chip reader only",
    "serial": "pyserial, optional: mst read --serial",
    "fcntl": "POSIX only",
    "termios": "POSIX only",
}
# a quick design loads the off-centre and general-load models (their tilt laws and poses, 5 ms)
# only when its spec asks for the off-centre figure or places two chips
OFF_CENTRE = ("mst_cli.model.offcentre", "mst_cli.simulation.run", "mst_cli.model.load_bound")
# The door loads only the layer of the verb that runs (mst simulate does not pay for the design
# search, the CAD layer or the calibration); the command group loads only the command run.
LAYER_DEFERRALS = {
    "mst_cli.api": (
        # the door's own verb families: a command loads its own (mst design not the calibration's)
        "mst_cli.api._calibrating",
        "mst_cli.api._designing",
        "mst_cli.api._making",
        "mst_cli.api._measuring",
        "mst_cli.api._simulating",
        "mst_cli.design",
        "mst_cli.cad",
        "mst_cli.calibration",
        "mst_cli.estimation",
        "mst_cli.firmware",
        "mst_cli.readout",
        "mst_cli.bench",
    ),
    "mst_cli.cli.app": ("mst_cli.cli",),
    # a design run loads the front's and the dearer rungs' search only when asked for (--pareto,
    # --refine): 8 ms of every quick design's start (benchmarks/bench_simulate.py)
    "mst_cli.design.run": ("mst_cli.design.pareto", "mst_cli.design.refine", *OFF_CENTRE),
    "mst_cli.design.files": ("mst_cli.design.pareto",),
    "mst_cli.design.result": OFF_CENTRE,
    # the rung a law is asked of: L1 (the frame and its path follower, 6 ms) only when asked for,
    # as L2 (scikit-fem) is; the quick commands use L0 alone
    "mst_cli.model.mechanics": ("mst_cli.model.mechanics.frame",),
}


def _heavy(name: str) -> bool:
    return any(name == lib or name.startswith(lib + ".") for lib in HEAVY_LIBRARIES)


def _eager_imports(module: str) -> set[str]:
    """What importing ``module`` runs at its top (TYPE_CHECKING blocks aside): dotted names."""
    path, is_package = MODULES[module]
    found: set[str] = set()

    def visit(body):
        for node in body:
            if isinstance(node, ast.Import):
                found.update(a.name for a in node.names)
            elif isinstance(node, ast.ImportFrom):
                found.add(_absolute(node.module or "", module, is_package, node.level))
            elif isinstance(node, ast.If) and not (isinstance(node.test, ast.Name) and node.test.id == "TYPE_CHECKING"):
                visit(node.body)
                visit(node.orelse)
            elif isinstance(node, ast.Try):
                visit(node.body)

    visit(ast.parse(path.read_text()).body)
    return found


def _loads_heavy_library(module: str, seen: set[str] | None = None) -> bool:
    """Whether importing ``module`` loads a heavy library at some module's top."""
    seen = set() if seen is None else seen
    seen.add(module)
    for name in _eager_imports(module):
        if _heavy(name):
            return True
        target = _nearest_module(name) if name.startswith("mst_cli") else None
        if target and target not in seen and _loads_heavy_library(target, seen):
            return True
    return False


def _deferred_imports():
    """(module, line, imported name) of every import inside a function of the package."""
    for module, (path, is_package) in sorted(MODULES.items()):
        tree = ast.parse(path.read_text())
        for fn in (n for n in ast.walk(tree) if isinstance(n, (ast.FunctionDef, ast.AsyncFunctionDef))):
            for node in ast.walk(fn):
                if isinstance(node, ast.Import):
                    yield from ((module, node.lineno, a.name) for a in node.names)
                elif isinstance(node, ast.ImportFrom):
                    base = _absolute(node.module or "", module, is_package, node.level)
                    # 'from package import submodule' imports the submodule
                    for a in node.names:
                        yield module, node.lineno, f"{base}.{a.name}" if f"{base}.{a.name}" in MODULES else base


def _deferral_allowed(module: str, name: str) -> bool:
    if _heavy(name):
        return True
    if not name.startswith("mst_cli"):
        return False
    door = next((d for d in LAYER_DEFERRALS if module == d or module.startswith(d + ".")), None)
    if door and any(name == layer or name.startswith(layer + ".") for layer in LAYER_DEFERRALS[door]):
        return True
    target = _nearest_module(name)
    return target is not None and _loads_heavy_library(target)


def test_deferred_imports_are_only_for_heavy_libraries():
    # an import inside a function is for a heavy library (HEAVY_LIBRARIES), for a module of the
    # package that loads one at its top, or the door's choice of the one layer a verb needs
    wrong = [f"{m}:{line} {name}" for m, line, name in _deferred_imports() if not _deferral_allowed(m, name)]
    assert wrong == []


def test_the_deferral_rule_refuses_a_light_module():
    assert _deferral_allowed("mst_cli.model.response", "scipy.optimize")
    assert _deferral_allowed("mst_cli.api._designing", "mst_cli.design.run")
    assert not _deferral_allowed("mst_cli.model.response", "json")
    assert not _deferral_allowed("mst_cli.model.mechanics.tilt", "mst_cli.model.cell")
    assert not _deferral_allowed("mst_cli.calibration.fit", "mst_cli.design.run")
