"""The advisor service and the page to play the plan: ``asmplan serve``.

:func:`create_app` builds the FastAPI application (:mod:`asmplan.serve.app`) over plan
documents; sessions live in :mod:`asmplan.serve.sessions`; the page's files are in
``static/`` beside this file. ``create_app`` is imported on first use, so the command line
reads :mod:`asmplan.serve.limits` without loading the web framework.
"""

__all__ = ["create_app"]


def __getattr__(name: str):
    if name == "create_app":
        from asmplan.serve.app import create_app

        return create_app
    raise AttributeError(f"module 'asmplan.serve' has no attribute {name!r}")
