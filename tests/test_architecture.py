"""The package's structure (docs/architecture.md, Layers): an import graph of ``gearopt`` and
the built-in plugins (``gearopt_plugins``) built from the source (AST, imports inside functions
included, imports under ``if TYPE_CHECKING:`` left out), and the rules it must keep:

- no import cycle between modules;
- no private name (a leading underscore) imported from another module, no private attribute of
  another module's object read;
- no module of ``gearopt`` imports the package root;
- imports inside functions only to load an optional dependency lazily, or the Optuna study layer
  (:data:`LAZY`);
- the textbook TCA (:mod:`gearopt.newton_tca`, the engine's reference) imported by no production
  module but the benchmarks;
- no module over 800 lines; no source, test or document citing a file outside the repository;
- the built-in plugins (docs/architecture.md, Layers of the built-in plugins): one subpackage per
  machine model plus the evaluators and the objectives, no flat module beside ``__init__.py``;
  a package imports another only from a lower layer (the helpers several models share), never
  a package ``__init__`` above it (the plugin); ``gearopt`` imports no built-in plugin; every
  entry point names a module of a plugin package.
"""

from __future__ import annotations

import ast
import re
import tomllib
from collections import defaultdict
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
PACKAGES = {"gearopt": ROOT / "gearopt", "gearopt_plugins": ROOT / "plugins"}

#: optional dependencies, loaded where they are used
OPTIONAL = {"matplotlib", "contourpy", "pyarrow", "dask", "psycopg"}
#: the study layer imports Optuna and SQLAlchemy (about 2 s of start-up): the package root and
#: the study commands load it when asked, so that the CLI and the worker processes start
#: without it
LAZY = {
    ("gearopt", "gearopt.study"),
    ("gearopt.study_cli", "gearopt.study"),
    ("gearopt.study_cli", "gearopt.export"),
    ("gearopt.cli", "gearopt.dashboard"),
    # the loaded contact (SciPy's linear algebra and spatial parts, about 0.4 s) where asked
    ("gearopt.analysis", "gearopt.loaded.pair"),
}
#: the reference TCA's importers outside the tests
REFERENCE = "gearopt.newton_tca"
REFERENCE_USERS = {"gearopt.bench"}
MAX_LINES = 800
#: the layers of ``gearopt`` (docs/architecture.md, Layers), lowest first: a module imports
#: from its own layer or the ones below (a prefix names a package and its modules)
LAYERS = (
    (
        "numerics",
        (
            "gearopt.errors",
            "gearopt.validate",
            "gearopt.kinematics",
            "gearopt.solve",
            "gearopt.jit",
            "gearopt.determinants",
            "gearopt.units",
        ),
    ),
    (
        "geometry",
        (
            "gearopt.flank",
            "gearopt.flank_jet",
            "gearopt.envelope",
            "gearopt.envelope_nodes",
            "gearopt.blank",
            "gearopt.iso23509",
            "gearopt.thickness",
            "gearopt.assembly",
            "gearopt.te_target",
            "gearopt.chains",
        ),
    ),
    (
        "design",
        (
            "gearopt.design",
            "gearopt.declarations",
            "gearopt.analysis_options",
            "gearopt.load_options",
        ),
    ),
    (
        "plugin API",
        (
            "gearopt.hookspecs",
            "gearopt.commands",
            "gearopt.machine",
            "gearopt.evaluation",
            "gearopt.plausibility",
            "gearopt.plugins",
            "gearopt.design_files",
            "gearopt.rexs",
            "gearopt.testing",
        ),
    ),
    ("contact", ("gearopt.contact", "gearopt.mesh", "gearopt.newton_tca", "gearopt.loaded")),
    (
        "analysis",
        (
            "gearopt.analysis",
            "gearopt.figures",
            "gearopt.measurement",
            "gearopt.plots",
            "gearopt.plots_declared",
            "gearopt.warmup",
        ),
    ),
    ("trial", ("gearopt.studyfile", "gearopt.trial")),
    (
        "study",
        (
            "gearopt.results",
            "gearopt.storage",
            "gearopt.pools",
            "gearopt.recovery",
            "gearopt.samplers",
            "gearopt.drafts",
            "gearopt.best",
            "gearopt.stops",
            "gearopt.study_workers",
            "gearopt.study",
            "gearopt.export",
            "gearopt.dashboard",
        ),
    ),
    (
        "cli",
        (
            "gearopt.cli",
            "gearopt.flank_cli",
            "gearopt.blank_cli",
            "gearopt.measurement_cli",
            "gearopt.rexs_cli",
            "gearopt.study_cli",
            "gearopt.bench",
            "gearopt.json_schemas",
            "gearopt",
        ),
    ),
)
#: the layers of the built-in plugins (docs/architecture.md, Layers of the built-in plugins),
#: lowest first: a package imports from another only in a lower layer. Inside a package its
#: modules lie below its ``__init__`` (the plugin: hook implementations, the model's class)
PLUGINS = "gearopt_plugins"
PLUGIN_LAYERS = (
    ("shared", ("gearopt_plugins.cutters", "gearopt_plugins.face_hobbing")),
    (
        "plugins",
        (
            "gearopt_plugins.chain_error",
            "gearopt_plugins.cyclo_palloid",
            "gearopt_plugins.epicycloid",
            "gearopt_plugins.evaluators",
            "gearopt_plugins.face_milling",
            "gearopt_plugins.objectives",
        ),
    ),
)
#: Optuna's private attributes a module may read: none (the coordinator is on Optuna's public
#: API, tests/test_optuna_public.py)
OPTUNA_PRIVATE: set[tuple[str, str]] = set()


