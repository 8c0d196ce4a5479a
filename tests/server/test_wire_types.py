"""web/js/wire_types.js is generated from the pydantic models and must not go stale; each typedef carries exactly
its model's fields (checked per typedef, not anywhere in the file), and the message-type lists are the models'."""

import re

from server import gen_wire_types
from server.stream import CLIENT_MESSAGE
from server.stream_models import CLIENT_MESSAGES, SERVER_MESSAGES


def _typedefs(text: str) -> dict[str, list[str]]:
    """{typedef name: its @property names in order} of a generated file."""
    found = {}
    for block in re.findall(r"/\*\*(.*?)\*/", text, flags=re.S):
        name = re.search(r"@typedef \{Object\} (\w+)", block)
        if name is not None:
            found[name.group(1)] = re.findall(r"@property \{[^\n]*?\} \[?(\w+)\]?", block)
    return found


def _constant(text: str, name: str) -> list[str]:
    match = re.search(rf"export const {name} = Object\.freeze\((\[.*?\])\);", text)
    assert match is not None, f"{name} missing from the generated file"
    return re.findall(r'"([^"]*)"', match.group(1))


def test_generated_wire_types_are_current():
    current = gen_wire_types.OUTPUT.read_text()
    assert current == gen_wire_types.render(), "web/js/wire_types.js is stale: run python -m server.gen_wire_types"
    assert gen_wire_types.main(["--check"]) == 0


def test_every_model_has_a_typedef_with_exactly_its_fields():
    text = gen_wire_types.render()
    assert text.startswith("// generated, do not edit")
    typedefs = _typedefs(text)
    for model in gen_wire_types.ALL_WIRE_MODELS:
        assert model.__name__ in typedefs, f"no typedef {model.__name__}"
        expected = [field.alias or name for name, field in model.model_fields.items()]
        assert sorted(typedefs[model.__name__]) == sorted(expected), model.__name__
    assert '@property {"frame"} [type]' in text or '@property {"frame"} type' in text


def test_message_type_lists_are_every_message_each_side_sends():
    text = gen_wire_types.render()
    assert _constant(text, "CLIENT_MESSAGE_TYPES") == ["ack", "view", "command", "heartbeat", "jog", "jog_cartesian", "jog_stop"]
    assert _constant(text, "SERVER_MESSAGE_TYPES") == ["frame", "telemetry", "event", "calibration", "hello", "jog_reply"]
    assert _constant(text, "EVENT_KINDS") == ["general", "scene"]
    # what the server parses is exactly the client list: one model per type, each accepted
    assert len(CLIENT_MESSAGES) == 7 and len(SERVER_MESSAGES) == 6
    samples = {"ack": '{"type": "ack", "seq": 1}', "view": '{"type": "view", "view": "color", "layers": []}',
               "command": '{"type": "command", "name": "estop"}', "heartbeat": '{"type": "heartbeat"}',
               "jog": '{"type": "jog", "velocity_rad_s": [0.1, 0, 0, 0, 0], "id": 1}',
               "jog_cartesian": '{"type": "jog_cartesian", "axis": "x", "velocity_m_s": 0.05}', "jog_stop": '{"type": "jog_stop"}'}
    for kind in _constant(text, "CLIENT_MESSAGE_TYPES"):
        assert type(CLIENT_MESSAGE.validate_json(samples[kind])).__name__.lower().startswith(kind.replace("_", ""))
