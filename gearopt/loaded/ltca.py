"""Loaded tooth contact analysis: load sharing, loaded transmission error, contact pressure.

At every mesh position of the unloaded TCA (the same positions, ``tca.phi1_deg``) the tooth pairs
that can come into contact are sampled finely around their unloaded contact points
(:mod:`gearopt.loaded.separations`): patch i has the angular clearance delta_i and the normal
factor f_i of the clearance field. With the gear turned back by theta from its ideal position,
the gap at patch i is

    g_i = delta_i f_i + sum_j C_ij F_j - theta f_i  >= 0,   F_i >= 0,   g_i F_i = 0,
    sum_i f_i F_i = T                                                  (gear torque, N mm)

with C the compliance: the bending and shear of both teeth (finite-element influence numbers of
each member's tooth, :mod:`gearopt.loaded.compliance`) plus the local contact compliance of the
two half-spaces (:mod:`gearopt.loaded.halfspace`) between patches of one pair. Teeth of different
pairs are separate bodies in the tooth models, so C couples patches of one pair only. f_i is
both the normal separation per radian of gear rotation and the moment arm of a normal force about
the gear axis, so the rigid-body approach and the torque balance share it. The complementarity
problem is solved exactly per position and torque (:mod:`gearopt.loaded.lcp`).

The loaded TE is theta as an angle of the gear on the unloaded TE's convention: LTE = (g_min -
theta) in arcsec, with g_min the unloaded TCA's reference lag, so at zero torque the LTE is the
unloaded TE at every position.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace

import numpy as np
from numpy.typing import NDArray
from scipy.spatial import ConvexHull, QhullError

from gearopt.contact import ClearanceField
from gearopt.errors import GearoptError
from gearopt.jit import blas_threads
from gearopt.load_options import PatchOptions, check_torques
from gearopt.loaded.lcp import solve_load_patches
from gearopt.loaded.patch_compliance import PatchCompliance
from gearopt.loaded.separations import PairPatches, position_patches
from gearopt.units import ARCSEC

__all__ = ["ARCSEC", "LoadedContact", "PositionLoad", "loaded_contact"]

#: extra positions per round of the LTE minimum's refinement
REFINE_POINTS = 5
#: rounds of the refinement
REFINE_ROUNDS = 2
#: a cold solve's first support: the patches whose rigid interpenetration exceeds this
#: fraction of its largest value (:func:`_solve`). Measured on the section 5.3 pair over the
#: ten torques of ``gearopt bench ltca_sweep_ms``: 8257 columns computed with 0.9, 11706 with
#: 0.5 (the Hertzian contact, were the approach all local); at 50 N m alone 831 and 676
#: (light loads: the approach is mostly local)
START_FRACTION = 0.9
#: a patch left out of a solve counts as closed where its gap's lower bound is below -this
_OPEN_MM = 1e-9


@dataclass(frozen=True, kw_only=True)
class PositionLoad:
    """The load distribution at one position and torque: patch forces of each pair in contact.

    Attributes
    ----------
    theta_rad
        The gear's loaded lag behind its ideal position.
    pairs
        The pairs' offsets (pitches from the base pair), in the order of ``forces_n``.
    forces_n, pressure_mpa
        One ``(along, across)`` array per pair.
    patches
        The pairs' patches (:class:`gearopt.loaded.separations.PairPatches`).
    """

    theta_rad: float
    pairs: tuple[int, ...]
    forces_n: tuple[NDArray, ...]
    pressure_mpa: tuple[NDArray, ...]
    patches: tuple[PairPatches, ...] = field(repr=False)


@dataclass(frozen=True, kw_only=True)
class LoadedContact:
    """Loaded TCA of one side at one torque (module docstring for the definitions).

    Attributes
    ----------
    side, torque_nm
        The side and the output torque on the gear (N m).
    phi1_deg, lte_arcsec
        ``(n,)`` the unloaded TCA's positions and the loaded TE there.
    lte_peak_to_peak_arcsec
        Maximum minus minimum of the LTE, each refined by a parabola through its neighbours.
    load_share
        ``(n, k)`` the share of the load of each pair in contact, earliest pair in its cycle
        first (zero where a pair does not carry).
    max_contact_pressure_mpa, max_line_load_n_per_mm
        The largest patch pressure and the largest load per unit length of contact line over
        the positions.
    mesh_stiffness_n_per_mm_um
        The total normal load per unit face width in contact over the normal approach (the
        loaded lag beyond the unloaded one times the normal factor at the contact), mean over
        the positions.
    edge_loading
        True where a loaded patch lies on a flank's boundary at any position.
    pattern_face_mm, pattern_profile_mm, pattern_pressure_mpa
        The centres of the loaded patches over the cycle (pattern coordinates) and their
        pressures: the loaded pattern, whose outline ``outline_mm`` is their convex hull.
    positions
        The load distribution of every position (:class:`PositionLoad`).
    """

    side: str
    torque_nm: float
    phi1_deg: NDArray
    lte_arcsec: NDArray
    lte_peak_to_peak_arcsec: float
    load_share: NDArray
    max_contact_pressure_mpa: float
    max_line_load_n_per_mm: float
    mesh_stiffness_n_per_mm_um: float
    edge_loading: bool
    pattern_face_mm: NDArray
    pattern_profile_mm: NDArray
    pattern_pressure_mpa: NDArray
    outline_mm: NDArray
    positions: tuple[PositionLoad, ...] = field(repr=False)

    def as_dict(self) -> dict:
        """JSON-ready form (the ``ltca`` entries of ``gearopt analyze --json``)."""
        return {
            "side": self.side,
            "torque_nm": self.torque_nm,
            "lte_arcsec": [float(v) for v in self.lte_arcsec],
            "lte_peak_to_peak_arcsec": self.lte_peak_to_peak_arcsec,
            "load_share": [[float(v) for v in row] for row in self.load_share],
            "max_contact_pressure_mpa": self.max_contact_pressure_mpa,
            "max_line_load_n_per_mm": self.max_line_load_n_per_mm,
            "mesh_stiffness_n_per_mm_um": self.mesh_stiffness_n_per_mm_um,
            "edge_loading": self.edge_loading,
            "pattern_outline_mm": [[float(a), float(b)] for a, b in self.outline_mm],
        }


def _peak(values: NDArray, sign: float) -> float:
    """The extreme of sampled values (max for sign +1, min for -1): each interior local
    extreme refined by the parabola through it and its neighbours, the ends as sampled (the
    cycle's samples repeat it, so an extreme at an end stands again inside, where the
    parabola refines it: ties between them decide nothing)."""
    y = sign * np.asarray(values, float)
    a, b, c = y[:-2], y[1:-1], y[2:]
    curve = a - 2.0 * b + c
    peak = (b >= a) & (b >= c) & (curve < 0.0)
    with np.errstate(divide="ignore", invalid="ignore"):
        refined = np.where(peak, b - 0.125 * (c - a) ** 2 / np.where(peak, curve, -1.0), b)
    return sign * float(max(y[0], y[-1], float(np.max(refined, initial=-np.inf))))


def _hull(points: NDArray) -> NDArray:
    """Convex hull of ``(n, 2)`` points, counter-clockwise from its lexicographically least
    vertex (scipy's Qhull); the distinct points, or the two extreme ones, where fewer than
    three or all on a line."""
    try:
        hull = points[ConvexHull(points).vertices]
    except (QhullError, ValueError):  # fewer than 3 distinct points, or collinear
        pts = np.unique(np.round(points, 9), axis=0)
        return pts if len(pts) < 3 else pts[[0, -1]]
    first = np.lexsort((hull[:, 1], hull[:, 0]))[0]
    return np.roll(hull, -first, axis=0)


@dataclass(frozen=True, kw_only=True)
class _Position:
    """One position's candidate patches and their compliance (the same for every torque)."""

    patches: tuple[PairPatches, ...]
    keep: tuple[NDArray, ...]  # flat indices of each pair's candidate patches
    separation_mm: NDArray
    lever_mm: NDArray
    area_mm2: NDArray
    compliance: PatchCompliance  # its columns kept for every torque
    strip_mm: tuple[NDArray, ...]  # each pair's strips' lengths along the contact line
    lag_rad: float  # the unloaded lag (least clearance over the pairs)
    contact_factor_mm: float  # the normal factor at the unloaded contact
    # the patches a solve considers and their column cache (:func:`_solve`), kept for the
    # next torques; shared by the copies of :func:`_periodic`
    near: list = field(default_factory=list)


def _periodic(pos: _Position, turns: int) -> _Position:
    """``pos`` seen ``turns`` pitches later: the same patches, solution and columns (the
    ``compliance`` object is shared, which marks the copies as one problem), each pair a pitch
    earlier per turn."""
    if turns == 0:
        return pos
    return replace(pos, patches=tuple(replace(p, pair=p.pair - turns) for p in pos.patches))


def _prepare_unique(
    field: ClearanceField, u, grid: PatchOptions, compliance, max_half_width_mm=None
) -> list[_Position]:
    """The positions ``u`` prepared in one batch (``max_half_width_mm``: one per position,
    default the grid's), each as it is."""
    base = np.round(-u / field.pinion.pitch_rad).astype(np.intp)
    batch = position_patches(field, u, base[:, None] + np.arange(-2, 3), grid, max_half_width_mm)
    reach_mm = grid.reach_um * 1e-3
    chosen = []
    for uj, patches in zip(u, batch, strict=True):
        if not patches:
            raise GearoptError(
                "load", math.degrees(uj), "no tooth pair touches at this position (deg)"
            )
        lag = min(p.contact_rad for p in patches)
        picked = []
        for p in patches:
            sep = (p.clearance_rad - lag) * p.factor_mm
            keep = np.flatnonzero((p.valid & (sep <= reach_mm)).ravel())
            if keep.size:
                picked.append((p, keep))
        chosen.append((lag, picked))
    blocks = compliance([picked for _, picked in chosen])
    return [
        _position(lag, picked, block) for (lag, picked), block in zip(chosen, blocks, strict=True)
    ]


def _position(lag: float, picked, compliance: PatchCompliance) -> _Position:
    """One position from its pairs' candidate patches ``(patches, keep)`` and their
    compliance."""
    kept = [p for p, _ in picked]
    keeps = [keep for _, keep in picked]
    best = min(kept, key=lambda p: p.contact_rad)
    centre = tuple(np.array(best.factor_mm.shape) // 2)
    return _Position(
        patches=tuple(kept),
        keep=tuple(keeps),
        separation_mm=np.concatenate(
            [p.clearance_rad.ravel()[k] * p.factor_mm.ravel()[k] for p, k in picked]
        ),
        lever_mm=np.concatenate([p.factor_mm.ravel()[k] for p, k in picked]),
        area_mm2=np.concatenate([p.area_mm2.ravel()[k] for p, k in picked]),
        compliance=compliance,
        strip_mm=tuple(np.sort(p.length_mm, axis=1)[:, p.length_mm.shape[1] // 2] for p in kept),
        lag_rad=lag,
        contact_factor_mm=float(best.factor_mm[centre]),
    )


class _Prepared:
    """Prepared positions, kept by their configuration: positions a whole number of pitches
    apart are one (every tooth pair meets the same flanks at the same angles), prepared once
    and handed out with the pairs renumbered (:func:`_periodic`). Each call prepares the
    configurations it does not know in one batch."""

    def __init__(self, field, grid, compliance) -> None:
        self._args = (field, grid, compliance)
        self._known: dict[int, tuple[float, _Position]] = {}  # phase -> (turns, position)

    def __call__(self, u_rad) -> list[_Position]:
        field, grid, compliance = self._args
        u = np.atleast_1d(np.asarray(u_rad, float))
        pitch = field.pinion.pitch_rad
        turns = np.round(u / pitch)
        # the position within a pitch, to 1e-9 of it
        phases = np.round((u / pitch - turns) * 1e9).astype(np.int64).tolist()
        new = {}
        for phase, uj, k in zip(phases, u.tolist(), turns.tolist(), strict=True):
            if phase not in self._known and phase not in new:
                new[phase] = (uj, k)
        if new:
            fresh = _prepare_unique(
                field, np.array([uj for uj, _ in new.values()]), grid, compliance
            )
            for (phase, (_, k)), pos in zip(new.items(), fresh, strict=True):
                self._known[phase] = (k, pos)
        out = []
        for phase, k in zip(phases, turns.tolist(), strict=True):
            k0, pos = self._known[phase]
            out.append(_periodic(pos, int(k - k0)))
        return out


def _solve(pos: _Position, torque_nm: float, start=None, theta_rad: float | None = None):
    """``(forces per pair, theta_rad)`` at one position and torque. A warm start: ``start``,
    the forces of another torque's solution at the position, or ``theta_rad``, a guess of the
    lag (a nearby position's at this torque), whose rigid interpenetration beyond
    :data:`START_FRACTION` of its largest value (each pair's), as pressure on the patches, is
    the first support: the core of the contact, which the solver grows by blocks of patches
    (a support larger than the contact would ask for the columns of patches it then drops;
    from one patch it grows in many steps).

    Only the patches near the contact enter the solve (the compliance columns cost in
    proportion to the patches they span): with a guess, those that close rigidly within
    twice the guessed approach, ``s_i <= r_i (lag + 2 (theta - lag))``, kept for the next
    torques. Those left out are proven open afterwards: their gap is at least ``s_i +
    bending_i - r_i theta`` (the contact's local compliance is positive), and where that is
    not positive they join and the solve runs again from its forces."""
    first = None if start is None else _flat(pos, start)
    if first is None and theta_rad is not None:
        reach = pos.lever_mm * theta_rad - pos.separation_mm
        ends = np.cumsum([k.size for k in pos.keep])[:-1]
        core = [np.full(r.size, START_FRACTION * r.max()) for r in np.split(reach, ends)]
        first = pos.area_mm2 * np.maximum(reach - np.maximum(np.concatenate(core), 0.0), 0.0)
        if not first.any():
            first = None
    s, r = pos.separation_mm, pos.lever_mm
    if not pos.near and theta_rad is not None and theta_rad > pos.lag_rad:
        _narrow(pos, np.flatnonzero(s <= r * _reach_rad(pos, theta_rad)))
    while True:
        rows, compliance = pos.near if pos.near else (slice(None), pos.compliance)
        solved = solve_load_patches(
            separation_mm=s[rows],
            area_mm2=pos.area_mm2[rows],
            lever_arm_mm=r[rows],
            torque_n_mm=torque_nm * 1e3,
            compliance=compliance,
            start_forces_n=None if first is None else first[rows],
        )
        forces = np.zeros(s.size)
        forces[rows] = solved.forces_n
        theta = float(solved.theta_rad)
        if not pos.near or torque_nm == 0.0:
            break
        gap = s + pos.compliance.bending_mm(forces) - r * theta
        out = np.ones(s.size, bool)
        out[rows] = False
        closed = out & (gap < -_OPEN_MM)
        if not closed.any():
            break
        _narrow(pos, np.flatnonzero(~out | closed | (s <= r * _reach_rad(pos, theta))))
        first = forces
    per_pair, at = [], 0
    for p, keep in zip(pos.patches, pos.keep, strict=True):
        f = np.zeros(p.valid.size)
        f[keep] = forces[at : at + keep.size]
        at += keep.size
        per_pair.append(f.reshape(p.valid.shape))
    return per_pair, theta


def _reach_rad(pos: _Position, theta_rad: float) -> float:
    """The lag within which a solve considers the patches: twice the approach ``theta_rad``
    makes beyond the unloaded lag (``s_i <= r_i`` times it)."""
    return pos.lag_rad + 2.0 * (theta_rad - pos.lag_rad)


def _narrow(pos: _Position, rows: NDArray) -> None:
    """Let the solves of ``pos`` consider the patches ``rows`` only (all where that is all)."""
    if rows.size == pos.separation_mm.size:
        pos.near[:] = []
    else:
        pos.near[:] = [rows, pos.compliance.subset(rows)]


def _solve_positions(prepared: list[_Position], torque_nm: float, starts=None) -> list:
    """``_solve`` at every prepared position, each configuration once (the copies of
    :func:`_periodic` share its solution): from ``starts`` (forces per position) or else each
    from the last solved one's lag."""
    known: dict[int, tuple] = {}
    out = []
    for j, pos in enumerate(prepared):
        key = id(pos.compliance)
        if key not in known:
            if starts is not None:
                known[key] = _solve(pos, torque_nm, starts[j])
            else:
                lag = out[-1][1] if out else None
                known[key] = _solve(pos, torque_nm, theta_rad=lag)
        out.append(known[key])
    return out


def _flat(pos: _Position, per_pair) -> NDArray:
    """The candidate patches' forces of one position as the solver orders them."""
    return np.concatenate([f.ravel()[keep] for f, keep in zip(per_pair, pos.keep, strict=True)])


def _truncated(pos: _Position, per_pair) -> bool:
    """Whether the load reaches the end of the potential contact zone inside the flanks."""
    pairs = zip(pos.patches, per_pair, strict=True)
    return any(bool(((f > 0.0) & p.open_end).any()) for p, f in pairs)


def loaded_contact(
    field: ClearanceField,
    tca,
    torques_nm,
    *,
    compliance,
    frame,
    grid: PatchOptions | None = None,
    side: str = "drive",
    refine_rounds: int = REFINE_ROUNDS,
) -> list[LoadedContact]:
    """Loaded TCA of one side at the unloaded TCA's positions, one result per torque.

    Parameters
    ----------
    field
        The side's clearance field.
    tca
        The side's unloaded TCA (:class:`gearopt.mesh.ToothContact`): its positions and its TE
        convention.
    torques_nm
        Output torques on the gear (N m).
    compliance
        ``compliance(positions) -> [PatchCompliance, ...]``: for each position of
        ``positions``, a list of its pairs' ``(pair_patches, keep)`` (a pair's patches and the
        flat indices of its candidates), the
        :class:`gearopt.loaded.patch_compliance.PatchCompliance` of its candidates, one group
        per pair in that order: both teeth's bending and the contact's local compliance, a
        symmetric positive definite matrix whose columns the load distribution computes as it
        needs them (those of the patches it tries only). One call for a batch of positions.
    frame
        The pattern coordinates (:class:`gearopt.mesh.ToothFrame`).
    grid
        The patch grid of the potential contact zone; where the load reaches its end inside the
        flanks, the reach is doubled (twice at most).
    refine_rounds
        Rounds of :data:`REFINE_POINTS` extra positions that refine the LTE's minimum between
        the samples (the hand-over of light loads): each narrows the bracket to 2 / (points +
        1) of its width.
    """
    # many small dense solves: BLAS threads only contend (measured 30x slower on two busy cores)
    with blas_threads(1):
        return _loaded_contact(field, tca, torques_nm, compliance, frame, grid, side, refine_rounds)


def _loaded_contact(field, tca, torques_nm, compliance, frame, grid, side, rounds):
    torques = check_torques(torques_nm)
    grid = grid or PatchOptions()
    u = np.radians(np.asarray(tca.phi1_deg, float))
    top = max(torques)
    for _ in range(3):
        prepared_at = _Prepared(field, grid, compliance)
        prepared = prepared_at(u)
        at_top = _solve_positions(prepared, top)
        if top == 0.0 or not any(
            _truncated(pos, per_pair) for pos, (per_pair, _) in zip(prepared, at_top, strict=True)
        ):
            break
        grid = replace(grid, reach_um=min(2.0 * grid.reach_um, 1000.0))
    lags = np.array([p.lag_rad for p in prepared])
    reference = lags + np.asarray(tca.te_arcsec, float) / ARCSEC
    g_min = float(np.median(reference))
    if np.ptp(reference) * ARCSEC > 1e-3:
        raise GearoptError(
            "load",
            float(np.ptp(reference) * ARCSEC),
            "the loaded contact's unloaded lags disagree with the TCA's (arcsec)",
        )
    # from the largest torque down, each solve started from the next larger torque's
    solved = {top: at_top}
    above = at_top
    for t in sorted(set(torques) - {top}, reverse=True):
        above = solved[t] = _solve_positions(prepared, t, [per_pair for per_pair, _ in above])
    results = {t: _at_torque(t, prepared, solved[t], tca, g_min, frame, side) for t in solved}
    loaded = sorted(t for t in results if t > 0.0)
    refined = _refined_minima(
        u, [results[t].lte_arcsec for t in loaded], loaded, g_min, prepared_at, rounds
    )
    lows = dict(zip(loaded, refined, strict=True))
    resolved = _resolved_pressures(field, u, [results[t] for t in loaded], grid, compliance)
    pressures = dict(zip(loaded, resolved, strict=True))
    out = []
    for t in torques:
        result = results[t]
        if t > 0.0:
            high = _peak(result.lte_arcsec, 1.0)
            result = replace(
                result,
                lte_peak_to_peak_arcsec=high - min(lows[t], float(result.lte_arcsec.min())),
                max_contact_pressure_mpa=pressures[t],
            )
        else:
            result = replace(result, lte_peak_to_peak_arcsec=float(tca.te_peak_to_peak_arcsec))
        out.append(result)
    return out


def _resolved_pressures(field, u, results, grid, compliance) -> list[float]:
    """Each result's largest contact pressure resolved across the contact: the position of
    the largest pressure on the cycle's patch grid (whose patches across the contact line are
    sized for the whole potential contact zone) evaluated again with patches fitted to the
    loaded width there (21 across 1.5 times its half-width, doubled while the load reaches
    the grid's side), so that the peak of the semi-elliptic pressure across is sampled, not
    averaged over a patch. The torques' positions are prepared in one batch per round."""
    best, pending = [], {}
    for n, result in enumerate(results):
        j = int(np.argmax([max(float(q.max()) for q in p.pressure_mpa) for p in result.positions]))
        load = result.positions[j]
        half = 0.0
        for patches, forces in zip(load.patches, load.forces_n, strict=True):
            loaded = forces > 0.0
            if loaded.any():
                edge = np.abs(patches.y_mm[loaded]) + patches.width_mm[loaded]
                half = max(half, float(np.max(edge)))
        best.append(max(float(q.max()) for q in load.pressure_mpa))
        if half > 0.0:
            pending[n] = (j, load.theta_rad, 1.5 * half)
    fine = replace(grid, across=21)
    for _ in range(3):
        if not pending:
            break
        keys = list(pending)
        prepared = _prepare_unique(
            field,
            np.array([u[pending[n][0]] for n in keys]),
            fine,
            compliance,
            np.array([pending[n][2] for n in keys]),
        )
        for n, pos in zip(keys, prepared, strict=True):
            j, theta, width = pending.pop(n)
            per_pair, _ = _solve(pos, results[n].torque_nm, theta_rad=theta)
            pairs = list(zip(pos.patches, per_pair, strict=True))
            best[n] = max(float(np.max(f / p.area_mm2)) for p, f in pairs)
            if any(
                bool(((f > 0.0) & (p.open_end | p.boundary))[:, [0, -1]].any()) for p, f in pairs
            ):
                pending[n] = (j, theta, 2.0 * width)
    return best


def _refined_minima(u, ltes, torques_nm, g_min, prepared_at, rounds) -> list[float]:
    """Each torque's LTE least value between the samples ``u`` around its sampled minimum (a
    light load's hand-over is a sharp valley that samples miss): ``rounds`` times, the LTE at
    :data:`REFINE_POINTS` positions evenly inside the bracket, the bracket then narrowed to
    the least one's neighbours. The bracket's middle is known (a sample, then the last
    round's least), the other positions of all torques are prepared in one batch per round
    (``prepared_at``, which keeps them: torques with the same bracket share them)."""
    state = []
    for lte in ltes:
        lte = np.asarray(lte, float)
        k = 1 + int(np.argmin(lte[1:-1])) if len(lte) > 2 else int(np.argmin(lte))  # (see _peak)
        near = [max(k - 1, 0), k, min(k + 1, len(u) - 1)]
        state.append([u[near], lte[near], float(lte[k])])  # the bracket, the LTE there, least
    middle = REFINE_POINTS // 2 if REFINE_POINTS % 2 else -1
    for _ in range(rounds):
        asks = []
        for x, values, _ in state:
            inside = np.linspace(x[0], x[-1], REFINE_POINTS + 2)[1:-1]
            order = np.argsort(x)  # the guesses' lag, interpolated from the LTE known
            guess = np.interp(inside, x[order], g_min - values[order] / ARCSEC)
            ask = np.ones(REFINE_POINTS, bool)
            if middle >= 0 and x[0] < x[1] < x[-1]:
                ask[middle] = False
            asks.append((inside, guess, ask))
        positions = iter(prepared_at(np.concatenate([i[a] for i, _, a in asks])))
        for entry, torque, (inside, guess, ask) in zip(state, torques_nm, asks, strict=True):
            x, values, best = entry
            found = np.full(REFINE_POINTS, values[1])
            for j in np.flatnonzero(ask):
                lag = _solve(next(positions), torque, theta_rad=float(guess[j]))[1]
                found[j] = (g_min - lag) * ARCSEC
            full = np.concatenate([values[:1], found, values[-1:]])
            i = int(np.argmin(found)) + 1
            entry[:] = [
                np.concatenate([x[:1], inside, x[-1:]])[i - 1 : i + 2],
                full[i - 1 : i + 2],
                min(best, float(full[i])),
            ]
    return [best for _, _, best in state]


def _figures(pos: _Position, per_pair, theta_rad: float, frame) -> dict:
    """One position's figures at one torque: pressures, load shares (the earliest pair in its
    cycle first), the largest pressure and line load, edge loading, the loaded patches'
    pattern points and the mesh stiffness (None without load or approach)."""
    out = {"pressures": [], "share": [], "p_max": 0.0, "line_max": 0.0, "edge": False}
    out.update(face=[], profile=[], pressed=[], stiffness=None)
    total = float(sum(f.sum() for f in per_pair))
    for p, f, strip in zip(pos.patches, per_pair, pos.strip_mm, strict=True):
        pressure = np.where(p.area_mm2 > 0.0, f / p.area_mm2, 0.0)
        out["pressures"].append(pressure)
        out["share"].append(float(f.sum()) / total if total > 0.0 else 0.0)
        loaded = f > 0.0
        if loaded.any():
            out["p_max"] = max(out["p_max"], float(pressure.max()))
            line = f.sum(axis=1) / strip
            out["line_max"] = max(out["line_max"], float(line.max()))
            out["edge"] = out["edge"] or bool((loaded & p.boundary).any())
            out["face"].append(p.face_mm[loaded] - frame.toe_mm)
            out["profile"].append(p.profile_mm[loaded] - frame.root_mm)
            out["pressed"].append(pressure[loaded])
    order = np.argsort([-p.pair for p in pos.patches])
    out["share"] = [out["share"][k] for k in order]
    if total > 0.0:
        approach_um = (theta_rad - pos.lag_rad) * pos.contact_factor_mm * 1e3
        loaded_face = np.concatenate(
            [p.face_mm[f > 0.0] for p, f in zip(pos.patches, per_pair, strict=True)]
        )
        width = float(np.ptp(loaded_face)) if loaded_face.size > 1 else 0.0
        if approach_um > 0.0 and width > 0.0:
            out["stiffness"] = total / width / approach_um
    return out


def _at_torque(torque_nm, prepared, solved, tca, g_min, frame, side) -> LoadedContact:
    """One torque's result from its solves at the prepared positions (each configuration's
    figures once, :func:`_figures`)."""
    theta = np.array([th for _, th in solved], float)
    known: dict[int, dict] = {}
    shares, loads, stiffness = [], [], []
    p_max = line_max = 0.0
    edge = False
    face, profile, pressed = [], [], []
    for pos, (per_pair, th) in zip(prepared, solved, strict=True):
        key = id(pos.compliance)
        if key not in known:
            known[key] = _figures(pos, per_pair, th, frame)
        fig = known[key]
        p_max, line_max = max(p_max, fig["p_max"]), max(line_max, fig["line_max"])
        edge = edge or fig["edge"]
        face += fig["face"]
        profile += fig["profile"]
        pressed += fig["pressed"]
        shares.append(fig["share"])
        if fig["stiffness"] is not None:
            stiffness.append(fig["stiffness"])
        loads.append(
            PositionLoad(
                theta_rad=float(th),
                pairs=tuple(p.pair for p in pos.patches),
                forces_n=tuple(per_pair),
                pressure_mpa=tuple(fig["pressures"]),
                patches=pos.patches,
            )
        )
    lte = (g_min - theta) * ARCSEC
    k = max(len(s) for s in shares)
    share = np.array([s + [0.0] * (k - len(s)) for s in shares])
    face_all = np.concatenate(face) if face else np.zeros(0)
    profile_all = np.concatenate(profile) if profile else np.zeros(0)
    outline = (
        _hull(np.stack([face_all, profile_all], axis=1)) if face_all.size else np.zeros((0, 2))
    )
    return LoadedContact(
        side=side,
        torque_nm=float(torque_nm),
        phi1_deg=np.asarray(tca.phi1_deg, float),
        lte_arcsec=lte,
        lte_peak_to_peak_arcsec=_peak(lte, 1.0) - _peak(lte, -1.0),
        load_share=share,
        max_contact_pressure_mpa=p_max,
        max_line_load_n_per_mm=line_max,
        mesh_stiffness_n_per_mm_um=float(np.mean(stiffness)) if stiffness else 0.0,
        edge_loading=edge,
        pattern_face_mm=face_all,
        pattern_profile_mm=profile_all,
        pattern_pressure_mpa=np.concatenate(pressed) if pressed else np.zeros(0),
        outline_mm=outline,
        positions=tuple(loads),
    )
