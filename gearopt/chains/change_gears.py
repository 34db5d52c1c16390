"""Change gears: the quadrant's meshing rule and the selection of quadrants for a ratio.

A quadrant ``a/b x c/d`` (ratio ``a c / (b d)``, ``a`` meshing ``b``, ``b`` and ``c`` on one
stud, ``c`` meshing ``d``) takes its gears from the machine's change-gear set
(:class:`~gearopt.chains.model.ChangeGearSet`: a multiset of tooth counts) and must mesh by the
set's rule (:func:`quadrant_ok`, :func:`check_quadrant`). :func:`select_change_gears` finds the
quadrants of the set nearest to a required ratio, exactly over the whole multiset.
"""

from __future__ import annotations

from collections.abc import Iterable, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from gearopt.chains.model import ChangeGearSet
from gearopt.chains.parsing import MAX_TEETH
from gearopt.errors import DesignError
from gearopt.validate import check_integer, check_number

__all__ = [
    "quadrant_ok",
    "check_quadrant",
    "ChangeGearChoice",
    "select_change_gears",
]


def quadrant_ok(gear_set: ChangeGearSet, a: Any, b: Any, c: Any, d: Any) -> np.ndarray:
    """Whether quadrants ``a/b x c/d`` (integer arrays) mesh by the set's rule (not the counts)."""
    a, b, c, d = (np.asarray(x, dtype=np.int64) for x in (a, b, c, d))
    clearance = gear_set.clearance_teeth
    ok = (a + b >= c + clearance) & (c + d >= b + clearance)
    if gear_set.shaft_distance_mm is not None:
        half = 0.5 * gear_set.module_mm
        first, second = (a + b) * half, (c + d) * half
        distance = gear_set.shaft_distance_mm
        ok &= (np.abs(first - second) <= distance) & (first + second >= distance)
    return ok


def _available(gear_set: ChangeGearSet, reserved: Iterable[int], where: str) -> np.ndarray:
    avail = np.zeros(MAX_TEETH + 1, dtype=np.int64)
    for teeth, count in gear_set.counts.items():
        avail[teeth] = count
    for teeth in reserved:
        teeth = check_integer(f"{where} reserved gear", teeth, ge=1, le=MAX_TEETH)
        if avail[teeth] <= 0:
            raise DesignError(
                f"{where} reserved gear", teeth, "is not in the change-gear set (or used up)"
            )
        avail[teeth] -= 1
    return avail


def _counts_ok(avail: np.ndarray, a: Any, b: Any, c: Any, d: Any) -> np.ndarray:
    """Quadrants that use no tooth count more often than ``avail`` (per count) allows."""
    ab, ac, ad, bc, bd, cd = a == b, a == c, a == d, b == c, b == d, c == d
    return (
        (1 + ab + ac + ad <= avail[a])
        & (1 + ab + bc + bd <= avail[b])
        & (1 + ac + bc + cd <= avail[c])
        & (1 + ad + bd + cd <= avail[d])
    )


def check_quadrant(
    gear_set: ChangeGearSet,
    gears: Sequence[int],
    *,
    where: str = "change gears",
    reserved: Iterable[int] = (),
) -> tuple[int, int, int, int]:
    """Check that ``(a, b, c, d)`` comes from the set and meshes by its rule; return it."""
    if not isinstance(gears, list | tuple) or len(gears) != 4:
        raise DesignError(where, gears, "must be four tooth counts a, b, c, d (a/b x c/d)")
    quad = tuple(check_integer(f"{where}[{i}]", g, ge=1, le=MAX_TEETH) for i, g in enumerate(gears))
    avail = _available(gear_set, reserved, where)
    for teeth in set(quad):
        if quad.count(teeth) > avail[teeth]:
            have = int(avail[teeth])
            raise DesignError(
                where,
                list(quad),
                f"uses {quad.count(teeth)} gear(s) of {teeth} teeth; the set has {have}",
            )
    a, b, c, d = quad
    if not bool(quadrant_ok(gear_set, a, b, c, d)):
        rule = (
            f"cannot mesh in the quadrant: needs a + b >= c + {gear_set.clearance_teeth} and "
            f"c + d >= b + {gear_set.clearance_teeth} (teeth)"
        )
        if gear_set.shaft_distance_mm is not None:
            rule += (
                f" and |(a + b) - (c + d)| m / 2 <= {gear_set.shaft_distance_mm:g} mm <= "
                "(a + b + c + d) m / 2"
            )
        raise DesignError(where, list(quad), rule)
    return quad  # type: ignore[return-value]


@dataclass(frozen=True, kw_only=True)
class ChangeGearChoice:
    """A quadrant ``a/b x c/d`` for a required ratio: ``error = ratio - required_ratio``."""

    gears: tuple[int, int, int, int]
    ratio: float
    required_ratio: float
    error: float
    error_percent: float

    def as_dict(self) -> dict[str, Any]:
        """JSON-ready dictionary."""
        return {
            "gears": list(self.gears),
            "ratio": self.ratio,
            "required_ratio": self.required_ratio,
            "error": self.error,
            "error_percent": self.error_percent,
        }


_CHUNK = 1 << 20  # candidates per block of the exact enumeration (bounds memory)
_WINDOWS = (1, 4, 16, 64)  # ratio-sorted neighbours on each side of every (a, b), first pass


