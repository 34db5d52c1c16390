"""The JSON Schemas of the commands' ``--json`` output, shipped with gearopt (docs/json.md).

Tools that read ``gearopt analyze --json`` (and ``settings``, ``flanks``, ``blank``,
``plugins``, ``study run``) validate what they read against these; gearopt's tests validate
the commands' real output against them.
"""

from __future__ import annotations

import json
from importlib import resources
from typing import Any

from gearopt.errors import GearoptError

__all__ = ["SCHEMAS", "json_schema"]

#: the commands with a schema, as ``gearopt`` spells them (``study-run``: ``gearopt study run``)
SCHEMAS = ("analyze", "blank", "flanks", "plugins", "settings", "study-run")


def json_schema(command: str) -> dict[str, Any]:
    """The JSON Schema (draft 2020-12) of ``gearopt COMMAND --json``'s output."""
    if command not in SCHEMAS:
        raise GearoptError("command", command, f"has no JSON schema; known: {list(SCHEMAS)}")
    text = (resources.files("gearopt") / "schemas" / f"{command}.schema.json").read_text()
    return json.loads(text)
