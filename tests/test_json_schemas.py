"""The JSON Schemas shipped for the commands' ``--json`` output hold for their real output
(issue 25 item 4; ``analyze`` and ``study run`` are checked in test_declarations)."""

from __future__ import annotations

import json

import jsonschema
import pytest

from gearopt.cli import main
from gearopt.errors import GearoptError
from gearopt.json_schemas import SCHEMAS, json_schema

from .conftest import STUDIES


def validate(document, command: str) -> None:
    """Validate a command's ``--json`` document against its shipped schema."""
    jsonschema.validate(document, json_schema(command), cls=jsonschema.Draft202012Validator)


@pytest.mark.parametrize("command", SCHEMAS)
def test_every_shipped_schema_is_a_valid_draft_2020_12_schema(command):
    schema = json_schema(command)
    jsonschema.Draft202012Validator.check_schema(schema)
    assert schema["title"].startswith("gearopt ") and "docs/json.md" in schema["description"]


def test_an_unknown_command_has_no_schema():
    with pytest.raises(GearoptError, match="no JSON schema"):
        json_schema("chain")


@pytest.mark.parametrize(
    ("command", "args"),
    [
        ("settings", ["settings", STUDIES / "seed001_section5_3.toml"]),
        ("settings", ["settings", STUDIES / "face_milling_tapered.toml"]),
        ("blank", ["blank", STUDIES / "iso23509" / "epicycloid_19x34.toml"]),
        ("blank", ["blank", STUDIES / "iso23509" / "face_milling_14x39.toml"]),
        ("flanks", ["flanks", STUDIES / "seed001_section5_3.toml", "--grid", "9,7"]),
        ("plugins", ["plugins"]),
    ],
)
def test_the_commands_json_follows_its_schema(capsys, command, args):
    assert main([*map(str, args), "--json"]) == 0
    document = json.loads(capsys.readouterr().out)
    validate(document, command)
    # and a document that breaks it is refused (the schema is not vacuous)
    broken = [] if command != "plugins" else {"kind": "plugin"}
    with pytest.raises(jsonschema.ValidationError):
        validate(broken, command)
