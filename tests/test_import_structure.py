"""The import rules of CONTRIBUTING.md, read from the source with ``ast`` (nothing is imported):
no two modules import each other, even through a longer circle, and the rooms of ``core`` and
``addon`` import one way, the shared helpers at ``core``'s top importing none of them; ``core``
never imports bpy, ``addon`` or ``operators``, and ``addon`` never ``operators``; imports inside
the package are relative and name modules and names that exist (lazy imports included, which
would otherwise wait for the slow tests), as do those of ``bench/``, ``tools/`` and ``tests/``;
pyproject.toml lists every subpackage. Imports count wherever they stand."""
from __future__ import annotations

import ast
import tomllib
from dataclasses import dataclass, field
from pathlib import Path

import pytest

from conftest import ROOT

PACKAGE = "xsl_render"
LAYERS = ("core", "addon", "operators")
BLENDER_MODULES = {"bpy", "bmesh", "mathutils", "gpu", "bl_math", "idprop", "aud", "freestyle"}
OUTSIDE = ("tests", "bench", "tools", "example_blends")


@dataclass
class Module:
    name: str                      # dotted, e.g. xsl_render.core.files
    path: Path
    is_package: bool
    tree: ast.Module
    defined: set[str] = field(default_factory=set)
    open_ended: bool = False       # star import or module __getattr__: any name may exist


def top_level_names(tree: ast.Module) -> tuple[set[str], bool]:
    names: set[str] = set()
    open_ended = False

    def visit(body):
        nonlocal open_ended
        for node in body:
            if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef, ast.ClassDef)):
                names.add(node.name)
                if node.name == "__getattr__":
                    open_ended = True
            elif isinstance(node, (ast.Assign, ast.AnnAssign, ast.AugAssign)):
                targets = node.targets if isinstance(node, ast.Assign) else [node.target]
                for target in targets:
                    names.update(n.id for n in ast.walk(target) if isinstance(n, ast.Name))
            elif isinstance(node, (ast.Import, ast.ImportFrom)):
                for alias in node.names:
                    if alias.name == "*":
                        open_ended = True
                    else:
                        names.add(alias.asname or alias.name.partition(".")[0])
            elif isinstance(node, (ast.If, ast.Try, ast.With)):
                for part in ("body", "orelse", "finalbody", "handlers"):
                    inner = getattr(node, part, [])
                    for item in inner:
                        visit(item.body if isinstance(item, ast.ExceptHandler) else [item])

    visit(tree.body)
    return names, open_ended


def load_package(root: Path, package: str, layers: tuple[str, ...]) -> dict[str, Module]:
    """Every module of the package whose folder is ``root``: its own __init__.py and the
    layers below it."""
    paths = [root / "__init__.py"] + [p for layer in layers for p in sorted((root / layer).rglob("*.py"))]
    modules = {}
    for path in paths:
        parts = path.relative_to(root).with_suffix("").parts
        is_package = parts[-1] == "__init__"
        name = ".".join((package, *(parts[:-1] if is_package else parts)))
        tree = ast.parse(path.read_text(encoding="utf-8"), filename=str(path))
        module = Module(name, path, is_package, tree)
        module.defined, module.open_ended = top_level_names(tree)
        modules[name] = module
    return modules


@dataclass(frozen=True)
class Import:
    source: str                    # importing module
    target: str                    # imported module (a submodule when ``from pkg import sub``)
    line: int
    name: str | None = None        # for ``from X import name``: the name, when not a module


def resolve(module: Module, node: ast.ImportFrom) -> str:
    if node.level == 0:
        return node.module or ""
    package = module.name if module.is_package else module.name.rpartition(".")[0]
    parts = package.split(".")
    if node.level - 1 > len(parts) - 1:
        return ""                  # above the top package: reported as missing
    base = parts[:len(parts) - (node.level - 1)]
    return ".".join(base + ([node.module] if node.module else []))


def imports_of(module: Module, modules: dict[str, Module]) -> list[Import]:
    found = []
    for node in ast.walk(module.tree):
        if isinstance(node, ast.Import):
            found += [Import(module.name, alias.name, node.lineno) for alias in node.names]
        elif isinstance(node, ast.ImportFrom):
            target = resolve(module, node)
            for alias in node.names:
                sub = f"{target}.{alias.name}"
                if sub in modules:
                    found.append(Import(module.name, sub, node.lineno))
                else:
                    found.append(Import(module.name, target, node.lineno,
                                        None if alias.name == "*" else alias.name))
    return found


