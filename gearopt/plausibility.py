"""Whether a result is a gear mesh: hard limits (errors) and what is legal but unusual (warnings).

Every ``--json`` output of ``gearopt settings``, ``flanks``, ``flank`` and ``analyze`` carries a
``warnings`` list of strings, each naming its rule; in text mode they go to stderr. Results that
are not a gear mesh are a :class:`~gearopt.errors.DesignError` (exit 2) instead:

- tool penetration of a generated flank above :data:`MAX_TOOL_PENETRATION_MM` (the envelope is
  then not what the tool cuts; the flanks promise 1e-12 mm);
- a TE peak-to-peak above :data:`MAX_TE_ARCSEC` (one degree of the gear);
- interference (negative backlash) deeper than :data:`MAX_INTERFERENCE_UM`.

Warnings: a flank generated over less than half the working depth below the pitch line (the
mating member's addendum) at the middle of the face (the mate's tip reaches flank the tool does
not generate, an undercut), edge contact,
a contact ratio below one (the contact leaves the flanks over part of the cycle), and the
numerical warnings (overflow, invalid values) raised while computing (:func:`caught`).
"""

from __future__ import annotations

import contextlib
import warnings
from collections.abc import Iterator, Mapping
from typing import Any

from gearopt.errors import DesignError, GearoptWarning

__all__ = [
    "MAX_INTERFERENCE_UM",
    "MAX_TE_ARCSEC",
    "MAX_TOOL_PENETRATION_MM",
    "MIN_WORKING_DEPTH_SHARE",
    "caught",
    "contact_findings",
    "flank_findings",
]

#: largest tool penetration of a generated flank (mm) that is still the tool's cut
MAX_TOOL_PENETRATION_MM = 1e-3
#: largest TE peak-to-peak (arcsec of the gear) of a gear mesh: one degree
MAX_TE_ARCSEC = 3600.0
#: deepest interference (um, circumferential) still read as a mesh with a tight spot
MAX_INTERFERENCE_UM = 5.0
#: the least share of the working depth below the pitch line (the mate's addendum) a flank must
#: be generated over at the middle of the face before it is worth a warning: the shipped
#: designs' pinions, cut to their envelope's fold, reach 0.69 to 0.85 of it (seed 001 Table 3
#: 0.85 on a fine grid), the seed 001 pinion with 7 teeth 0.28
MIN_WORKING_DEPTH_SHARE = 0.5


@contextlib.contextmanager
def caught() -> Iterator[list[str]]:
    """Collect the warnings raised inside the block as warning strings instead of lines on
    stderr: numpy's RuntimeWarning (overflow, invalid value, division by zero) as
    ``"numerical: ..."`` and :class:`~gearopt.errors.GearoptWarning` (a legal but unusual
    design, e.g. a root cut above its nominal line) as its message."""
    found: list[str] = []
    with warnings.catch_warnings(record=True) as records:
        warnings.simplefilter("always", RuntimeWarning)
        warnings.simplefilter("always", GearoptWarning)
        yield found
    seen = set()
    for record in records:
        if issubclass(record.category, GearoptWarning):
            text = str(record.message)
            if text not in seen:
                seen.add(text)
                found.append(text)
            continue
        if not issubclass(record.category, RuntimeWarning):
            warnings.warn_explicit(record.message, record.category, record.filename, record.lineno)
            continue
        text = f"numerical: {record.message} (in {record.filename.rsplit('/', 1)[-1]})"
        if text not in seen:
            seen.add(text)
            found.append(text)


def flank_findings(
    design, member: str, flank: str, summary: Mapping[str, Any], *, row_mm: float
) -> list[str]:
    """Warnings on one generated flank (``FlankMap.summary()`` plus ``tool_penetration_mm``;
    ``row_mm`` the grid's profile spacing: the flank may reach one row below its lowest
    generated one, so the working depth is judged at that row); a :class:`DesignError` when
    the tool penetrates it."""
    where = f"{member} {flank} flank"
    penetration = summary.get("tool_penetration_mm")
    if penetration is not None and penetration > MAX_TOOL_PENETRATION_MM:
        raise DesignError(
            f"{where}: tool penetration",
            f"{penetration:.4g} mm",
            f"must stay below {MAX_TOOL_PENETRATION_MM:g} mm (the tool cuts into the flank it "
            "generated: the settings do not generate this flank; check the cutter radii, the "
            "roll and the face width)",
        )
    index = ("pinion", "gear").index(member)
    mate_addendum_mm = design.blank.mean_addendum_mm[1 - index]
    low = summary["lowest_generated_height_mm"]["middle"]
    if row_mm - low >= MIN_WORKING_DEPTH_SHARE * mate_addendum_mm:
        return []
    mate = ("pinion", "gear")[1 - index]
    return [
        f"working depth: the {where} is generated down to h = {low:.3f} mm at the middle of "
        f"the face (to the grid's row of {row_mm:.3f} mm), less than "
        f"{MIN_WORKING_DEPTH_SHARE:g} of the working depth below the pitch line "
        f"(h = {-mate_addendum_mm:.3f} mm, the {mate}'s addendum): the mating tip reaches "
        "flank the tool does not generate (undercut)"
    ]


def contact_findings(out: Mapping[str, Any], *, strict: bool = True) -> list[str]:
    """Warnings on contact results (the reports' ``tca``, ``tca_coast``, ``backlash``, those
    present); a result that is not a gear mesh is a :class:`DesignError`, or with ``strict``
    False a warning too (a study's trial keeps its values: its constraints judge it)."""
    try:
        return _contact_findings(out)
    except DesignError as exc:
        if strict:
            raise
        return [f"not a gear mesh: {exc}"]


def _contact_findings(out: Mapping[str, Any]) -> list[str]:
    found = []
    for key in ("tca", "tca_coast"):
        if key not in out:
            continue
        side = out[key]
        te = side["te_peak_to_peak_arcsec"]
        if te > MAX_TE_ARCSEC:
            raise DesignError(
                f"{side['side']} side: TE peak-to-peak",
                f"{te:.1f} arcsec",
                f"must stay below one degree ({MAX_TE_ARCSEC:g} arcsec): not a gear mesh "
                "(check the misalignment and the settings)",
            )
        if side["contact_ratio"] < 1.0:
            found.append(
                f"contact ratio: {side['side']} side {side['contact_ratio']:.3f} < 1, the "
                "contact leaves the flanks (edge contact or none) over part of the cycle"
            )
        if side["pattern"]["edge_contact"]:
            found.append(f"edge contact: {side['side']} side, the contact reaches a flank edge")
    backlash = out.get("backlash")
    if backlash is not None and backlash["min_um"] < -MAX_INTERFERENCE_UM:
        raise DesignError(
            "backlash",
            f"{backlash['min_um']:.1f} um",
            f"interference deeper than {MAX_INTERFERENCE_UM:g} um: the teeth cut into each "
            "other, not a gear mesh (thin the teeth or correct the assembly)",
        )
    return found
