"""Layers without a cycle: the import graph of src/robustgait, function-local and type-checking imports included; and
packages in the layers of docs/design.md, bottom to top, none importing a package above its own."""

from __future__ import annotations

import ast
from pathlib import Path

import robustgait

SRC = Path(robustgait.__file__).parent


def module_name(path: Path) -> str:
    rel = path.relative_to(SRC.parent).with_suffix("")
    parts = list(rel.parts)
    if parts[-1] == "__init__":
        parts.pop()
    return ".".join(parts)


def import_graph() -> dict[str, set[str]]:
    """Module → the robustgait modules it imports anywhere in its body (an import of a package's name resolves to
    the submodule when it is one)."""
    files = {module_name(p): p for p in SRC.rglob("*.py")}
    graph: dict[str, set[str]] = {m: set() for m in files}
    for mod, path in files.items():
        package = mod if path.name == "__init__.py" else mod.rsplit(".", 1)[0]
        for node in ast.walk(ast.parse(path.read_text())):
            targets: list[str] = []
            if isinstance(node, ast.Import):
                targets = [a.name for a in node.names]
            elif isinstance(node, ast.ImportFrom):
                base = node.module or ""
                if node.level:
                    base = ".".join(package.split(".")[: len(package.split(".")) - node.level + 1] + ([base] if base
                                                                                                     else []))
                targets = [f"{base}.{a.name}" if f"{base}.{a.name}" in files else base for a in node.names]
            for t in targets:
                while t and t not in files and "." in t:
                    t = t.rsplit(".", 1)[0]
                if t in files and t != mod:
                    graph[mod].add(t)
    return graph


def cycles(graph: dict[str, set[str]]) -> list[list[str]]:
    """Strongly connected components of more than one module (Tarjan)."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    on: set[str] = set()
    out: list[list[str]] = []

    def visit(v: str) -> None:
        index[v] = low[v] = len(index)
        stack.append(v)
        on.add(v)
        for w in graph[v]:
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            comp = []
            while True:
                w = stack.pop()
                on.discard(w)
                comp.append(w)
                if w == v:
                    break
            if len(comp) > 1:
                out.append(sorted(comp))

    for v in sorted(graph):
        if v not in index:
            visit(v)
    return out


def test_the_import_graph_has_no_cycle():
    graph = import_graph()
    assert len(graph) >= 60 and "robustgait.config" in graph["robustgait.certificate.certify"]
    assert cycles(graph) == []


def test_the_check_finds_a_cycle():
    assert cycles({"a": {"b"}, "b": {"c"}, "c": {"a"}, "d": {"a"}}) == [["a", "b", "c"]]


def test_data_modules_read_no_files_and_the_config_imports_no_pipeline():
    graph = import_graph()
    for data in ("robustgait.gait", "robustgait.robots.spec"):
        assert not any(m.startswith("robustgait.io") for m in graph[data]), (data, graph[data])
    for m, deps in graph.items():
        if m.startswith("robustgait.config"):
            assert all(d.startswith(("robustgait.config", "robustgait.errors")) for d in deps), (m, deps)


# the packages of docs/design.md's table, bottom to top ("__init__": the package robustgait itself)
LAYERS = ("errors", "_lazy", "config", "bezier", "rotations", "robots", "gait", "domains", "closure", "dynamics",
          "learn", "io", "sim", "inspection", "certificate", "gaitgen", "robotinit", "validate", "study", "report",
          "web", "cli", "__init__")


def package_of(module: str) -> str:
    """robustgait.X.y → X; robustgait itself → __init__."""
    parts = module.split(".")
    return parts[1] if len(parts) > 1 else "__init__"


def upward_imports(graph: dict[str, set[str]], layers: tuple[str, ...]) -> list[tuple[str, str]]:
    """The (module, imported module) pairs whose imported package lies above the importer's in ``layers``."""
    rank = {p: i for i, p in enumerate(layers)}
    return sorted((m, d) for m, deps in graph.items() for d in deps
                  if rank[package_of(d)] > rank[package_of(m)])


def test_no_package_imports_one_above_it():
    graph = import_graph()
    assert {package_of(m) for m in graph} == set(LAYERS)  # a new package takes its place in the layers
    assert upward_imports(graph, LAYERS) == []


def test_the_layer_check_finds_an_upward_import():
    graph = {"robustgait.sim.walk": {"robustgait.certificate.orbit"}, "robustgait.certificate.orbit": set()}
    assert upward_imports(graph, ("sim", "certificate")) == [("robustgait.sim.walk", "robustgait.certificate.orbit")]
    assert upward_imports(graph, ("certificate", "sim")) == []


def test_the_layers_are_the_design_documents():
    """docs/design.md names each package's layer in this order (its table, bottom to top)."""
    text = (SRC.parents[1] / "docs" / "design.md").read_text()
    table = text[text.index("| layer | module | owns |"):]
    table = table[:table.index("\n\n")]
    found = [p for p in LAYERS if p not in ("__init__", "_lazy")]
    where = {p: min(i for i in (table.find(f"`{p}/"), table.find(f"`{p}.py")) if i >= 0) for p in found}
    assert sorted(found, key=where.__getitem__) == found


def test_the_tests_mirror_the_package():
    """tests/ mirrors src/robustgait: each test folder is named after a package, and holds the tests of its modules;
    the tests left at the top are those of top-level modules (bezier.py, dynamics.py, …) and of the whole (imports,
    contracts, the public API)."""
    tests = Path(__file__).resolve().parent
    packages = {p.name for p in SRC.iterdir() if (p / "__init__.py").is_file()}
    folders = {p.name for p in tests.iterdir() if p.is_dir() and p.name not in ("data", "__pycache__")}
    assert folders <= packages, f"test folders with no package of that name: {sorted(folders - packages)}"
    modules = {p.stem for p in SRC.glob("*.py")}
    whole = {"imports", "contracts", "init"}
    top = {p.stem.removeprefix("test_") for p in tests.glob("test_*.py")}
    assert top <= modules | whole, f"top-level tests of no top-level module: {sorted(top - modules - whole)}"
