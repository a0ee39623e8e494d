"""The report as PDF: the same HTML printed by headless Chromium (the Debian package the
project already needs for its browser tests), in a process of its own with a time limit, so
the event loop never waits for it. The page size and margins come from the HTML's print CSS
(`@page`); Chromium's own header and footer (date, file URL) are left off.
"""

from __future__ import annotations

import asyncio
import contextlib
import os
import signal
import tempfile
from pathlib import Path

from backend.errors import Unavailable

PRINT_TIMEOUT_S = 60.0


async def html_to_pdf(html: str, chromium: Path, timeout_s: float = PRINT_TIMEOUT_S) -> bytes:
    """Print `html` to PDF bytes with `chromium`; 503 when it is missing, fails or hangs."""
    if not chromium.is_file():
        raise Unavailable(
            f"the PDF needs Chromium at {chromium}, which is not installed "
            "(apt install chromium); the HTML report works without it"
        )
    with tempfile.TemporaryDirectory(prefix="inbetrieb-report-") as tmp:
        page, out = Path(tmp) / "report.html", Path(tmp) / "report.pdf"
        page.write_text(html, encoding="utf-8")
        proc = await asyncio.create_subprocess_exec(
            str(chromium),
            "--headless",
            "--no-sandbox",
            "--disable-gpu",
            "--no-first-run",
            "--no-pdf-header-footer",
            f"--user-data-dir={tmp}/profile",  # never the user's, never shared with another
            f"--print-to-pdf={out}",
            page.as_uri(),
            stdin=asyncio.subprocess.DEVNULL,
            stdout=asyncio.subprocess.DEVNULL,
            stderr=asyncio.subprocess.PIPE,
            start_new_session=True,  # its renderer and zygote processes go with it on a hang
        )
        try:
            _, err = await asyncio.wait_for(proc.communicate(), timeout_s)
        except TimeoutError:
            with contextlib.suppress(ProcessLookupError):
                os.killpg(proc.pid, signal.SIGKILL)
            await proc.wait()
            why = f"Chromium did not print the report within {timeout_s:g} s"
            raise Unavailable(why) from None
        data = out.read_bytes() if out.is_file() else b""
        if proc.returncode != 0 or not data.startswith(b"%PDF-"):
            tail = err.decode("utf-8", "replace").strip().splitlines()[-1:] or [""]
            why = f"Chromium could not print the report (exit {proc.returncode}): {tail[0]}"
            raise Unavailable(why[:500])
        return data
