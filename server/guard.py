"""Host and Origin checks: a pure ASGI middleware in front of every route, the page and /ws.

A page on another site must not read the station (camera image, status) nor drive it, even from the
operator's own browser. Two browser tricks are closed here:
- DNS rebinding: a foreign name resolved to 127.0.0.1 arrives with that name in `Host`; only the
  names the station serves are accepted (loopback names, the `--host` name, config `allowed_hosts`,
  and the IP literal the connection arrived on: an IP literal cannot be rebound).
- Cross-origin requests: a browser names the calling page in `Origin` (fetch, form posts, websocket
  handshakes); only the station's own origin (same scheme, host and port as the request) passes.
  Requests without `Origin` (curl, scripts, the Python client) pass the Origin check.
Refusals are 403 with the API's JSON error body; nothing else runs. CORS stays closed: no
Access-Control-* header is ever sent.
"""

from __future__ import annotations

import ipaddress
from collections.abc import Iterable
from urllib.parse import urlsplit

from starlette.types import ASGIApp, Receive, Scope, Send

from server.errors import error_response

LOOPBACK_HOSTS = ("127.0.0.1", "localhost", "::1")
_UNSPECIFIED = ("", "0.0.0.0", "::")


def normalize_host(name: str) -> str:
    """A host name as compared here: lower case, no trailing dot, IPv6 without brackets."""
    return name.strip().lower().rstrip(".").strip("[]")


def allowed_host_names(extra: Iterable[str] = ()) -> frozenset[str]:
    """The loopback names plus `extra` (the --host name, config allowed_hosts); bind-all addresses are not names."""
    names = {normalize_host(name) for name in (*LOOPBACK_HOSTS, *extra)}
    return frozenset(name for name in names if name not in _UNSPECIFIED)


def split_host(value: str, default_port: int) -> tuple[str, int] | None:
    """(host, port) of a Host header value or an Origin's netloc; None when malformed."""
    if not value or any(char in value for char in "/?#@ \t"):
        return None
    try:
        parts = urlsplit("//" + value)
        port = parts.port
    except ValueError:
        return None
    if not parts.hostname:
        return None
    return normalize_host(parts.hostname), port if port is not None else default_port


def _is_ip(name: str) -> bool:
    try:
        ipaddress.ip_address(name)
    except ValueError:
        return False
    return True


class HostOriginGuard:
    """ASGI middleware: 403 for a Host the station does not serve or a foreign Origin (HTTP and websocket)."""

    def __init__(self, app: ASGIApp, allowed_hosts: Iterable[str] = ()) -> None:
        self.app = app
        self.allowed_hosts = allowed_host_names(allowed_hosts)

    async def __call__(self, scope: Scope, receive: Receive, send: Send) -> None:
        if scope["type"] not in ("http", "websocket"):
            await self.app(scope, receive, send)
            return
        refusal = self.refusal(scope)
        if refusal is None:
            await self.app(scope, receive, send)
            return
        response = error_response(403, "forbidden", refusal)
        if scope["type"] == "websocket":
            if "websocket.http.response" not in scope.get("extensions", {}):
                await send({"type": "websocket.close", "code": 1008, "reason": "forbidden"})  # the server answers 403
                return
        await response(scope, receive, send)  # on a websocket scope Starlette sends it as the denial response

    def refusal(self, scope: Scope) -> str | None:
        """Why this request is refused, or None when its Host and Origin are the station's own."""
        headers = _headers(scope)
        secure = scope.get("scheme") in ("https", "wss")
        default_port = 443 if secure else 80
        host_value = headers.get("host")
        host = split_host(host_value, default_port) if host_value is not None else None
        if host is None or not self._serves(host[0], scope):
            shown = (host_value or "")[:80]
            return (
                f"refused: Host {shown!r} is not a name this station serves "
                f"(serves {', '.join(sorted(self.allowed_hosts))}; add others to allowed_hosts in config/station.yaml)"
            )
        origin = headers.get("origin")
        if origin is not None and not self._same_origin(origin, host, secure):
            return f"refused: cross-origin request from Origin {origin[:80]!r}; only pages served by this station may call it"
        return None

    def _serves(self, name: str, scope: Scope) -> bool:
        if name in self.allowed_hosts:
            return True
        server = scope.get("server")
        return bool(server) and _is_ip(name) and name == normalize_host(str(server[0]))

    @staticmethod
    def _same_origin(origin: str, host: tuple[str, int], secure: bool) -> bool:
        scheme, _, netloc = origin.partition("://")
        if scheme.lower() != ("https" if secure else "http"):
            return False
        return split_host(netloc, 443 if secure else 80) == host


def _headers(scope: Scope) -> dict[str, str]:
    """The request headers that matter here (first value of each), decoded as latin-1."""
    found: dict[str, str] = {}
    for raw_name, raw_value in scope.get("headers", ()):
        name = raw_name.decode("latin-1").lower()
        if name in ("host", "origin"):
            found[name] = "" if name in found else raw_value.decode("latin-1")  # repeated: malformed, refused
    return found
