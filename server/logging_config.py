"""uvicorn's logging with secrets redacted: the control token never reaches a log line.

Access lines carry the request's query string (`GET /?token=…`, `"WebSocket /ws?token=…" [accepted]`);
the RedactSecrets filter, attached to every handler, rewrites `token=<value>` in a record's message
and arguments to `token=[redacted]` before any formatter sees it.
"""

from __future__ import annotations

import copy
import logging
import re

SECRET_QUERY = re.compile(r"(?i)(?<=[?&;])(token|access_token)=[^&;#\s\"']*")
REDACTED = "[redacted]"


def redact(text: str) -> str:
    """`text` with the value of every token=… query parameter replaced by [redacted]."""
    return SECRET_QUERY.sub(lambda match: f"{match.group(1)}={REDACTED}", text)


class RedactSecrets(logging.Filter):
    """Rewrites token query values in a record's message and its string arguments (kept as a tuple:
    uvicorn's AccessFormatter unpacks them)."""

    def filter(self, record: logging.LogRecord) -> bool:
        if isinstance(record.msg, str):
            record.msg = redact(record.msg)
        if isinstance(record.args, tuple):
            record.args = tuple(redact(arg) if isinstance(arg, str) else arg for arg in record.args)
        elif isinstance(record.args, dict):
            record.args = {key: redact(value) if isinstance(value, str) else value for key, value in record.args.items()}
        color_message = record.__dict__.get("color_message")
        if isinstance(color_message, str):
            record.color_message = redact(color_message)
        return True


def log_config() -> dict:
    """uvicorn's default LOGGING_CONFIG with RedactSecrets on every handler (pass as uvicorn.run(log_config=…))."""
    from uvicorn.config import LOGGING_CONFIG

    config = copy.deepcopy(LOGGING_CONFIG)
    config.setdefault("filters", {})["redact_secrets"] = {"()": RedactSecrets}
    for handler in config["handlers"].values():
        handler["filters"] = [*handler.get("filters", []), "redact_secrets"]
    return config
