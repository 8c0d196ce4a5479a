"""Generate web/js/wire_types.js (JSDoc typedefs + constants) from the pydantic wire models.

    python -m server.gen_wire_types          # rewrite the file
    python -m server.gen_wire_types --check  # exit 1 if the file is stale (the tests do this)
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

from armlab.station.slots import EventLog
from armlab.station.states import ARM_COMMANDS, COMMANDS, State
from server.models import ERROR_CODES, WIRE_MODELS
from server.program_models import PROGRAM_WIRE_MODELS
from server.stream_models import CLIENT_MESSAGES, SERVER_MESSAGES, message_type
from server.views import LAYERS, VIEWS

OUTPUT = Path(__file__).resolve().parents[1] / "web" / "js" / "wire_types.js"
ALL_WIRE_MODELS = (*WIRE_MODELS, *PROGRAM_WIRE_MODELS)


def _js_type(schema: dict) -> str:
    """JSDoc type of a JSON-schema fragment."""
    if "$ref" in schema:
        return schema["$ref"].rsplit("/", 1)[-1]
    if "const" in schema:
        return json.dumps(schema["const"])
    if "enum" in schema:
        return "(" + "|".join(json.dumps(value) for value in schema["enum"]) + ")"
    for union in ("anyOf", "oneOf"):
        if union in schema:
            return "(" + "|".join(_js_type(option) for option in schema[union]) + ")"
    kind = schema.get("type")
    if kind in ("number", "integer"):
        return "number"
    if kind == "string":
        return "string"
    if kind == "boolean":
        return "boolean"
    if kind == "null":
        return "null"
    if kind == "array":
        return f"Array<{_js_type(schema.get('items', {}))}>"
    if kind == "object":
        return "Object<string, *>"
    return "*"


def _typedef(name: str, schema: dict) -> list[str]:
    lines = ["/**"]
    description = (schema.get("description") or "").strip().splitlines()
    lines += [f" * {line}".rstrip() for line in description]
    lines.append(f" * @typedef {{Object}} {name}")
    required = set(schema.get("required", ()))
    for field_name, field_schema in schema.get("properties", {}).items():
        js_type = _js_type(field_schema)
        label = field_name if field_name in required else f"[{field_name}]"
        note = field_schema.get("description", "")
        lines.append(f" * @property {{{js_type}}} {label}{(' ' + note) if note else ''}")
    lines.append(" */")
    return lines


def render() -> str:
    """The whole generated file's text."""
    definitions: dict[str, dict] = {}
    for model in ALL_WIRE_MODELS:
        schema = model.model_json_schema(ref_template="#/$defs/{model}")
        for name, sub in schema.pop("$defs", {}).items():
            definitions.setdefault(name, sub)
        if "$ref" in schema and "properties" not in schema:  # a recursive model (a loop's body of steps): its own definition
            schema = definitions[model.__name__]
        definitions[model.__name__] = schema
    lines = [
        "// generated, do not edit: made by `python -m server.gen_wire_types` from server/models.py and server/program_models.py.",
        "// The wire protocol between the station server and the browser (SI units; field names carry them).",
        "// Binary frames: [uint32 little-endian header length N][N bytes UTF-8 JSON FrameHeader][JPEG bytes].",
        "",
        f"export const STATES = Object.freeze({json.dumps([state.value for state in State])});",
        f"export const COMMANDS = Object.freeze({json.dumps(list(COMMANDS))});",
        f"export const ARM_COMMANDS = Object.freeze({json.dumps([c for c in COMMANDS if c in ARM_COMMANDS])});",
        f"export const VIEWS = Object.freeze({json.dumps(list(VIEWS))});",
        f"export const LAYERS = Object.freeze({json.dumps(list(LAYERS))});",
        f"export const ERROR_CODES = Object.freeze({json.dumps(list(ERROR_CODES))});",
        f"export const SERVER_MESSAGE_TYPES = Object.freeze({json.dumps([message_type(m) for m in SERVER_MESSAGES])});",
        f"export const CLIENT_MESSAGE_TYPES = Object.freeze({json.dumps([message_type(m) for m in CLIENT_MESSAGES])});",
        f"export const EVENT_KINDS = Object.freeze({json.dumps(list(EventLog.KINDS))});",
        "",
    ]
    for name in sorted(definitions):
        lines += _typedef(name, definitions[name])
        lines.append("")
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--check", action="store_true", help="exit 1 if the file is stale")
    args = parser.parse_args(argv)
    text = render()
    if args.check:
        current = OUTPUT.read_text() if OUTPUT.exists() else ""
        if current != text:
            print(f"{OUTPUT} is stale: run python -m server.gen_wire_types", file=sys.stderr)
            return 1
        return 0
    OUTPUT.write_text(text)
    print(f"wrote {OUTPUT}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
