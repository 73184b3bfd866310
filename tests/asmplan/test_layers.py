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
    """``asp/salbp.py`` -> ``asp.salbp``."""
    parts = path.relative_to(REPO).with_suffix("").parts
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


def imports(path: Path, package: str | None = None) -> list[tuple[int, str]]:
    """``(line, module)`` of every import in ``path`` (relative imports resolved; ``from m
    import x`` as ``m.x``, the module ``m.x`` or a name of ``m``)."""
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
            # ``from asmplan import pipeline`` imports the module asmplan.pipeline (the
            # graph takes the longest known prefix, so a name from a module stays that module)
            out += [(node.lineno, f"{module}.{alias.name}") for alias in node.names]
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
    assert found == ["arl.trainer", "torch"]


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


ASP_FLOORS = (
    ("errors", "numbers", "atomic", "heap", "cad_keys", "lazy"),
    ("game",),
    ("salbp",),
    ("spec",),
    ("graph",),
    ("schedule", "fromcad"),
    ("concurrent", "subassemblies"),
)
"""The rooms of ``asp`` from the ground up (a room: a sub-package or a top-level module). A
module imports its own room and the rooms of lower floors; two rooms of one floor never
import each other."""


def asp_room(module: str) -> str:
    """``asp.graph.symmetry`` -> ``graph``; ``asp.spec`` -> ``spec``."""
    return module.split(".")[1]


def floor(room: str) -> int:
    return next(k for k, rooms in enumerate(ASP_FLOORS) if room in rooms)


def test_every_asp_module_has_a_room():
    rooms = {room for rooms in ASP_FLOORS for room in rooms}
    homeless = [
        str(path.relative_to(REPO))
        for path in sources("asp")
        if module_name(path) != "asp" and asp_room(module_name(path)) not in rooms
    ]
    assert not homeless, f"place these in a room of ASP_FLOORS: {homeless}"


def test_asp_rooms_import_down():
    wrong = []
    for path in sources("asp"):
        name = module_name(path)
        if name == "asp":
            continue  # the package's face names what the rooms define
        room = asp_room(name)
        for line, module in imports(path):
            if module.split(".")[0] != "asp" or module == "asp":
                continue
            other = asp_room(module)
            if other != room and floor(other) >= floor(room):
                wrong.append(f"{path.relative_to(REPO)}:{line} ({room}) imports {module}")
    assert not wrong, f"asp's rooms import their own and lower floors only: {wrong}"


def test_no_module_imports_private_names():
    wrong = []
    for pkg in ("asp", "arl", "asmplan"):
        for path in sources(pkg):
            tree = ast.parse(path.read_text(encoding="utf-8"), filename=str(path))
            for node in ast.walk(tree):
                if not isinstance(node, ast.ImportFrom) or node.level or not node.module:
                    continue
                if node.module.split(".")[0] not in LAYERS:
                    continue
                wrong += [
                    f"{path.relative_to(REPO)}:{node.lineno} imports {node.module}.{a.name}"
                    for a in node.names
                    if a.name.startswith("_")
                ]
    assert not wrong, f"a private name stays in its module: {wrong}"


PACKAGES = sorted(
    {module_name(p) for pkg in LAYERS for p in sources(pkg) if p.name == "__init__.py"}
)


@pytest.mark.parametrize("package", PACKAGES)
def test_every_package_names_its_public_api(package):
    """Issue 22 B5: ``__all__`` in every package; each name is there (sub-packages import
    their modules only when a name is used, :mod:`asp.lazy`)."""
    import importlib.util

    module = importlib.import_module(package)
    assert isinstance(getattr(module, "__all__", None), list), f"{package}: no __all__"
    missing = [
        n
        for n in module.__all__
        if getattr(module, n, None) is None and importlib.util.find_spec(f"{package}.{n}") is None
    ]
    assert not missing, f"{package}.__all__ names what it does not have: {missing}"


def test_every_asp_module_room_names_its_public_api():
    """A room that is one module (``asp/spec.py``) names what others may use in its own
    ``__all__``, as a sub-package does in its ``__init__``."""
    import importlib

    wrong = []
    for path in sorted((REPO / "asp").glob("*.py")):
        if path.name == "__init__.py":
            continue
        module = importlib.import_module(f"asp.{path.stem}")
        names = getattr(module, "__all__", None)
        if not isinstance(names, list):
            wrong.append(f"asp.{path.stem}: no __all__")
            continue
        wrong += [f"asp.{path.stem}.{n}: not defined" for n in names if not hasattr(module, n)]
    assert not wrong, f"each module room names its public API: {wrong}"