def import_graph(modules: dict[str, Module], package: str) -> dict[str, set[str]]:
    graph: dict[str, set[str]] = {name: set() for name in modules}
    for module in modules.values():
        for imp in imports_of(module, modules):
            if imp.target in modules and imp.target != module.name:
                graph[module.name].add(imp.target)
    return graph


def mutual_pairs(graph: dict[str, set[str]]) -> list[tuple[str, str]]:
    return sorted((a, b) for a, targets in graph.items() for b in targets if a < b and a in graph.get(b, ()))


def cycles(graph: dict[str, set[str]]) -> list[list[str]]:
    """The strongly connected components with more than one module (Tarjan)."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    on_stack: set[str] = set()
    found: list[list[str]] = []

    def connect(node: str) -> None:
        index[node] = low[node] = len(index)
        stack.append(node)
        on_stack.add(node)
        for nxt in sorted(graph.get(node, ())):
            if nxt not in index:
                connect(nxt)
                low[node] = min(low[node], low[nxt])
            elif nxt in on_stack:
                low[node] = min(low[node], index[nxt])
        if low[node] == index[node]:
            component = []
            while True:
                member = stack.pop()
                on_stack.discard(member)
                component.append(member)
                if member == node:
                    break
            if len(component) > 1:
                found.append(sorted(component))

    for node in sorted(graph):
        if node not in index:
            connect(node)
    return found


def room_of(name: str, modules: dict[str, Module], package: str) -> str:
    """The subpackage a module sits in below its layer ("core.maps"), or the layer itself
    for the modules at the layer's top ("core": the shared helpers)."""
    parts = name.split(".")
    if len(parts) > 3 or (len(parts) == 3 and modules[name].is_package):
        return ".".join(parts[1:3])
    return parts[1] if len(parts) > 1 else package


def room_graph(graph: dict[str, set[str]], modules: dict[str, Module], package: str,
               layers: tuple[str, ...]) -> dict[str, set[str]]:
    """Imports between the rooms of the given layers (other layers left out)."""
    rooms: dict[str, set[str]] = {}
    for source, targets in graph.items():
        a = room_of(source, modules, package)
        if a.partition(".")[0] not in layers:
            continue
        rooms.setdefault(a, set())
        for target in targets:
            b = room_of(target, modules, package)
            if b != a and b.partition(".")[0] in layers:
                rooms[a].add(b)
    return rooms


def layer_of(name: str, package: str) -> str | None:
    parts = name.split(".")
    return parts[1] if len(parts) > 1 and parts[0] == package else None


def layer_violations(modules: dict[str, Module], package: str) -> list[str]:
    bad = []
    for module in modules.values():
        layer = layer_of(module.name, package)
        for imp in imports_of(module, modules):
            top = imp.target.partition(".")[0]
            target_layer = layer_of(imp.target, package)
            where = f"{module.path.name}:{imp.line} ({module.name})"
            if layer == "core" and top in BLENDER_MODULES:
                bad.append(f"{where} imports {imp.target}: core never imports Blender")
            if layer == "core" and target_layer in ("addon", "operators"):
                bad.append(f"{where} imports {imp.target}: core never imports {target_layer}")
            if layer == "addon" and target_layer == "operators":
                bad.append(f"{where} imports {imp.target}: addon never imports operators")
    return bad


def absolute_imports_inside(modules: dict[str, Module], package: str) -> list[str]:
    bad = []
    for module in modules.values():
        for node in ast.walk(module.tree):
            names = ([a.name for a in node.names] if isinstance(node, ast.Import)
                     else [node.module or ""] if isinstance(node, ast.ImportFrom) and node.level == 0
                     else [])
            bad += [f"{module.path.name}:{node.lineno} ({module.name}) imports {n} absolutely"
                    for n in names if n == package or n.startswith(package + ".")]
    return bad


def missing_targets(source: str, imports: list[Import], modules: dict[str, Module], package: str) -> list[str]:
    """Imports of our package that name a module or a name that does not exist."""
    bad = []
    for imp in imports:
        if not (imp.target == package or imp.target.startswith(package + ".")):
            continue
        target = modules.get(imp.target)
        if target is None:
            bad.append(f"{source}:{imp.line} imports {imp.target}, which does not exist")
        elif imp.name and not target.open_ended and imp.name not in target.defined:
            bad.append(f"{source}:{imp.line} imports {imp.name} from {imp.target}, which does not define it")
    return bad


