"""The web service (issue 4 builds it out). For now: health and the parameter registry."""

from __future__ import annotations

from typing import Any

from fastapi import FastAPI

from nc_sim.params import registry

app = FastAPI(title="Inbetrieb", version="0.1.0")


@app.get("/api/health")
def health() -> dict[str, str]:
    return {"status": "ok"}


@app.get("/api/parameters")
def parameters() -> list[dict[str, Any]]:
    """Every parameter the simulated NC knows, with range, unit kind and default."""
    return [
        {
            "id": d.id,
            "name": d.name,
            "scope": d.scope.value,
            "dtype": d.dtype.value,
            "quantity": d.quantity.value,
            "default": d.default,
            "effect": d.effect.value,
            "per_gear": d.per_gear,
            "title": d.title,
            "source": d.source,
        }
        for d in registry()
    ]
