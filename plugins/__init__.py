"""gearopt's built-in plugins, installed as ``gearopt_plugins``.

Each module is a plugin written exactly as a third party would write one, registered through the
entry-point group ``gearopt`` in ``pyproject.toml``.
"""
