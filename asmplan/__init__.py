"""asmplan: the application layer over ``cad`` <- ``asp`` <- ``arl``.

It holds what people use: the command line (:mod:`asmplan.cli`) and the experiment runner
that reproduces the paper (:mod:`asmplan.experiments`).
"""

__all__ = ["advisor", "errors", "pipeline", "planfile"]
"""The modules asmplan's users call (imported as ``from asmplan import pipeline``)."""
