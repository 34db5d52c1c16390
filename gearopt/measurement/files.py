"""The measured-deviation file the closed loop reads (``gearopt correct --measured``).

CSV, a header line ``flank,i_face,i_profile,deviation_um`` and one row per measured point of
the nominal grid (``gearopt grid``): the flank, the point's indices toe to heel and root to top,
and its normal deviation in um, + = material above nominal (along the outward normal). A point
left out was not measured.
"""

from __future__ import annotations

import csv
import math
from pathlib import Path

import numpy as np

from gearopt.errors import GearoptError
from gearopt.flank import FLANKS

__all__ = ["MEASURED_HEADER", "read_measured"]

MEASURED_HEADER = "flank,i_face,i_profile,deviation_um"


def read_measured(path: str | Path, shape: tuple[int, int]) -> dict[str, np.ndarray]:
    """``{flank: (n_face, n_profile)}`` deviations (um) from a measured-deviation CSV file
    (module docstring); NaN where a point is not given. Errors name the file, line and rule."""
    out = {f: np.full(shape, np.nan) for f in FLANKS}
    try:
        text = Path(path).read_text(encoding="utf-8-sig")
    except (OSError, UnicodeDecodeError) as exc:
        raise GearoptError("--measured", str(path), f"cannot be read ({exc})") from None
    reader = csv.reader(text.splitlines())
    header = next(reader, None)
    if header is None or ",".join(h.strip() for h in header) != MEASURED_HEADER:
        raise GearoptError("--measured", str(path), f"must start with the line {MEASURED_HEADER}")
    seen = set()
    for number, row in enumerate(reader, start=2):
        where = f"--measured {Path(path).name} line {number}"
        if not row or all(not c.strip() for c in row):
            continue
        if len(row) != 4:
            raise GearoptError(where, ",".join(row), "needs 4 fields: " + MEASURED_HEADER)
        flank = row[0].strip()
        if flank not in FLANKS:
            raise GearoptError(where, flank, f"flank must be one of {FLANKS}")
        try:
            i, j, value = int(row[1]), int(row[2]), float(row[3])
        except ValueError:
            raise GearoptError(where, ",".join(row), "needs integer indices and a number") from None
        if not (0 <= i < shape[0] and 0 <= j < shape[1]):
            raise GearoptError(
                where, (i, j), f"is outside the {shape[0]}x{shape[1]} grid (see --points)"
            )
        if not math.isfinite(value) or abs(value) > 1e4:
            raise GearoptError(where, value, "deviation_um must be finite, within +/- 10 mm")
        if (flank, i, j) in seen:
            raise GearoptError(where, (flank, i, j), "is given twice")
        seen.add((flank, i, j))
        out[flank][i, j] = value
    given = {f: v for f, v in out.items() if np.isfinite(v).any()}
    if not given:
        raise GearoptError("--measured", str(path), "holds no measured point")
    return given
