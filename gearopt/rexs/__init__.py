"""REXS export and import of designs (issue 26 item 3): :mod:`gearopt.rexs.attributes` (what a
machine model exchanges), :mod:`gearopt.rexs.document` (the REXS model) and
:mod:`gearopt.rexs.files` (the API: :func:`~gearopt.rexs.files.export_rexs`,
:func:`~gearopt.rexs.files.load_rexs`). ``docs/rexs.md`` documents the mapping.

This package's ``__init__`` imports nothing: :mod:`gearopt.machine` imports
:mod:`gearopt.rexs.attributes`, and :mod:`gearopt.rexs.files` reads designs through the plugin
registry, which imports :mod:`gearopt.machine`.
"""
