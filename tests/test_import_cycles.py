"""No import cycles between raycheck's modules: dependencies point one way (DESIGN.md:
harness -> mitsuba_ref -> tracer.scene, harness -> tracer), and within a package a module
that needs another's names imports it, never the reverse as well. Every import counts, also
one inside a function (a deferred import hides a cycle from Python, not from a reader); only
`if TYPE_CHECKING:` blocks are left out. Read from the source with `ast`, nothing imported."""
from __future__ import annotations

import ast
from pathlib import Path

REPO = Path(__file__).resolve().parent.parent
# the repository's folders as the installed package names (pyproject.toml's package-dir)
PACKAGES = {"tracer": "raycheck.tracer", "harness": "raycheck.harness",
            "mitsuba_ref": "raycheck.mitsuba_ref"}


def modules() -> dict[str, tuple[Path, bool]]:
    """Dotted name -> (file, whether it is a package's __init__)."""
    found = {}
    for folder, name in PACKAGES.items():
        for path in (REPO / folder).rglob("*.py"):
            parts = list(path.relative_to(REPO / folder).with_suffix("").parts)
            package = parts[-1] == "__init__"
            found[".".join([name, *(parts[:-1] if package else parts)])] = (path, package)
    return found


def _type_checking_only(node: ast.AST) -> bool:
    return isinstance(node, ast.If) and "TYPE_CHECKING" in ast.unparse(node.test)


def imported_names(module: str, path: Path, package: bool, known: set[str]) -> set[str]:
    """The modules a module's import statements name, absolute (relative ones resolved):
    `from pkg import name` names pkg.name where that is a module of `known`, else pkg."""
    here = module if package else module.rpartition(".")[0]
    names: set[str] = set()
    pending: list[ast.AST] = [ast.parse(path.read_text(), str(path))]
    while pending:
        for node in ast.iter_child_nodes(pending.pop()):
            if _type_checking_only(node):
                continue
            if isinstance(node, ast.Import):
                names.update(alias.name for alias in node.names)
            elif isinstance(node, ast.ImportFrom):
                if node.level:
                    base = here.split(".")[:len(here.split(".")) - (node.level - 1)]
                    source = ".".join(base + ([node.module] if node.module else []))
                else:
                    source = node.module or ""
                names.update(f"{source}.{alias.name}" if f"{source}.{alias.name}" in known
                             else source for alias in node.names)
            pending.append(node)
    return names


def import_graph() -> dict[str, set[str]]:
    """Module -> the project's modules it imports (a submodule imported by name is an edge to
    the submodule only, not to its package's __init__)."""
    found = modules()
    graph = {}
    for module, (path, package) in found.items():
        edges = set()
        for name in imported_names(module, path, package, set(found)):
            while name and name not in found:
                name = name.rpartition(".")[0]
            if name and name != module:
                edges.add(name)
        graph[module] = edges
    return graph


def cycles(graph: dict[str, set[str]]) -> list[list[str]]:
    """The strongly connected components of more than one module (Tarjan), sorted."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    found = []

    def visit(v: str) -> None:
        index[v] = low[v] = len(index)
        stack.append(v)
        for w in sorted(graph[v]):
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in stack:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            component = []
            while True:
                w = stack.pop()
                component.append(w)
                if w == v:
                    break
            if len(component) > 1:
                found.append(sorted(component))

    for v in sorted(graph):
        if v not in index:
            visit(v)
    return sorted(found)


def test_the_graph_sees_imports_of_every_form():
    graph = import_graph()
    # absolute, relative, deferred (inside a function) and of a package
    assert "raycheck.tracer.scene.request" in graph["raycheck.tracer.scene.flags"]
    assert "raycheck.harness.pytest_check" in graph["raycheck.harness.pytest_plugin"]
    assert "raycheck.harness.check_options" in graph["raycheck.harness.pytest_plugin"]
    assert "raycheck.tracer.scene" in graph["raycheck.harness.pytest_check"]


def test_cycles_are_found():
    assert cycles({"a": {"b"}, "b": {"c"}, "c": {"a"}, "d": {"a"}}) == [["a", "b", "c"]]
    assert cycles({"a": {"b"}, "b": set()}) == []


def test_no_import_cycle():
    assert cycles(import_graph()) == []


def test_dependencies_point_one_way():
    """The tracer knows nothing of Mitsuba or the harness; Mitsuba's side shares only the
    course contract (tracer.scene) and the Dr.Jit/LLVM and process setup with it."""
    graph = import_graph()
    shared = ("raycheck.tracer.scene", "raycheck.tracer.kernel.backend", "raycheck.tracer.process")
    for module, edges in graph.items():
        if module.startswith("raycheck.tracer"):
            assert not {e for e in edges if not e.startswith("raycheck.tracer")}, module
        if module.startswith("raycheck.mitsuba_ref"):
            wrong = {e for e in edges if e.startswith("raycheck.tracer")
                     and not e.startswith(shared)} | \
                    {e for e in edges if e.startswith("raycheck.harness")}
            assert not wrong, (module, wrong)


# The harness's layers, lowest first (docs/architecture.md): a module imports from its own
# package (or, at the top level, its own module) and from lower layers only. A layer is a
# package of harness/ or one of its top-level modules; bench/records.py, the benchmarks' records,
# sits with the records so that the pages can read it.
LAYERS = (
    {"records", "check_options", "versions"},
    {"bench.records"},
    {"renderers"},
    {"catalog", "submission"},
    {"cases", "provenance"},
    {"judge"},
    {"pages"},
    {"storage"},
    {"case_settings"},
    {"diagnosis"},
    {"pipeline"},
    {"bench"},
    {"commands"},
    {"pytest_check"},
    {"cli", "pytest_plugin"},
    {"__main__"},
)


def layer_of(module: str) -> tuple[int, str]:
    """(rank, name) of a harness module's layer."""
    rest = module.removeprefix("raycheck.harness.").split(".")
    name = ".".join(rest[:2]) if ".".join(rest[:2]) in LAYERS[1] else rest[0]
    return next(i for i, layer in enumerate(LAYERS) if name in layer), name


def test_every_harness_module_has_a_layer():
    named = {name for layer in LAYERS for name in layer}
    for module in import_graph():
        if module.startswith("raycheck.harness."):
            assert layer_of(module)[1] in named, module


def test_harness_layers_point_down():
    """The case pipeline, the diagnosis and the stores know nothing of the commands; the pages
    read records (and the judge's pictures) and import nothing of the pipeline."""
    wrong = []
    for module, edges in import_graph().items():
        if not module.startswith("raycheck.harness."):
            continue
        here = layer_of(module)
        for e in edges:
            if e.startswith("raycheck.harness."):
                there = layer_of(e)
                if there[0] > here[0] or (there[0] == here[0] and there != here):
                    wrong.append((module, e))
    assert wrong == []
