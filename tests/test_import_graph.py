"""No import cycle anywhere in the package, imports inside functions included.

Imports under ``if TYPE_CHECKING:`` are left out: they never run.

Every ``import sonar_gym...`` / ``from sonar_gym... import ...`` of every module (at any depth of
the syntax tree, so deferred imports count) is an edge to the module it names; a
``from package import name`` where ``name`` is a submodule is an edge to that submodule.
"""

from __future__ import annotations

import ast
import os
from pathlib import Path

import sonar_gym

ROOT = "sonar_gym"


def _module_files() -> dict[str, Path]:
    """Module name -> file (``envs``, ``agents``, ``train`` are linked in: links are followed)."""
    top = Path(sonar_gym.__file__).parent
    paths = [
        Path(folder) / name
        for folder, _, names in os.walk(top, followlinks=True)
        for name in names
        if name.endswith(".py")
    ]
    files = {}
    for path in sorted(paths):
        relative = path.relative_to(top).with_suffix("")
        parts = [ROOT, *relative.parts]
        if parts[-1] == "__init__":
            parts.pop()
        files[".".join(parts)] = path
    return files


def _imports(module: str, path: Path, modules: set[str]) -> set[str]:
    package = module if path.name == "__init__.py" else module.rpartition(".")[0]
    found = set()
    for node in _runtime_nodes(ast.parse(path.read_text())):
        if isinstance(node, ast.Import):
            names = [alias.name for alias in node.names]
        elif isinstance(node, ast.ImportFrom):
            base = node.module or ""
            if node.level:
                anchor = package.split(".")[: len(package.split(".")) - node.level + 1]
                base = ".".join([*anchor, base] if base else anchor)
            names = [base] + [f"{base}.{alias.name}" for alias in node.names]
        else:
            continue
        found |= {name for name in names if name in modules and name != module}
    return found


def _runtime_nodes(tree: ast.AST) -> list[ast.AST]:
    """Every node except those under ``if TYPE_CHECKING:`` (never executed)."""
    nodes, pending = [], [tree]
    while pending:
        node = pending.pop()
        nodes.append(node)
        if isinstance(node, ast.If) and "TYPE_CHECKING" in ast.unparse(node.test):
            pending.extend(node.orelse)
            continue
        pending.extend(ast.iter_child_nodes(node))
    return nodes


def _cycles(graph: dict[str, set[str]]) -> list[list[str]]:
    """Strongly connected components with more than one module (Tarjan)."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    on_stack: set[str] = set()
    components: list[list[str]] = []

    def visit(node: str) -> None:
        index[node] = low[node] = len(index)
        stack.append(node)
        on_stack.add(node)
        for target in graph[node]:
            if target not in index:
                visit(target)
                low[node] = min(low[node], low[target])
            elif target in on_stack:
                low[node] = min(low[node], index[target])
        if low[node] == index[node]:
            component = []
            while True:
                member = stack.pop()
                on_stack.discard(member)
                component.append(member)
                if member == node:
                    break
            if len(component) > 1:
                components.append(sorted(component))

    for node in graph:
        if node not in index:
            visit(node)
    return components


def _graph() -> dict[str, set[str]]:
    files = _module_files()
    return {module: _imports(module, path, set(files)) for module, path in files.items()}


def test_the_graph_sees_the_whole_package() -> None:
    graph = _graph()
    assert {"sonar_gym.envs.beacon_scan", "sonar_gym.agents.base", "sonar_gym.train.cli"} <= set(
        graph
    )
    assert "sonar_gym.envs.base" in graph["sonar_gym.envs.beacon_scan"]


def test_a_planted_cycle_is_found() -> None:
    assert _cycles({"a": {"b"}, "b": {"c"}, "c": {"a"}, "d": {"a"}}) == [["a", "b", "c"]]


def test_no_module_takes_part_in_an_import_cycle() -> None:
    graph = _graph()
    # a package's __init__ re-exporting its own submodules is how packages are built
    for module in graph:
        graph[module] = {t for t in graph[module] if not t.startswith(module + ".")}
    assert _cycles(graph) == []
