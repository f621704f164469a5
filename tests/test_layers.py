"""The architecture, as data, and a test that keeps it: every import in `src/lumos` (an AST walk, imports inside
functions included) runs down the layers below, never up; no two modules import each other, directly or round a
loop; and no module imports another's `_private` names or reads them off it.

A newcomer reads the architecture from `LAYERS`: bottom to top, a module may import its own layer and the layers
below it. DESIGN.md §2 draws the same order.
"""

from __future__ import annotations

import ast
from collections import defaultdict
from pathlib import Path

import pytest

SRC = Path(__file__).resolve().parent.parent / "src" / "lumos"

#: lumos's layers, bottom to top: (what the layer is, the top-level modules and packages in it).
LAYERS = (
    ("foundation: settings, errors, the sRGB curve", ("config", "errors", "tonemap")),
    ("kernels (Numba, arrays only) and mesh operations (NumPy)", ("kernels", "mesh")),
    ("the scene model and the files scenes, models and images come from", ("scene", "io")),
    ("compile: a scene to flat arrays, BVH, polygons, patches", ("compile",)),
    ("the rendering methods and radiosity's solver", ("methods", "radiosity", "denoise")),
    ("the API: render and its Image, animations, the cluster, ray queries, progress, compile-time messages",
     ("api", "image", "queries", "jitwatch", "progress", "animate", "cluster", "live")),
    ("tools on top of the API (the preview page among them) and the command line",
     ("tools", "preview", "cli", "__main__", "__init__")),
)

#: Cycles allowed, each with its reason. Remove an entry when its cycle goes; the test fails on a stale one.
ALLOWED_CYCLES = {
    # `Solution.save`, `.load` and `.export` are the documented convenience methods of a solution; they import
    # their implementations (which build and read `Solution`s) when called.
    frozenset({"lumos.radiosity.solution", "lumos.radiosity.store", "lumos.radiosity.export"}):
        "Solution's save/load/export methods",
}


def module_name(path: Path, root: Path) -> str:
    parts = list(path.relative_to(root.parent).with_suffix("").parts)
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


def read_imports(root: Path):
    """{module: path} and the imports between them: (importer, imported module, name or None, line)."""
    modules = {module_name(p, root): p for p in root.rglob("*.py")}
    package = root.name
    edges = []
    for mod, path in modules.items():
        is_package = path.name == "__init__.py"
        for node in ast.walk(ast.parse(path.read_text(), str(path))):
            if isinstance(node, ast.ImportFrom):
                if node.level:
                    base = mod.split(".") if is_package else mod.split(".")[:-1]
                    base = base[:len(base) - node.level + 1]
                    target = ".".join(base + ([node.module] if node.module else []))
                else:
                    target = node.module or ""
                if target.split(".")[0] != package:
                    continue
                for alias in node.names:
                    sub = f"{target}.{alias.name}"
                    if sub in modules:  # `from . import tonemap`: the module itself
                        edges.append((mod, sub, None, node.lineno))
                    else:
                        edges.append((mod, target, alias.name, node.lineno))
            elif isinstance(node, ast.Import):
                edges += [(mod, a.name, None, node.lineno) for a in node.names if a.name.split(".")[0] == package]
    return modules, edges


def private_attributes(modules: dict, edges: list):
    """`module._name` reads where `module` is another lumos module imported under a name: (reader, line, what)."""
    found = []
    imported = defaultdict(set)  # module: the names it binds to lumos modules
    for a, b, name, _ in edges:
        if name is None and b in modules:
            imported[a].add(b.rsplit(".", 1)[-1])
    for mod, path in modules.items():
        tree = ast.parse(path.read_text(), str(path))
        aliases = set(imported[mod])
        for node in ast.walk(tree):
            if isinstance(node, ast.ImportFrom):
                aliases |= {a.asname for a in node.names if a.asname and a.name in imported[mod]}
        for node in ast.walk(tree):
            if (isinstance(node, ast.Attribute) and isinstance(node.value, ast.Name) and node.value.id in aliases
                    and node.attr.startswith("_") and not node.attr.startswith("__")):
                found.append((mod, node.lineno, f"{node.value.id}.{node.attr}"))
    return found