def _modules() -> dict[str, Path]:
    out = {}
    for name, folder in PACKAGES.items():
        for path in sorted(folder.rglob("*.py")):
            parts = [name, *path.relative_to(folder).with_suffix("").parts]
            if parts[-1] == "__init__":
                parts = parts[:-1]
            out[".".join(parts)] = path
    return out


MODULES = _modules()


def _type_checking(node: ast.If) -> bool:
    test = node.test
    return (isinstance(test, ast.Name) and test.id == "TYPE_CHECKING") or (
        isinstance(test, ast.Attribute) and test.attr == "TYPE_CHECKING"
    )


class _Imports(ast.NodeVisitor):
    """Every import of a module: ``(line, target module, imported name or None, in a function)``."""

    def __init__(self, module: str, package: bool) -> None:
        self.module, self.package = module, package
        self.found: list[tuple[int, str, str | None, bool]] = []
        self.depth = 0

    def visit_FunctionDef(self, node) -> None:
        self.depth += 1
        self.generic_visit(node)
        self.depth -= 1

    visit_AsyncFunctionDef = visit_FunctionDef

    def visit_If(self, node: ast.If) -> None:
        if _type_checking(node):
            for child in node.orelse:
                self.visit(child)
            return
        self.generic_visit(node)

    def visit_Import(self, node: ast.Import) -> None:
        for alias in node.names:
            self.found.append((node.lineno, alias.name, None, self.depth > 0))

    def visit_ImportFrom(self, node: ast.ImportFrom) -> None:
        if node.level:
            base = self.module.split(".")
            if not self.package:
                base = base[:-1]
            base = base[: len(base) - (node.level - 1)]
            source = ".".join(base + ([node.module] if node.module else []))
        else:
            source = node.module
        for alias in node.names:
            full = f"{source}.{alias.name}"
            if full in MODULES:  # a submodule
                self.found.append((node.lineno, full, None, self.depth > 0))
            else:
                self.found.append((node.lineno, source, alias.name, self.depth > 0))


def _imports() -> dict[str, list[tuple[int, str, str | None, bool]]]:
    out = {}
    for module, path in MODULES.items():
        visitor = _Imports(module, path.name == "__init__.py")
        visitor.visit(ast.parse(path.read_text(encoding="utf-8")))
        out[module] = visitor.found
    return out


IMPORTS = _imports()


def _internal(target: str) -> bool:
    return target.split(".")[0] in PACKAGES


