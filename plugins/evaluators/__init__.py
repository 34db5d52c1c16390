"""The built-in evaluators, one plugin module each: :mod:`.tca` (unloaded TCA and ease-off),
:mod:`.ltca` (loaded TCA), :mod:`.backlash`. Each is registered through its own entry point of
the group ``gearopt`` (``pyproject.toml``), as a third party's evaluator would be.
"""
