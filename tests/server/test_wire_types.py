"""web/js/wire_types.js is generated from the pydantic models and must not go stale."""

from server import gen_wire_types


def test_generated_wire_types_are_current():
    current = gen_wire_types.OUTPUT.read_text()
    assert current == gen_wire_types.render(), "web/js/wire_types.js is stale: run python -m server.gen_wire_types"
    assert gen_wire_types.main(["--check"]) == 0


def test_every_model_has_a_typedef_with_its_fields():
    text = gen_wire_types.render()
    assert text.startswith("// generated, do not edit")
    for model in gen_wire_types.ALL_WIRE_MODELS:
        assert f"@typedef {{Object}} {model.__name__}\n" in text
        for field_name in model.model_fields:
            assert f"{field_name}" in text
    assert '@property {"frame"} [type]' in text or '@property {"frame"} type' in text