def _cycles(edges: dict[str, set[str]]) -> list[list[str]]:
    """Strongly connected components of more than one module (Tarjan)."""
    index, low, stack, on, found = {}, {}, [], set(), []
    counter = [0]

    def visit(v: str) -> None:
        index[v] = low[v] = counter[0]
        counter[0] += 1
        stack.append(v)
        on.add(v)
        for w in edges.get(v, ()):
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            component = []
            while True:
                w = stack.pop()
                on.discard(w)
                component.append(w)
                if w == v:
                    break
            if len(component) > 1:
                found.append(sorted(component))

    for v in sorted(edges):
        if v not in index:
            visit(v)
    return found


def test_the_graph_sees_the_imports():
    # the graph is built from the real sources: it finds the modules and their imports
    assert {"gearopt.contact.engine", "gearopt.mesh", "gearopt_plugins.evaluators.tca"} <= set(
        MODULES
    )
    assert any(t == "gearopt.contact.kernels" for _, t, _, _ in IMPORTS["gearopt.contact.engine"])


def test_no_import_cycle():
    edges = defaultdict(set)
    for module, found in IMPORTS.items():
        for _, target, _, _ in found:
            if target in MODULES and target != module:
                edges[module].add(target)
    assert _cycles(edges) == []


def _layer(module: str) -> int:
    for k, (_, prefixes) in enumerate(LAYERS):
        for prefix in prefixes:
            if module == prefix or (prefix != "gearopt" and module.startswith(prefix + ".")):
                return k
    raise AssertionError(f"{module} is in no layer: add it to LAYERS and docs/architecture.md")


def test_layers_import_one_way():
    upward = [
        f"{module} ({LAYERS[_layer(module)][0]}) imports {target} ({LAYERS[_layer(target)][0]})"
        for module, found in IMPORTS.items()
        if module.split(".")[0] == "gearopt"
        for _, target, _, _ in found
        if target in MODULES and _layer(target) > _layer(module) and (module, target) not in LAZY
    ]
    assert upward == []


def test_no_private_name_crosses_a_module():
    crossing = [
        f"{module}:{line} imports {name} from {target}"
        for module, found in IMPORTS.items()
        for line, target, name, _ in found
        if _internal(target) and name and name.startswith("_") and not name.startswith("__")
    ]
    assert crossing == []


def test_no_module_imports_the_package_root():
    rooted = [
        f"{module}:{line}"
        for module, found in IMPORTS.items()
        if module.startswith("gearopt.")
        for line, target, _, _ in found
        if target == "gearopt"
    ]
    assert rooted == []


def test_imports_inside_functions_only_load_optional_dependencies():
    inner = [
        f"{module}:{line} imports {target}"
        for module, found in IMPORTS.items()
        for line, target, _, in_function in found
        if in_function
        and target.split(".")[0] not in OPTIONAL
        and (module, target) not in LAZY
        and _internal(target)
    ]
    assert inner == []


def test_the_reference_tca_is_no_production_dependency():
    users = {
        module
        for module, found in IMPORTS.items()
        for _, target, _, _ in found
        if target == REFERENCE and module != REFERENCE
    }
    assert users <= REFERENCE_USERS


def _own_private_names(tree: ast.AST) -> set[str]:
    """Private names a module defines: functions, classes, attributes it assigns (``x._a =``,
    class bodies), ``__slots__`` entries."""
    names = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.FunctionDef | ast.AsyncFunctionDef | ast.ClassDef):
            names.add(node.name)
        elif isinstance(node, ast.Attribute) and isinstance(node.ctx, ast.Store):
            names.add(node.attr)
        elif isinstance(node, ast.Name) and isinstance(node.ctx, ast.Store):
            names.add(node.id)
        elif isinstance(node, ast.Constant) and isinstance(node.value, str):
            names.add(node.value)  # __slots__, setattr and getattr names
    return {n for n in names if n.startswith("_")}


def test_no_private_attribute_of_another_modules_object_is_read():
    reads = []
    for module, path in MODULES.items():
        tree = ast.parse(path.read_text(encoding="utf-8"))
        own = _own_private_names(tree)
        for node in ast.walk(tree):
            if not (isinstance(node, ast.Attribute) and isinstance(node.ctx, ast.Load)):
                continue
            attr = node.attr
            if not attr.startswith("_") or attr.startswith("__") or attr in own:
                continue
            if (module, attr) in OPTUNA_PRIVATE:
                continue
            reads.append(f"{module}:{node.lineno} reads .{attr}")
    assert reads == []


