"""The advisor service and the page to play the plan: ``asmplan serve``.

:func:`create_app` builds the FastAPI application (:mod:`asmplan.serve.app`) over plan
documents; sessions live in :mod:`asmplan.serve.sessions`; the page's files are in
``static/`` beside this file.
"""

from asmplan.serve.app import create_app

__all__ = ["create_app"]
