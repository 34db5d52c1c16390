"""Cutter and blade descriptions that several machine models share (:mod:`.blades`)."""
