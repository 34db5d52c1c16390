"""Closed loop: the machine settings that cut a measured flank topography, and the corrective
settings for the next cut.

Identification. The measured deviations m (um, on the nominal grid, both flanks of a member) are
modelled as the deviation of the nominal design with its correction settings p (offered by the
machine model, :meth:`gearopt.machine.BaseMachineModel.correction_settings`) changed by dp, plus
a rotation phi_f of each flank about the member axis (the tooth's angular position: spacing and
thickness, fitted, never removed):

    m ~ D(p0 + dp) + sum_f phi_f T_f,

D from regenerating the flanks (:class:`gearopt.measurement.topography.NominalMeasurement`),
T_f the deviation of flank f turned by one degree. The sensitivities J = dD/dp are central
differences of the generator. The columns scaled to unit norm, the rotations projected out, a
QR factorisation with column pivoting orders the settings by what the grid can see; those whose
pivot falls below 1/``condition_limit`` of the first cannot be told apart from the ones before
them: they stay at their nominal values and the report names the kept settings that mimic each
of them. The kept settings and the rotations are then found by bounded linear least squares
(scipy's ``lsq_linear``), iterated with regenerated flanks (Gauss-Newton with a fixed Jacobian)
until the model moves by less than 1e-4 um. Their standard uncertainties are
sqrt(diag(sigma^2 (J^T J)^-1)) with sigma^2 the residual's sum of squares over the degrees of
freedom. What no setting explains stays in the residual.

Correction. A machine repeats its setting errors e (the identified values minus the nominal
ones); the next cut with the settings dialled at p0 + dc comes out at p0 + e + dc. The
corrective dc over the correctable settings (the machine's, not the blade's) minimises the
predicted deviation D(p0 + e + dc) in the linear model; the prediction is then verified by
regenerating that gear, and reported with the measured residual added (what no setting can
remove).
"""

from __future__ import annotations

import warnings
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field

import numpy as np
import scipy.linalg
from numpy.typing import NDArray
from scipy.optimize import lsq_linear

from gearopt.design import Design
from gearopt.design_files import with_overrides
from gearopt.errors import GearoptError, GearoptWarning
from gearopt.flank import FLANKS
from gearopt.machine import CorrectionSetting
from gearopt.measurement.topography import NominalMeasurement, split_deviation
from gearopt.plugins import get_machine_model

__all__ = ["Correction", "Identification", "correct", "identify", "design_with"]


@dataclass(frozen=True, kw_only=True)
class Identification:
    """The settings identified from a measured topography (module docstring).

    Attributes
    ----------
    nominal
        The nominal measurement.
    settings
        The candidate settings, in the machine model's order.
    kept
        Keys of the settings identified (the rest stay nominal).
    aliases
        ``{dropped key: {kept key: ratio}}``: a change of the dropped setting by 1 is mimicked
        by the kept ones changed by ``ratio`` (the largest few), with ``"_alias"`` the share of
        the dropped setting's deviation that they reproduce (1: indistinguishable).
    values, sigma
        ``{key: identified value}`` and ``{key: standard uncertainty}`` of the kept settings.
    rotation_deg, rotation_sigma_deg
        ``{flank: rotation about the member axis}`` and its uncertainty.
    measured_um, modelled_um, valid
        ``{flank: (n_face, n_profile)}`` the measurement, the identified model's deviation and
        where both exist.
    condition_number, condition_number_all
        Of the scaled Jacobian of the kept settings and rotations, and of all candidates.
    iterations
        Regenerations after the first linear solve.
    """

    nominal: NominalMeasurement
    settings: tuple[CorrectionSetting, ...]
    kept: tuple[str, ...]
    aliases: Mapping[str, Mapping[str, float]]
    values: Mapping[str, float]
    sigma: Mapping[str, float]
    rotation_deg: Mapping[str, float]
    rotation_sigma_deg: Mapping[str, float]
    measured_um: Mapping[str, NDArray] = field(repr=False)
    modelled_um: Mapping[str, NDArray] = field(repr=False)
    valid: Mapping[str, NDArray] = field(repr=False)
    condition_number: float
    condition_number_all: float
    iterations: int

    def errors(self) -> dict[str, float]:
        """``{key: identified - nominal}`` of the kept settings."""
        by_key = {s.key: s for s in self.settings}
        return {k: v - by_key[k].value for k, v in self.values.items()}

    def residual_um(self, flank: str) -> NDArray:
        """Measured minus modelled deviation of ``flank`` (0 where not valid)."""
        return np.where(self.valid[flank], self.measured_um[flank] - self.modelled_um[flank], 0.0)

    def rms_um(self, flank: str, what: str = "residual") -> float:
        """RMS over the valid points of ``"measured"``, ``"modelled"`` or ``"residual"``."""
        data = {
            "measured": self.measured_um[flank],
            "modelled": self.modelled_um[flank],
            "residual": self.residual_um(flank),
        }[what]
        ok = self.valid[flank]
        return float(np.sqrt(np.mean(data[ok] ** 2))) if ok.any() else 0.0

    def design(self) -> Design:
        """The nominal design with the identified settings: the gear as it was cut."""
        return design_with(self.nominal.design, self.settings, self.values)

    def report(self) -> dict:
        """JSON-ready summary: settings, uncertainties, aliases, RMS and the split per flank."""
        by_key = {s.key: s for s in self.settings}
        grid = self.nominal.grid
        return {
            "member": self.nominal.member,
            "settings": {
                k: {
                    "nominal": by_key[k].value,
                    "identified": self.values[k],
                    "error": self.values[k] - by_key[k].value,
                    "sigma": self.sigma[k],
                }
                for k in self.kept
            },
            "not_identifiable": {k: dict(v) for k, v in self.aliases.items()},
            "rotation_deg": dict(self.rotation_deg),
            "rotation_sigma_deg": dict(self.rotation_sigma_deg),
            "condition_number": self.condition_number,
            "condition_number_all": self.condition_number_all,
            "iterations": self.iterations,
            "flanks": {
                f: {
                    "points": int(self.valid[f].sum()),
                    "measured_rms_um": self.rms_um(f, "measured"),
                    "residual_rms_um": self.rms_um(f),
                    "measured": split_deviation(grid, self.measured_um[f], self.valid[f]),
                    "residual": split_deviation(grid, self.residual_um(f), self.valid[f]),
                }
                for f in self.measured_um
            },
        }