@pytest.mark.parametrize("module", list(MODULES))
def test_no_module_over_800_lines(module):
    lines = MODULES[module].read_text(encoding="utf-8").count("\n")
    assert lines <= MAX_LINES, f"{module}: {lines} lines"


OUTSIDE = re.compile(r"DESIGN\.md|\.\./shared|shared/(?:reference|seeds|DESIGN)")


def test_nothing_cites_a_file_outside_the_repository():
    files = [
        *ROOT.glob("gearopt/**/*.py"),
        *ROOT.glob("plugins/**/*.py"),
        *ROOT.glob("tests/**/*.py"),
        *ROOT.glob("studies/**/*.py"),
        *ROOT.glob("studies/**/*.toml"),
        *ROOT.glob("docs/**/*.md"),
        ROOT / "README.md",
    ]
    citing = [
        f"{path.relative_to(ROOT)}:{k + 1}"
        for path in files
        if path != Path(__file__)
        for k, line in enumerate(path.read_text(encoding="utf-8").splitlines())
        if OUTSIDE.search(line)
    ]
    assert citing == []


def _plugin_package(module: str) -> str:
    """The top-level package of a built-in plugin module (``gearopt_plugins.x`` of
    ``gearopt_plugins.x.y``)."""
    return ".".join(module.split(".")[:2])


def _plugin_layer(module: str) -> int:
    package = _plugin_package(module)
    for k, (_, packages) in enumerate(PLUGIN_LAYERS):
        if package in packages:
            return k
    raise AssertionError(f"{package} is in no plugin layer: add it to PLUGIN_LAYERS and docs")


def test_plugins_hold_no_flat_module():
    folder = PACKAGES[PLUGINS]
    flat = [p.name for p in folder.glob("*.py") if p.name != "__init__.py"]
    assert flat == []
    # every folder of Python modules is a package
    loose = [
        str(d.relative_to(folder))
        for d in folder.rglob("*")
        if d.is_dir() and any(d.glob("*.py")) and not (d / "__init__.py").exists()
    ]
    assert loose == []
    packages = {_plugin_package(m) for m in MODULES if m.startswith(PLUGINS + ".")}
    assert packages == {p for _, layer in PLUGIN_LAYERS for p in layer}


def test_plugin_packages_import_one_way():
    wrong = []
    for module, found in IMPORTS.items():
        if module.split(".")[0] != PLUGINS or module == PLUGINS:
            continue
        for line, target, _, _ in found:
            if target not in MODULES or target.split(".")[0] != PLUGINS:
                continue
            if target == PLUGINS or (
                _plugin_package(target) != _plugin_package(module)
                and _plugin_layer(target) >= _plugin_layer(module)
            ):
                wrong.append(f"{module}:{line} imports {target}")
            elif module.startswith(target + "."):  # its own package's __init__: the plugin
                wrong.append(f"{module}:{line} imports its package {target}")
    assert wrong == []


def test_the_core_imports_no_built_in_plugin():
    found = [
        f"{module}:{line} imports {target}"
        for module, imports in IMPORTS.items()
        if module.split(".")[0] == "gearopt"
        for line, target, _, _ in imports
        if target.split(".")[0] == PLUGINS
    ]
    assert found == []


def _project() -> dict:
    return tomllib.loads((ROOT / "pyproject.toml").read_text(encoding="utf-8"))


def test_every_package_is_installed():
    # a wheel holds the packages pyproject.toml lists, not the folders beside them
    packages = {m for m, path in MODULES.items() if path.name == "__init__.py"}
    assert set(_project()["tool"]["setuptools"]["packages"]) == packages


def test_entry_points_name_modules_of_plugin_packages():
    points = _project()["project"]["entry-points"]["gearopt"]
    assert set(points) >= {"cyclo-palloid", "epicycloid", "face-milling", "tca", "objectives"}
    for name, target in points.items():
        module = target.split(":")[0]
        assert module in MODULES, name
        _plugin_layer(module)  # in a plugin package
        assert _plugin_package(module) in PLUGIN_LAYERS[-1][1], name
