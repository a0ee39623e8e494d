"""Live telemetry: `/api/machines/{mid}/telemetry` websocket (protocol in api/telemetry.py)."""

from __future__ import annotations

import json

from fastapi import APIRouter, WebSocket, WebSocketDisconnect
from pydantic import ValidationError

from api.auth import Action
from api.telemetry import ErrorMessage, Hello, Subscribe
from backend.deps import ActorDep, ServicesDep, permit
from backend.errors import ApiError
from backend.services.status import signal_infos
from backend.services.telemetry import CLOSE_POLICY, Subscriber

CLOSE_UNSUPPORTED = 1003  # binary frame (RFC 6455 7.4.1)
CLOSE_INVALID = 1007  # payload we cannot take apart

router = APIRouter(prefix="/api/machines", tags=["telemetry"])


@router.websocket("/{mid}/telemetry", dependencies=[permit(Action.OBSERVE)])
async def telemetry(ws: WebSocket, mid: str, services: ServicesDep, actor: ActorDep) -> None:
    """Send `hello`, then binary frames for the subscribed signals and `event` messages.

    The client sends `{"type": "subscribe", "signals": [...]}` (again at any time to change
    them); `?signals=a,b` subscribes at once. A bad subscription gets an `error` reply; a
    binary message closes with 1003, JSON nested too deeply with 1007, a message over 64 KiB
    with 1009, a client that does not read what we send with 1008 (one that reads nothing at
    all answers no ping: the server's keepalive closes it with 1008 too).
    """
    try:
        machine = services.machines.get(mid)
    except ApiError as e:
        await ws.close(code=4404, reason=str(e)[:120])
        return
    await ws.accept()
    hub = services.hub
    sub = hub.add(ws, machine, actor)
    sub.reply(
        Hello(
            machine=machine.id,
            cycle=machine.link.cycle,
            cycle_s=machine.link.cycle_s,
            signals=signal_infos(machine),
        )
    )
    query = ws.query_params.get("signals")
    if query:
        _subscribe(sub, {"signals": [n for n in query.split(",") if n]})
    try:
        while True:
            msg = await ws.receive()
            if msg["type"] == "websocket.disconnect":
                hub.lost(sub, msg.get("code", 1005))
                break
            code, reason = _read(sub, msg.get("text"))
            if not code and sub.flooding:
                code, reason = CLOSE_POLICY, "client sends without reading the replies"
            if code:
                await hub.end(sub, code, reason)
                break
    except WebSocketDisconnect:
        pass
    finally:
        hub.remove(sub)


def _read(sub: Subscriber, text: str | None) -> tuple[int, str]:
    """Act on one client message; returns a close code and reason for a message that ends the
    connection (0 otherwise). Messages larger than MAX_MESSAGE_BYTES never get here: the server
    closes those with 1009 while they stream in."""
    if text is None:
        return CLOSE_UNSUPPORTED, "binary messages are not part of the protocol"
    try:
        data = json.loads(text)
    except RecursionError:
        return CLOSE_INVALID, "JSON nested too deeply"
    except ValueError as e:
        sub.reply(ErrorMessage(message=f"bad message: not JSON ({e})"))
        return 0, ""
    _subscribe(sub, data)
    return 0, ""


def _subscribe(sub: Subscriber, data: object) -> None:
    """Subscribe as asked, or reply what is wrong with the request (without echoing it)."""
    try:
        sub.subscribe(Subscribe.model_validate(data))
    except ValidationError as e:
        problems = "; ".join(
            f"{'.'.join(map(str, err['loc'])) or 'message'}: {err['msg']}"
            for err in e.errors(include_input=False)[:5]
        )
        sub.reply(ErrorMessage(message=f"bad message: {problems}"[:500]))