def layer_of(module: str, layers=LAYERS) -> int:
    parts = module.split(".")
    top = parts[1] if len(parts) > 1 else "__init__"
    for i, (_, names) in enumerate(layers):
        if top in names:
            return i
    raise AssertionError(f"{module}: in no layer of LAYERS; add its top-level name to the layer it belongs to")


def upward_imports(modules, edges, layers=LAYERS):
    return [f"{a}:{line} imports {b}{'.' + name if name else ''} ({layers[layer_of(a, layers)][0]} -> "
            f"{layers[layer_of(b, layers)][0]})"
            for a, b, name, line in edges if layer_of(b, layers) > layer_of(a, layers)]


def cycles(modules, edges):
    """The strongly connected components of more than one module (Tarjan), as frozensets."""
    graph = defaultdict(set)
    for a, b, _, _ in edges:
        if a != b and b in modules:
            graph[a].add(b)
    index, low, stack, on_stack, found = {}, {}, [], set(), []

    def visit(v):
        index[v] = low[v] = len(index)
        stack.append(v)
        on_stack.add(v)
        for w in sorted(graph[v]):
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on_stack:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            component = set()
            while True:
                w = stack.pop()
                on_stack.discard(w)
                component.add(w)
                if w == v:
                    break
            if len(component) > 1:
                found.append(frozenset(component))

    for v in sorted(modules):
        if v not in index:
            visit(v)
    return found


def private_imports(edges):
    return [f"{a}:{line} imports {name} from {b}" for a, b, name, line in edges
            if name and name.startswith("_") and not name.startswith("__") and a != b]


@pytest.fixture(scope="module")
def lumos_imports():
    return read_imports(SRC)


def test_every_module_is_in_a_layer(lumos_imports):
    modules, _ = lumos_imports
    for mod in modules:
        layer_of(mod)


def test_imports_run_down_the_layers(lumos_imports):
    assert upward_imports(*lumos_imports) == []


def test_no_module_imports_itself_round_a_loop(lumos_imports):
    found = set(cycles(*lumos_imports))
    assert found - set(ALLOWED_CYCLES) == set(), "import cycles"
    assert set(ALLOWED_CYCLES) - found == set(), "ALLOWED_CYCLES lists a cycle that is gone: remove it"


def test_no_module_imports_or_reads_another_modules_private_names(lumos_imports):
    modules, edges = lumos_imports
    assert private_imports(edges) == []
    assert private_attributes(modules, edges) == []


def test_the_checks_catch_what_they_are_for(tmp_path):
    """A made-up package with one of each fault: an upward import (inside a function), a cycle and a private
    import, and a private name read off a module."""
    root = tmp_path / "pkg"
    (root / "low").mkdir(parents=True)
    (root / "high").mkdir()
    (root / "__init__.py").write_text("")
    (root / "low" / "__init__.py").write_text("")
    (root / "high" / "__init__.py").write_text("")
    (root / "low" / "a.py").write_text("def f():\n    from ..high.b import g\n    return g()\n")
    (root / "high" / "b.py").write_text("from ..low import a\n\ndef g():\n    return a._hidden\n")
    (root / "high" / "c.py").write_text("from .b import _secret\nfrom .d import x\n")
    (root / "high" / "d.py").write_text("from . import c\nx = 1\n")
    layers = (("low", ("low",)), ("high", ("high", "__init__")))
    modules, edges = read_imports(root)
    assert upward_imports(modules, edges, layers) == ["pkg.low.a:2 imports pkg.high.b.g (low -> high)"]
    assert set(cycles(modules, edges)) == {frozenset({"pkg.low.a", "pkg.high.b"}),
                                           frozenset({"pkg.high.c", "pkg.high.d"})}
    assert private_imports(edges) == ["pkg.high.c:1 imports _secret from pkg.high.b"]
    assert private_attributes(modules, edges) == [("pkg.high.b", 4, "a._hidden")]
