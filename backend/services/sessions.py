"""Ended sessions end everything they hold: their telemetry websockets close (4401, "session
ended") and their control of any machine and their requests for it go.

A session or API token ends by logout, expiry, a new password, the user's removal or a revoked
token, also done by `inbetrieb user|token` in another process, straight in the store. So the
watch compares, every `period_s`, what websockets and control holders act through with the
store's live sessions and tokens; a route that ends one pokes it to look at once.
"""

from __future__ import annotations

import asyncio
import contextlib
import logging

from backend.services.accounts import Accounts
from backend.services.control import Control
from backend.services.telemetry import TelemetryHub
from backend.tasks import cancel

log = logging.getLogger(__name__)

CLOSE_SESSION_ENDED = 4401  # websocket close code: log in (or fetch a ticket) again
WATCH_S = 2.0


class SessionWatch:
    """Closes what ended sessions and tokens hold, within `period_s` of their end."""

    def __init__(
        self, accounts: Accounts, hub: TelemetryHub, control: Control, period_s: float = WATCH_S
    ) -> None:
        self.accounts = accounts
        self.hub = hub
        self.control = control
        self.period_s = period_s
        self._wake = asyncio.Event()
        self._loop: asyncio.AbstractEventLoop | None = None
        self._task: asyncio.Task[None] | None = None

    def start(self) -> None:
        self._loop = asyncio.get_running_loop()
        self._task = self._loop.create_task(self._run(), name="session-watch")

    async def stop(self) -> None:
        await cancel(self._task)

    def poke(self) -> None:
        """Look now (from any thread): a route ended a session, a token or a user."""
        if self._loop is not None:
            self._loop.call_soon_threadsafe(self._wake.set)

    async def _run(self) -> None:
        while True:
            with contextlib.suppress(TimeoutError):
                await asyncio.wait_for(self._wake.wait(), self.period_s)
            self._wake.clear()
            try:
                await self.sweep()
            except Exception:  # the store busy or gone: look again next period
                log.exception("checking for ended sessions failed")

    async def sweep(self) -> None:
        """Close the websockets and release the control of sessions no longer live."""
        live = await asyncio.to_thread(self.accounts.live)
        ended: set[str] = set()
        for sub in list(self.hub.subscribers):
            if sub.actor.session not in live:
                ended.add(sub.actor.session)
                self.hub.drop(sub, CLOSE_SESSION_ENDED, "session ended")
        for m in self.control.machines.proxies():
            c = m.control
            holders = {r.session for r in c.requests}
            if c.holder is not None:
                holders.add(c.holder.session)
            ended |= holders - live.keys()
        for session in ended:
            self.control.end_session(session, "the session ended")