def public_names(module: str) -> tuple[set[str], set[str]] | None:
    """The names others may import from ``module`` and the modules beside them: of an asp
    room (``asp.<room>.<module>``: the room's ``__all__``; ``asp.<module>``: the module's own)
    or of cad (``cad.<module>``: ``cad.__all__``); None for any other module."""
    import importlib

    parts = module.split(".")
    if parts[0] == "asp" and len(parts) == 3:
        room = importlib.import_module(".".join(parts[:2]))
        return set(room.__all__), {p.stem for p in (REPO / "asp" / parts[1]).glob("*.py")}
    if parts[0] == "asp" and len(parts) == 2 and (REPO / "asp" / f"{parts[1]}.py").is_file():
        return set(importlib.import_module(module).__all__), set()
    if parts[0] == "cad" and len(parts) == 2:
        import cad

        return set(cad.__all__), {p.stem for p in (REPO / "cad").glob("*.py")}
    return None


def test_asmplan_and_arl_use_the_public_names_of_asp_and_cad():
    """What asmplan and arl import from ``asp.<room>.<module>`` is in ``asp.<room>.__all__``
    (or is a module of the room), from ``asp.<module>`` in that module's ``__all__``, and from
    ``cad.<module>`` in ``cad.__all__``: add a new name to the room's face."""
    wrong = []
    for pkg in ("arl", "asmplan"):
        for path in sources(pkg):
            tree = ast.parse(path.read_text(encoding="utf-8"), filename=str(path))
            for node in ast.walk(tree):
                if not isinstance(node, ast.ImportFrom) or node.level or not node.module:
                    continue
                face = public_names(node.module)
                if face is None:
                    continue
                public, modules = face
                wrong += [
                    f"{path.relative_to(REPO)}:{node.lineno} {node.module}.{a.name}"
                    for a in node.names
                    if a.name not in public and a.name not in modules
                ]
    assert not wrong, f"not in the room's __all__ (its __init__.py, or the module's): {wrong}"


# --------------------------------------------------------------------------- turn models

TURN_REGISTRY = REPO / "asp" / "game" / "turns.py"
"""The one module that spells the turn models' names (:data:`asp.game.turns.TURNS`)."""


def turn_name_comparisons(path: Path, names) -> list[int]:
    """Lines of ``path`` that compare a value with a turn model's name written as a string
    (``x == "concurrent"``, ``"alternate" != x``, ``case "concurrent":``)."""
    tree = ast.parse(path.read_text(encoding="utf-8"), filename=str(path))

    def named(node) -> bool:
        return isinstance(node, ast.Constant) and node.value in names

    lines = []
    for node in ast.walk(tree):
        if isinstance(node, ast.Compare):
            sides = [node.left, *node.comparators]
            if any(isinstance(op, ast.Eq | ast.NotEq) for op in node.ops) and any(
                named(s) for s in sides
            ):
                lines.append(node.lineno)
        elif isinstance(node, ast.MatchValue) and named(node.value):
            lines.append(node.lineno)
    return lines


def test_turn_models_are_compared_through_the_registry():
    """Issue 22, "no seams": code that behaves by turn model looks it up in
    :data:`asp.game.turns.TURNS` (or compares with ``ALTERNATE.name``), never with the name
    spelled out, so a new game model is one entry there plus its modules."""
    from asp.game.turns import TURNS

    wrong = [
        f"{path.relative_to(REPO)}:{line}"
        for pkg in ("asp", "arl", "asmplan")
        for path in sources(pkg)
        if path != TURN_REGISTRY
        for line in turn_name_comparisons(path, set(TURNS))
    ]
    assert not wrong, f"compare with asp.game.turns (TURNS, ALTERNATE, ...): {wrong}"


def test_the_turn_name_reader_sees_each_form(tmp_path):
    probe = tmp_path / "probe.py"
    probe.write_text(
        'a = x == "concurrent"\nb = "alternate" != y\nc = "concurrent" in d\n'
        'match z:\n    case "concurrent":\n        pass\n'
    )
    assert turn_name_comparisons(probe, {"alternate", "concurrent"}) == [1, 2, 5]


def test_every_turn_model_has_its_lookups():
    """Each lookup above asp that names a turn model's classes or functions has an entry for
    every model of the registry."""
    from asmplan.advisor import ADVISORS
    from asmplan.cli.train import TRAINING_GAMES
    from asp.game.turns import TURNS
    from asp.spec import TURN_MODELS

    assert list(TURN_MODELS) == list(TURNS)
    for lookup in (ADVISORS, TRAINING_GAMES):
        assert sorted(lookup) == sorted(TURNS)
    assert all(cls.TURN_MODEL is TURNS[name] for name, cls in ADVISORS.items())


DOCUMENT_MODULES = ("asmplan/planfile.py",)
"""Modules that only write and read documents: they never open CAD (cad) nor compute (the
pipeline hands them computed values)."""


@pytest.mark.parametrize("path", DOCUMENT_MODULES)
def test_the_plan_document_module_reads_no_cad(path):
    cad_imports = [
        (line, name) for line, name in imports(REPO / path) if name.split(".")[0] == "cad"
    ]
    assert cad_imports == [], f"{path} imports cad at {cad_imports}: compute in asmplan.pipeline"
