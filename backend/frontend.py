"""Serves the built browser HMI at `/` (or says how to build it)."""

from __future__ import annotations

from pathlib import Path

from fastapi import FastAPI
from fastapi.responses import HTMLResponse
from fastapi.staticfiles import StaticFiles

_NOT_BUILT = """<!doctype html><meta charset="utf-8"><title>Inbetrieb</title>
<p>The browser HMI is not built. <code>make run</code> builds it; the API is at
<a href="/docs">/docs</a>.</p>"""


def mount(app: FastAPI, dist: Path) -> None:
    """Mount `dist` at / after the API routes, so /api and /docs keep precedence."""
    if (dist / "index.html").is_file():
        app.mount("/", StaticFiles(directory=dist, html=True), name="frontend")
        return

    @app.get("/", include_in_schema=False)
    def not_built() -> HTMLResponse:
        return HTMLResponse(_NOT_BUILT)
