"""The control token: from --token or $ARMLAB_TOKEN, else generated; compared in constant time."""

from __future__ import annotations

import hmac
import os
import secrets


def resolve_token(explicit: str | None = None) -> tuple[str, bool]:
    """(token, generated): the explicit token, else $ARMLAB_TOKEN, else a new random one."""
    for candidate in (explicit, os.environ.get("ARMLAB_TOKEN")):
        if candidate:
            return candidate, False
    return secrets.token_urlsafe(24), True


def token_matches(expected: str, given: str | None) -> bool:
    return given is not None and hmac.compare_digest(expected.encode(), given.encode())


def bearer_token(authorization: str | None) -> str | None:
    """The token of an 'Authorization: Bearer <token>' header, else None."""
    if not authorization:
        return None
    scheme, _, value = authorization.partition(" ")
    return value.strip() if scheme.lower() == "bearer" and value.strip() else None


def open_url(host: str, port: int, token: str) -> str:
    """The ready-to-open URL printed at start-up."""
    shown_host = "127.0.0.1" if host in ("0.0.0.0", "::", "") else host
    return f"http://{shown_host}:{port}/?token={token}"