@dataclass(frozen=True, kw_only=True)
class Correction:
    """Corrective settings for the next cut (module docstring).

    Attributes
    ----------
    identification
        What the correction starts from.
    values
        ``{key: value to dial}`` of the correctable settings.
    predicted_um
        ``{flank: (n_face, n_profile)}`` the next cut's predicted deviation (regenerated, with
        the measured residual added).
    """

    identification: Identification
    values: Mapping[str, float]
    predicted_um: Mapping[str, NDArray] = field(repr=False)

    def design(self) -> Design:
        """The nominal design with the corrective settings (what to dial on the machine)."""
        ident = self.identification
        return design_with(ident.nominal.design, ident.settings, self.values)

    def report(self) -> dict:
        """JSON-ready summary."""
        ident = self.identification
        by_key = {s.key: s for s in ident.settings}
        flanks = {}
        for f, pred in self.predicted_um.items():
            ok = ident.valid[f]
            flanks[f] = {
                "predicted_rms_um": float(np.sqrt(np.mean(pred[ok] ** 2))) if ok.any() else 0.0,
                "predicted": split_deviation(ident.nominal.grid, pred, ok),
            }
        return {
            "settings": {
                k: {"nominal": by_key[k].value, "corrective": v, "change": v - by_key[k].value}
                for k, v in self.values.items()
            },
            "flanks": flanks,
        }


def design_with(
    design: Design, settings: Sequence[CorrectionSetting], values: Mapping[str, float]
) -> Design:
    """``design`` with the settings of ``values`` (keys of ``settings``) replaced."""
    by_key = {s.key: s for s in settings}
    overrides: dict[str, float] = {}
    for key, value in values.items():
        overrides.update(by_key[key].overrides(value))
    with warnings.catch_warnings():  # a root cut above its line is legal here
        warnings.simplefilter("ignore", GearoptWarning)
        return with_overrides(design, overrides)


def _candidates(nominal: NominalMeasurement, keys: Sequence[str] | None):
    model = get_machine_model(nominal.design.model)
    offered = model.correction_settings(nominal.design, nominal.member)
    if not offered:
        raise GearoptError(
            "--settings",
            rule=f"the {model.name!r} machine model offers no correction settings",
        )
    if keys is None:
        return offered
    by_key = {s.key: s for s in offered}
    unknown = [k for k in keys if k not in by_key]
    if unknown:
        raise GearoptError("--settings", ",".join(unknown), f"must be among {', '.join(by_key)}")
    return tuple(by_key[k] for k in keys)


