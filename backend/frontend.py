"""Serves the built browser HMI at `/` and the API documentation at `/docs`, both from our
own build (no third-party assets), or says how to build them."""

from __future__ import annotations

from pathlib import Path

from fastapi import FastAPI
from fastapi.responses import FileResponse, HTMLResponse, Response
from fastapi.staticfiles import StaticFiles

_NOT_BUILT = """<!doctype html><meta charset="utf-8"><title>Inbetrieb</title>
<p>The browser HMI and the API documentation are not built: <code>make run</code> builds
them. The API schema is at <a href="/openapi.json">/openapi.json</a>.</p>"""


def mount(app: FastAPI, dist: Path) -> None:
    """Mount `dist` at / after the API routes, so /api and /docs keep precedence."""

    @app.get("/docs", include_in_schema=False)
    def docs() -> Response:
        page = dist / "docs.html"
        return FileResponse(page) if page.is_file() else HTMLResponse(_NOT_BUILT)

    if (dist / "index.html").is_file():
        app.mount("/", StaticFiles(directory=dist, html=True), name="frontend")
        return

    @app.get("/", include_in_schema=False)
    def not_built() -> HTMLResponse:
        return HTMLResponse(_NOT_BUILT)
