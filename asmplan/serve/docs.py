"""The API's browsable documentation, served from installed files (nothing from a CDN).

FastAPI's own ``/docs`` and ``/redoc`` pages load Swagger UI and ReDoc from a CDN and a
favicon from FastAPI's site: offline they are blank, and online they tell a third party who
opened them. :func:`add_docs` serves ``/docs`` with the Swagger UI files that the
``fastapi-offline`` package ships (a fixed table of names: no path from a request reaches
the file system) and Swagger's online validator off. ``/redoc`` is off: ReDoc always loads
its logo from Redocly's CDN and links to Redocly's site.
"""

from __future__ import annotations

from importlib import resources
from pathlib import Path

from fastapi import FastAPI, HTTPException
from fastapi.openapi.docs import (
    get_swagger_ui_html,
    get_swagger_ui_oauth2_redirect_html,
)
from fastapi.responses import FileResponse, HTMLResponse

DOCS_STATIC = "/docs-static"
"""Where the documentation pages' own files are served."""
DOCS_FILES = {
    "swagger-ui-bundle.js": "application/javascript",
    "swagger-ui.css": "text/css",
    "favicon.png": "image/png",
}
"""The files of ``fastapi_offline/static`` the pages use, with their media types."""
SWAGGER_PARAMETERS = {"validatorUrl": None}
"""Swagger UI settings: no online validation (it would send the API document away)."""


def docs_file(name: str) -> Path:
    """The installed file ``name`` (one of :data:`DOCS_FILES`)."""
    return Path(str(resources.files("fastapi_offline").joinpath("static", name)))


def add_docs(app: FastAPI, title: str) -> None:
    """Serve ``/docs`` (Swagger UI) and its files on ``app``, which was made with
    ``docs_url=None, redoc_url=None``."""
    redirect = "/docs/oauth2-redirect"

    @app.get("/docs", include_in_schema=False)
    def swagger() -> HTMLResponse:
        return get_swagger_ui_html(
            openapi_url=app.openapi_url,
            title=f"{title}: API",
            swagger_js_url=f"{DOCS_STATIC}/swagger-ui-bundle.js",
            swagger_css_url=f"{DOCS_STATIC}/swagger-ui.css",
            swagger_favicon_url=f"{DOCS_STATIC}/favicon.png",
            oauth2_redirect_url=redirect,
            swagger_ui_parameters=SWAGGER_PARAMETERS,
        )

    @app.get(redirect, include_in_schema=False)
    def swagger_redirect() -> HTMLResponse:
        return get_swagger_ui_oauth2_redirect_html()

    @app.get(DOCS_STATIC + "/{name}", include_in_schema=False)
    def docs_static(name: str) -> FileResponse:
        if name not in DOCS_FILES:
            raise HTTPException(404, f"no documentation file {name!r}")
        return FileResponse(docs_file(name), media_type=DOCS_FILES[name])