def _vector(values: Mapping[str, tuple[NDArray, NDArray]], valid) -> NDArray:
    return np.concatenate([values[f][0][valid[f]] for f in valid])


def _jacobian(nominal, design, settings, values, valid) -> NDArray:
    """Central differences of the deviations on the ``valid`` points (narrowed to where every
    perturbed flank is generated) by each of ``settings`` about ``values`` in ``design``."""
    columns = []
    for s in settings:
        at = values[s.key]
        plus = nominal.deviations(design_with(design, (s,), {s.key: at + s.step}))
        minus = nominal.deviations(design_with(design, (s,), {s.key: at - s.step}))
        for f in valid:
            valid[f] &= plus[f][1] & minus[f][1]
        columns.append((plus, minus, s.step))
    return np.stack(
        [(_vector(p, valid) - _vector(m, valid)) / (2.0 * h) for p, m, h in columns], axis=1
    )


def _rotations(nominal: NominalMeasurement, valid) -> NDArray:
    out = []
    for f in valid:
        col = {g: (np.zeros(nominal.grid.shape), None) for g in valid}
        col[f] = (nominal.rotation_um_per_deg(f), None)
        out.append(_vector(col, valid))
    return np.stack(out, axis=1)


def _aliases(scaled: NDArray, norms, order, kept_n, settings) -> dict:
    kept = order[:kept_n]
    out = {}
    for j in order[kept_n:]:
        if not kept:
            out[settings[j].key] = {"_alias": 0.0}
            continue
        coef, *_ = np.linalg.lstsq(scaled[:, kept], scaled[:, j], rcond=None)
        share = 1.0 - np.linalg.norm(scaled[:, j] - scaled[:, kept] @ coef)
        top = sorted(zip(kept, coef, strict=True), key=lambda kc: -abs(kc[1]))[:3]
        out[settings[j].key] = {
            **{settings[k].key: float(c * norms[j] / norms[k]) for k, c in top},
            "_alias": float(share),
        }
    return out


