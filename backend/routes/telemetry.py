"""Live telemetry: `/api/machines/{mid}/telemetry` websocket (protocol in api/telemetry.py)."""

from __future__ import annotations

import json

from fastapi import APIRouter, WebSocket, WebSocketDisconnect
from pydantic import ValidationError

from api.auth import Action
from api.telemetry import ErrorMessage, Hello, Subscribe
from backend.deps import ActorDep, ServicesDep
from backend.errors import ApiError
from backend.services.auth import authorize
from backend.services.status import signal_infos

router = APIRouter(prefix="/api/machines", tags=["telemetry"])


@router.websocket("/{mid}/telemetry")
async def telemetry(ws: WebSocket, mid: str, services: ServicesDep, actor: ActorDep) -> None:
    """Send `hello`, then binary frames for the subscribed signals and `event` messages.

    The client sends `{"type": "subscribe", "signals": [...]}` (again at any time to change
    them); `?signals=a,b` subscribes at once.
    """
    try:
        host = services.machines.get(mid)
        authorize(actor, Action.OBSERVE, mid)
    except ApiError as e:
        await ws.close(code=4403 if e.status == 403 else 4404, reason=str(e)[:120])
        return
    await ws.accept()
    hub = services.hub
    sub = hub.add(ws, host)
    sub.reply(
        Hello(machine=host.id, cycle=host.cycle, cycle_s=host.cycle_s, signals=signal_infos(host))
    )
    query = ws.query_params.get("signals")
    if query:
        sub.subscribe(Subscribe(signals=[n for n in query.split(",") if n]))
    try:
        while True:
            text = await ws.receive_text()
            try:
                sub.subscribe(Subscribe.model_validate(json.loads(text)))
            except (ValidationError, ValueError) as e:
                sub.reply(ErrorMessage(message=f"bad message: {e}"))
    except WebSocketDisconnect:
        pass
    finally:
        hub.remove(sub)
