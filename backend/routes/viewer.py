"""`/rerun/…`: the bundled Rerun web viewer, forwarded from its loopback-only process."""

from __future__ import annotations

import httpx
from fastapi import APIRouter, Request
from fastapi.concurrency import run_in_threadpool
from fastapi.responses import RedirectResponse, StreamingResponse
from starlette.background import BackgroundTask

from api.auth import Action
from backend.deps import ServicesDep, permit
from backend.errors import ViewerSilent

router = APIRouter(include_in_schema=False)
_PASS = ("content-type", "content-encoding", "content-length", "cache-control", "etag")
# The viewer page may talk to this service only: no usage telemetry, release checks or web
# fonts leave a commissioning network from the engineer's browser.
_CSP = "connect-src 'self'; font-src 'self' data:; style-src 'self' 'unsafe-inline'"


@router.get("/rerun", dependencies=[permit(Action.CAPTURE)])
def rerun_root() -> RedirectResponse:
    return RedirectResponse("/rerun/")


@router.get("/rerun/{path:path}", dependencies=[permit(Action.CAPTURE)])
async def rerun_asset(path: str, request: Request, services: ServicesDep) -> StreamingResponse:
    """Stream one file of the viewer (index.html, its script, its wasm) from 127.0.0.1."""
    port = await run_in_threadpool(services.viewer.ensure)
    client = httpx.AsyncClient(timeout=httpx.Timeout(30.0, read=None))
    url = f"http://127.0.0.1:{port}/{path}"
    try:
        upstream = await client.send(
            client.build_request("GET", url, params=request.query_params), stream=True
        )
    except httpx.TransportError as e:
        await client.aclose()
        raise ViewerSilent(f"Rerun viewer: {e}") from None

    async def close() -> None:
        await upstream.aclose()
        await client.aclose()

    headers = {k: v for k, v in upstream.headers.items() if k.lower() in _PASS}
    headers["content-security-policy"] = _CSP
    return StreamingResponse(
        upstream.aiter_raw(),
        status_code=upstream.status_code,
        headers=headers,
        background=BackgroundTask(close),
    )
