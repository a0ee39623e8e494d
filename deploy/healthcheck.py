"""The container image's HEALTHCHECK: does the service answer `/api/health` in this container?

Exit 0 when it answers 200, 1 otherwise, as docker and podman expect. Only the standard
library: the image has no curl. The address and the scheme follow the server's own command
line (PID 1 in the container) and then the same INBETRIEB_* variables the server reads, so
`serve --port 9000` or a certificate given either way is checked where it serves.
"""

from __future__ import annotations

import http.client
import ipaddress
import os
import ssl
import sys
import urllib.request
from pathlib import Path

TIMEOUT_S = 4.0  # under the HEALTHCHECK's --timeout, so a hung service is a clear failure


def server_args() -> list[str]:
    """The server's options when PID 1 is `inbetrieb serve` (empty otherwise: --init, a shell)."""
    try:
        argv = Path("/proc/1/cmdline").read_bytes().decode().rstrip("\0").split("\0")
    except OSError:
        return []
    return argv[argv.index("serve") + 1 :] if "serve" in argv else []


def option(args: list[str], name: str, env: str, default: str | None) -> str | None:
    """An option's value as the server takes it: the option given wins over its variable."""
    for i, arg in enumerate(args):
        if arg == name and i + 1 < len(args):
            return args[i + 1]
        if arg.startswith(name + "="):
            return arg.split("=", 1)[1]
    return os.environ.get(env) or default


def url(host: str, port: str, scheme: str) -> str:
    """Where to ask: a wildcard bind answers on loopback; an IPv6 address in brackets."""
    host = {"0.0.0.0": "127.0.0.1", "::": "::1"}.get(host, host)
    try:
        if ipaddress.ip_address(host).version == 6:
            host = f"[{host}]"
    except ValueError:
        pass  # a name
    return f"{scheme}://{host}:{port}/api/health"


def healthy(address: str) -> bool:
    context = None
    if address.startswith("https"):
        # the certificate names the host clients use, not this loopback address: not checked
        context = ssl.create_default_context()
        context.check_hostname = False
        context.verify_mode = ssl.CERT_NONE
    try:
        with urllib.request.urlopen(address, timeout=TIMEOUT_S, context=context) as r:
            return bool(r.status == 200)
    except (OSError, http.client.HTTPException) as e:
        print(f"{address}: {e}", file=sys.stderr)
        return False


def main() -> int:
    args = server_args()
    host = option(args, "--host", "INBETRIEB_HOST", "127.0.0.1") or "127.0.0.1"
    port = option(args, "--port", "INBETRIEB_PORT", "8000") or "8000"
    tls = option(args, "--tls-cert", "INBETRIEB_TLS_CERT", None)
    return 0 if healthy(url(host, port, "https" if tls else "http")) else 1


if __name__ == "__main__":
    sys.exit(main())
