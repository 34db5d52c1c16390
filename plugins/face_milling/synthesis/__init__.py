"""Face milling from the blank: the gear's settings, and the pinion by local synthesis.

Two parts, one module each: :mod:`.gear` sets the gear's cutter and machine from the blank alone;
:mod:`.pinion` solves each pinion flank's settings by local synthesis at the mean contact point,
against the gear's flank. :mod:`.targets` reads what the synthesis is asked (``[synthesis]``) and
reports how it closed. The public names of all three are importable from this package.
"""

from gearopt_plugins.face_milling.synthesis.gear import (
    STANDARD_CUTTER_RADII_IN,
    CradleCone,
    PitchLinePoint,
    default_cutter_radius_mm,
    gear_flanks_from_blank,
    gear_tool,
    pitch_line_point,
    slot_width_mm,
)
from gearopt_plugins.face_milling.synthesis.pinion import (
    default_chosen,
    pinion_start,
    synthesize_pinion_flank,
)
from gearopt_plugins.face_milling.synthesis.targets import (
    CHOSEN_KEYS,
    SIDES,
    SOLVED_KEYS,
    SYNTHESIS_KEYS,
    TARGET_KEYS,
    TOLERANCE,
    SideTargets,
    SynthesisReport,
    read_synthesis,
)

__all__ = [
    "CHOSEN_KEYS",
    "SIDES",
    "SOLVED_KEYS",
    "STANDARD_CUTTER_RADII_IN",
    "SYNTHESIS_KEYS",
    "TARGET_KEYS",
    "TOLERANCE",
    "CradleCone",
    "PitchLinePoint",
    "SideTargets",
    "SynthesisReport",
    "default_chosen",
    "default_cutter_radius_mm",
    "gear_flanks_from_blank",
    "gear_tool",
    "pinion_start",
    "pitch_line_point",
    "read_synthesis",
    "slot_width_mm",
    "synthesize_pinion_flank",
]
