"""A package's public names, imported from its modules on first use (PEP 562).

A sub-package names its public API in ``__all__`` without importing its modules, so that
importing ``asp.graph`` stays cheap and the modules load only when a name is used::

    __all__, __getattr__ = lazy_exports(__name__, {"state_graph": ("StateGraph",)})

``asp.graph.StateGraph`` is then ``asp.graph.state_graph.StateGraph``. A name that is also a
module of the package (``asp.game.rules``) is left out: the module keeps that name.
"""

from __future__ import annotations

import importlib
from collections.abc import Callable


def lazy_exports(
    package: str, modules: dict[str, tuple[str, ...]]
) -> tuple[list[str], Callable[[str], object]]:
    """``(__all__, __getattr__)`` of ``package`` whose public names live in ``modules``
    (module name -> the names it defines).

    Raises
    ------
    ValueError
        A name listed under two modules.
    """
    home: dict[str, str] = {}
    for module, names in modules.items():
        for name in names:
            if name in home:
                raise ValueError(f"{package}: {name} listed under {home[name]} and {module}")
            home[name] = module

    def __getattr__(name: str) -> object:
        module = home.get(name)
        if module is None:
            raise AttributeError(f"module {package!r} has no attribute {name!r}")
        return getattr(importlib.import_module(f"{package}.{module}"), name)

    return sorted(home), __getattr__


__all__ = [
    "lazy_exports",
]
"""What other modules may use (asmplan and arl among them)."""
