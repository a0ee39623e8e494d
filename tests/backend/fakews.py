"""A stand-in for a websocket that the telemetry hub sends to, in process."""

from __future__ import annotations


class FakeSocket:
    """Records what the hub sends; never blocks."""

    def __init__(self) -> None:
        self.frames: list[bytes] = []
        self.texts: list[str] = []
        self.close_code: int | None = None

    async def send_bytes(self, data: bytes) -> None:
        self.frames.append(data)

    async def send_text(self, data: str) -> None:
        self.texts.append(data)

    async def close(self, code: int = 1000, reason: str = "") -> None:
        self.close_code = code