def select_change_gears(
    ratio: float,
    gear_set: ChangeGearSet,
    *,
    top_k: int = 5,
    reserved: Iterable[int] = (),
) -> tuple[ChangeGearChoice, ...]:
    """The ``top_k`` quadrants ``a/b x c/d`` of the set nearest to ``ratio``, best first.

    Exact over the whole multiset (every ordered choice of four gears that the set holds and
    whose quadrant meshes by the set's rule), ranked by ``|a c / (b d) - ratio|``, ties by
    ``(a, b, c, d)``. Vectorised in two passes: all ordered pairs ``(a, b)`` and ``(c, d)``, the
    latter sorted by ratio; a first pass over a few ratio-neighbours per ``(a, b)`` bounds the
    k-th best error, a second enumerates every ``(c, d)`` within that bound (binary search) and
    keeps the best. ``reserved`` gears are taken out of the set first.

    Raises
    ------
    DesignError
        A ratio that is not a positive finite number, or a set with no quadrant that meshes.
    """
    ratio = check_number("ratio", ratio, gt=0.0)
    top_k = check_integer("top_k", top_k, ge=1, le=10_000)
    avail = _available(gear_set, reserved, "change gears")
    values = np.flatnonzero(avail)
    # every ordered pair the set holds: (x, y) with x != y, or x == y when there are two
    i, j = np.meshgrid(np.arange(values.size), np.arange(values.size), indexing="ij")
    keep = (i != j) | (avail[values][i] >= 2)
    first = values[i[keep]], values[j[keep]]
    pair_ratio = first[0] / first[1]
    order = np.argsort(pair_ratio, kind="stable")
    c_all, d_all, cd_ratio = first[0][order], first[1][order], pair_ratio[order]
    a_all, b_all, ab_ratio = first[0], first[1], pair_ratio
    target = ratio / ab_ratio

    def evaluate(ab: np.ndarray, cd: np.ndarray) -> tuple[np.ndarray, ...]:
        """The feasible quadrants among the candidates: a, b, c, d, ratio, |error|."""
        a, b, c, d = a_all[ab], b_all[ab], c_all[cd], d_all[cd]
        ok = quadrant_ok(gear_set, a, b, c, d) & _counts_ok(avail, a, b, c, d)
        a, b, c, d = a[ok], b[ok], c[ok], d[ok]
        value = (a * c) / (b * d)  # exact integer products: equal ratios are equal floats
        return a, b, c, d, value, np.abs(value - ratio)

    # pass 1: any k feasible quadrants bound the k-th best error; look for them among a few
    # ratio-neighbours of every (a, b) (more if too few mesh), the most accurate first
    pos = np.searchsorted(cd_ratio, target)
    bound = np.inf
    for window in _WINDOWS:
        cd = pos[:, None] + np.arange(-window, window)
        inside = (cd >= 0) & (cd < cd_ratio.size)
        ab = np.broadcast_to(np.arange(target.size)[:, None], cd.shape)[inside]
        cd = cd[inside]
        errors = np.abs(ab_ratio[ab] * cd_ratio[cd] - ratio)  # ranking only
        size = 64 * top_k
        near = np.argpartition(errors, size)[:size] if size < errors.size else slice(None)
        feasible = evaluate(ab[near], cd[near])[-1]
        if feasible.size < top_k and size < errors.size:
            feasible = evaluate(ab, cd)[-1]
        if feasible.size >= top_k:
            bound = np.partition(feasible, top_k - 1)[top_k - 1]
            break

    # pass 2: every (c, d) within the bound, in blocks
    if np.isfinite(bound):
        # widened by 1e-12 relative: pair ratios are rounded, the quadrants' errors are not
        low, high = (ratio - bound) / ab_ratio, (ratio + bound) / ab_ratio
        lo = np.searchsorted(cd_ratio, low * (1.0 - 1e-12), side="left")
        hi = np.searchsorted(cd_ratio, high * (1.0 + 1e-12), side="right")
    else:
        lo = np.zeros(target.size, dtype=np.int64)
        hi = np.full(target.size, cd_ratio.size, dtype=np.int64)
    counts = hi - lo
    best = (np.empty((0, 4), dtype=np.int64), np.empty(0), np.empty(0))
    start = 0
    cumulative = np.cumsum(counts)
    while start < target.size:
        base = cumulative[start - 1] if start else 0
        stop = max(int(np.searchsorted(cumulative, base + _CHUNK, side="right")), start + 1)
        rows = np.arange(start, stop)
        n = counts[rows]
        ab = np.repeat(rows, n)
        within = np.arange(ab.size) - np.repeat(np.cumsum(n) - n, n)
        cd = lo[ab] + within
        a, b, c, d, value, error = evaluate(ab, cd)
        quads = np.concatenate([best[0], np.stack([a, b, c, d], axis=1)])
        value = np.concatenate([best[1], value])
        error = np.concatenate([best[2], error])
        pick = np.lexsort((quads[:, 3], quads[:, 2], quads[:, 1], quads[:, 0], error))[:top_k]
        best = (quads[pick], value[pick], error[pick])
        start = stop
    if best[0].shape[0] == 0:
        raise DesignError(
            "change_gears.teeth",
            list(gear_set.teeth),
            f"no quadrant a/b x c/d of the set meshes (a + b >= c + {gear_set.clearance_teeth}, "
            f"c + d >= b + {gear_set.clearance_teeth}"
            + (", and the shaft distance" if gear_set.shaft_distance_mm is not None else "")
            + ")",
        )
    return tuple(
        ChangeGearChoice(
            gears=tuple(int(g) for g in quad),  # type: ignore[arg-type]
            ratio=float(value),
            required_ratio=ratio,
            error=float(value - ratio),
            error_percent=float(100.0 * (value - ratio) / ratio),
        )
        for quad, value in zip(best[0], best[1], strict=True)
    )