def identify(
    nominal: NominalMeasurement,
    measured_um: Mapping[str, NDArray],
    *,
    settings: Sequence[str] | None = None,
    condition_limit: float = 1e3,
    max_iterations: int = 6,
) -> Identification:
    """Identify the settings that cut ``measured_um`` (module docstring).

    Parameters
    ----------
    nominal
        The nominal measurement of the member.
    measured_um
        ``{flank: (n_face, n_profile)}`` measured normal deviations on the nominal grid (um, +
        material above nominal); NaN where a point was not measured. One flank or both.
    settings
        Keys of the candidate settings (default: all the machine model offers).
    condition_limit
        Largest condition number of the identified set (scaled columns).
    max_iterations
        Regenerations after the first linear solve.
    """
    flanks = [f for f in FLANKS if f in measured_um]
    if not flanks or set(measured_um) - set(FLANKS):
        raise GearoptError("measured flanks", sorted(measured_um), f"must be among {FLANKS}")
    cands = _candidates(nominal, settings)
    measured = {f: np.asarray(measured_um[f], float) for f in flanks}
    valid = {f: nominal.points[f].generated & np.isfinite(measured[f]) for f in flanks}
    j_set = _jacobian(nominal, nominal.design, cands, {c.key: c.value for c in cands}, valid)
    j_rot = _rotations(nominal, valid)
    m_vec = np.concatenate([measured[f][valid[f]] for f in flanks])
    if m_vec.size < len(cands) + len(flanks) + 1:
        raise GearoptError(
            "measured points", m_vec.size, f"too few for {len(cands)} settings and the rotations"
        )
    norms = np.linalg.norm(j_set, axis=0)
    alive = norms > 1e-9 * max(norms.max(), 1e-300)
    scaled = j_set / np.where(alive, norms, 1.0)
    q_rot, _ = np.linalg.qr(j_rot / np.linalg.norm(j_rot, axis=0))
    perp = scaled - q_rot @ (q_rot.T @ scaled)
    _, r, order = scipy.linalg.qr(perp, pivoting=True, mode="economic")
    diag = np.abs(np.diag(r))
    kept_n = int(np.sum(diag >= diag[0] / condition_limit)) if diag.size and diag[0] > 0 else 0
    order = [int(k) for k in order]
    order = [k for k in order if alive[k]] + [k for k in order if not alive[k]]
    kept_n = min(kept_n, int(alive.sum()))
    kept = order[:kept_n]
    every = np.hstack([scaled, j_rot / np.linalg.norm(j_rot, axis=0)])
    sv_all = np.linalg.svd(every, compute_uv=False)
    cond_all = float(sv_all[0] / sv_all[-1]) if sv_all[-1] > 0 else float("inf")
    jac = np.hstack([j_set[:, kept], j_rot])
    sv = np.linalg.svd(np.hstack([scaled[:, kept], every[:, len(cands) :]]), compute_uv=False)
    lows = np.array([cands[k].low - cands[k].value for k in kept] + [-np.inf] * len(flanks))
    highs = np.array([cands[k].high - cands[k].value for k in kept] + [np.inf] * len(flanks))
    first = {f: valid[f].copy() for f in flanks}
    jac0, m0 = jac, m_vec
    rows = np.ones(m0.size, bool)
    model0 = np.zeros(m0.size)
    x = np.zeros(jac.shape[1])
    iterations = 0
    for iterations in range(max_iterations + 1):  # noqa: B007 - the count is reported
        step = lsq_linear(jac0[rows], m0[rows] - model0[rows], bounds=(lows - x, highs - x)).x
        x = x + step
        values = {cands[k].key: cands[k].value + x[i] for i, k in enumerate(kept)}
        dev = nominal.deviations(design_with(nominal.design, cands, values))
        rot = x[kept_n:]
        modelled = {
            f: dev[f][0] + rot[i] * nominal.rotation_um_per_deg(f) for i, f in enumerate(flanks)
        }
        for f in flanks:
            valid[f] &= dev[f][1]
        rows = np.concatenate([valid[f][first[f]] for f in flanks])
        new = np.concatenate([modelled[f][first[f]] for f in flanks])
        moved = float(np.max(np.abs(new - model0)[rows])) if rows.any() else 0.0
        model0 = new
        if moved < 1e-4:
            break
    jac, m_vec, model_vec = jac0[rows], m0[rows], model0[rows]
    rest = m_vec - model_vec
    dof = max(m_vec.size - jac.shape[1], 1)
    sigma2 = float(rest @ rest) / dof
    cov = sigma2 * np.linalg.pinv(jac.T @ jac)
    std = np.sqrt(np.clip(np.diag(cov), 0.0, None))
    return Identification(
        nominal=nominal,
        settings=cands,
        kept=tuple(cands[k].key for k in kept),
        aliases=_aliases(scaled, norms, order, kept_n, list(cands)),
        values=values,
        sigma={cands[k].key: float(std[i]) for i, k in enumerate(kept)},
        rotation_deg={f: float(rot[i]) for i, f in enumerate(flanks)},
        rotation_sigma_deg={f: float(std[kept_n + i]) for i, f in enumerate(flanks)},
        measured_um=measured,
        modelled_um={f: np.where(valid[f], modelled[f], 0.0) for f in flanks},
        valid=valid,
        condition_number=float(sv[0] / sv[-1]) if sv[-1] > 0 else float("inf"),
        condition_number_all=cond_all,
        iterations=iterations,
    )


def correct(identification: Identification) -> Correction:
    """Corrective settings for the next cut (module docstring)."""
    ident = identification
    nominal = ident.nominal
    by_key = {s.key: s for s in ident.settings}
    machine = [k for k in ident.kept if by_key[k].correctable]
    if not machine:
        raise GearoptError(
            "--corrective-out", rule="no machine setting was identified to correct with"
        )
    flanks = list(ident.measured_um)
    valid = {f: ident.valid[f].copy() for f in flanks}
    cut = ident.design()
    base = nominal.deviations(cut)
    chosen = [by_key[k] for k in machine]
    jac = _jacobian(nominal, cut, chosen, ident.values, valid)
    target = -np.concatenate([base[f][0][valid[f]] for f in flanks])
    lows = np.array([s.low - ident.values[s.key] for s in chosen])
    highs = np.array([s.high - ident.values[s.key] for s in chosen])
    dc = lsq_linear(jac, target, bounds=(lows, highs)).x
    values = {s.key: s.value + dc[i] for i, s in enumerate(chosen)}
    after = {**ident.values, **{s.key: ident.values[s.key] + dc[i] for i, s in enumerate(chosen)}}
    regenerated = nominal.deviations(design_with(nominal.design, ident.settings, after))
    predicted = {
        f: np.where(
            ident.valid[f] & regenerated[f][1],
            regenerated[f][0] + ident.residual_um(f),
            0.0,
        )
        for f in flanks
    }
    return Correction(identification=ident, values=values, predicted_um=predicted)
