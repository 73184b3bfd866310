"""The packages import one way: ``cad`` <- ``asp`` <- ``arl`` <- ``asmplan``.

Every import is read from the source with :mod:`ast`, function-level ones included, so a
lazy import cannot hide a cycle; ``cad`` and ``asp`` never import torch (nor the RL stack).
"""

from __future__ import annotations

import ast
from pathlib import Path

import pytest

from tests.conftest import REPO

LAYERS = ("cad", "asp", "arl", "asmplan")
"""Bottom to top: a package may import the ones before it, never the ones after."""
NO_TORCH = {"cad", "asp"}
TORCH_STACK = ("torch", "stable_baselines3", "sb3_contrib", "tensorboard")


def module_name(path: Path) -> str:
    """``asp/readers/in2.py`` -> ``asp.readers.in2``."""
    parts = path.relative_to(REPO).with_suffix("").parts
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


def imports(path: Path, package: str | None = None) -> list[tuple[int, str]]:
    """``(line, module)`` of every import in ``path`` (relative imports resolved)."""
    tree = ast.parse(path.read_text(encoding="utf-8"), filename=str(path))
    if package is None:
        package = ".".join(path.relative_to(REPO).with_suffix("").parts[:-1])
    out = []
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            out += [(node.lineno, alias.name) for alias in node.names]
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                base = package.split(".")[: len(package.split(".")) - node.level + 1]
                module = ".".join([*base, node.module] if node.module else base)
            else:
                module = node.module or ""
            out.append((node.lineno, module))
    return out


def sources(package: str) -> list[Path]:
    return sorted((REPO / package).rglob("*.py"))


@pytest.mark.parametrize("package", LAYERS)
def test_imports_flow_one_way(package):
    above = LAYERS[LAYERS.index(package) + 1 :]
    wrong = [
        f"{path.relative_to(REPO)}:{line} imports {module}"
        for path in sources(package)
        for line, module in imports(path)
        if module.split(".")[0] in above
    ]
    assert not wrong, f"{package} may import only {LAYERS[: LAYERS.index(package)]}: {wrong}"


@pytest.mark.parametrize("package", sorted(NO_TORCH))
def test_cad_and_asp_never_import_torch(package):
    wrong = [
        f"{path.relative_to(REPO)}:{line} imports {module}"
        for path in sources(package)
        for line, module in imports(path)
        if module.split(".")[0] in TORCH_STACK
    ]
    assert not wrong


def test_the_reader_sees_function_level_imports(tmp_path):
    probe = tmp_path / "probe.py"
    probe.write_text("def f():\n    from arl import trainer\n    import torch\n")
    found = [m for _, m in imports(probe, package="asp")]
    assert found == ["arl", "torch"]


KNOWN_CYCLES: set[frozenset[str]] = set()
"""Cycles still to break (issue 10); do not add to this list, break the cycle instead."""


def module_graph() -> dict[str, set[str]]:
    """Module -> the project modules it imports (any level; packages' ``__init__`` left out)."""
    modules = {module_name(p): p for pkg in LAYERS for p in sources(pkg)}
    graph: dict[str, set[str]] = {m: set() for m in modules}
    for name, path in modules.items():
        for _, imported in imports(path):
            parts = imported.split(".")
            for k in range(len(parts), 1, -1):
                target = ".".join(parts[:k])
                if target in modules and target != name:
                    graph[name].add(target)
                    break
    return graph


def test_no_import_cycles():
    import networkx as nx

    g = nx.DiGraph([(a, b) for a, bs in module_graph().items() for b in bs])
    cycles = [c for c in nx.simple_cycles(g) if frozenset(c) not in KNOWN_CYCLES]
    assert not cycles, f"import cycles (function-level imports included): {cycles}"