@pytest.fixture(scope="module")
def modules():
    return load_package(ROOT, PACKAGE, LAYERS)


def test_no_two_modules_import_each_other(modules):
    graph = import_graph(modules, PACKAGE)
    assert mutual_pairs(graph) == []
    assert cycles(graph) == []


def test_subpackages_import_one_way_and_shared_helpers_import_none(modules):
    rooms = room_graph(import_graph(modules, PACKAGE), modules, PACKAGE, ("core", "addon"))
    assert cycles(rooms) == []
    assert sorted(room for room in rooms["core"] if room.startswith("core.")) == []


def test_core_is_blender_free_and_addon_never_imports_operators(modules):
    assert layer_violations(modules, PACKAGE) == []


def test_package_imports_are_relative_and_resolve(modules):
    assert absolute_imports_inside(modules, PACKAGE) == []
    bad = []
    for module in modules.values():
        bad += missing_targets(str(module.path.relative_to(ROOT)), imports_of(module, modules), modules, PACKAGE)
    assert bad == []


def test_scripts_and_tests_import_modules_that_exist(modules):
    bad = []
    for folder in OUTSIDE:
        for path in sorted((ROOT / folder).rglob("*.py")):
            script = Module(path.stem, path, False, ast.parse(path.read_text(encoding="utf-8")))
            bad += missing_targets(str(path.relative_to(ROOT)), imports_of(script, modules), modules, PACKAGE)
    assert bad == []


def test_pyproject_lists_every_package(modules):
    config = tomllib.loads((ROOT / "pyproject.toml").read_text(encoding="utf-8"))["tool"]["setuptools"]
    assert config["package-dir"] == {PACKAGE: "."}
    packages = sorted(name for name, module in modules.items() if module.is_package)
    assert sorted(config["packages"]) == packages


# ---------------------------------------------------------------------------------------
# The checks themselves must be able to fail: a small package that breaks every rule.

def _write(root: Path, files: dict[str, str]) -> None:
    for rel, text in files.items():
        path = root / rel
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_text(text, encoding="utf-8")


def test_the_checks_catch_what_they_are_for(tmp_path):
    _write(tmp_path, {
        "__init__.py": "",
        "core/__init__.py": "",
        "core/a.py": "from .b import B\nA = 1\n",
        "core/b.py": "def f():\n    from .a import A\nB = 2\nimport bpy\n",
        "core/c.py": "from ..addon.x import X\nfrom .gone import Y\nfrom .a import NOT_THERE\n",
        "core/d.py": "from . import e\n",
        "core/e.py": "from .f import F\n",
        "core/f.py": "from .d import nothing_but_a_circle\n",
        "core/helper.py": "from .sub.m import M\n",
        "core/sub/__init__.py": "",
        "core/sub/m.py": "from ..other.n import N\nM = 1\n",
        "core/other/__init__.py": "",
        "core/sub/j.py": "J = 1\n",
        "core/other/n.py": "N = 2\n",
        "core/other/k.py": "def f():\n    from ..sub.j import J\n",
        "addon/__init__.py": "",
        "addon/x.py": "from ..operators import op\nimport pkg.core.a\nX = 3\n",
        "operators/__init__.py": "",
        "operators/op.py": "",
    })
    fake = load_package(tmp_path, "pkg", LAYERS)
    graph = import_graph(fake, "pkg")
    assert mutual_pairs(graph) == [("pkg.core.a", "pkg.core.b")]
    assert sorted(cycles(graph)) == [["pkg.core.a", "pkg.core.b"], ["pkg.core.d", "pkg.core.e", "pkg.core.f"]]
    rooms = room_graph(graph, fake, "pkg", ("core", "addon"))
    assert sorted(cycles(rooms)) == [["addon", "core"], ["core.other", "core.sub"]]
    assert "core.sub" in rooms["core"]
    violations = "\n".join(layer_violations(fake, "pkg"))
    assert "imports bpy" in violations and "core never imports addon" in violations
    assert "addon never imports operators" in violations
    assert len(absolute_imports_inside(fake, "pkg")) == 1
    missing = [m for module in fake.values()
               for m in missing_targets(module.name, imports_of(module, fake), fake, "pkg")]
    assert any("pkg.core.gone" in m for m in missing)
    assert any("NOT_THERE" in m for m in missing)
    assert any("nothing_but_a_circle" in m for m in missing)
