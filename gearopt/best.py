"""The best (or picked) design of a study, and its trials' constraint values.

Each COMPLETE trial's constraint values are stored once, as a list in the study file's order
under Optuna's ``constraints`` system attribute: the form ``optuna-dashboard`` reads (its trial
list and Pareto plot), and the one Optuna's own samplers' ``constraints_func`` writes; Optuna
reads it as constraints named ``"0"``, ``"1"``, ... (:attr:`FrozenTrial.constraints`), so each
sampler sees every constraint once. :func:`constraint_values` names them again.
"""

from __future__ import annotations

import math

import optuna
import tomli_w
from optuna.trial import TrialState

from gearopt.storage import storage_tag
from gearopt.studyfile import StudySpec

__all__ = ["CONSTRAINTS_KEY", "constraint_values", "feasible", "pick_best", "save_design"]

#: Optuna's system attribute of a trial's constraint values as a list
CONSTRAINTS_KEY = "constraints"


def constraint_values(spec: StudySpec, trial: optuna.trial.FrozenTrial) -> dict[str, float]:
    """A trial's constraint values by the study file's labels (stored as a list, in the
    file's order; a trial of an earlier gearopt has them under their labels)."""
    values = trial.system_attrs.get(CONSTRAINTS_KEY)
    if values is None:
        return dict(trial.constraints)
    return dict(zip((c.label for c in spec.constraints), values, strict=True))


def feasible(trial: optuna.trial.FrozenTrial) -> bool:
    """Whether every constraint of the trial is met (its value <= 0)."""
    return all(c <= 0.0 for c in trial.constraints.values())


def pick_best(study, spec: StudySpec) -> optuna.trial.FrozenTrial | None:
    """The best feasible COMPLETE trial; for several objectives the Pareto design the study's
    ``pick`` rule chooses: ``utopia`` (least distance to the front's ideal point, each
    objective scaled by its range on the front) or ``objective:<label>`` (the front's best of
    that objective). None when no feasible trial exists."""
    done = [
        t
        for t in study.get_trials(deepcopy=False, states=(TrialState.COMPLETE,))
        if feasible(t) and t.values is not None
    ]
    if not done:
        return None
    signs = [1.0 if d == "minimize" else -1.0 for d in spec.directions]
    if len(signs) == 1:
        return min(done, key=lambda t: (signs[0] * t.values[0], t.number))
    scored = [[s * v for s, v in zip(signs, t.values, strict=True)] for t in done]
    front = [
        i
        for i, a in enumerate(scored)
        if not any(all(x <= y for x, y in zip(b, a, strict=True)) and b != a for b in scored)
    ]
    if spec.pick.startswith("objective:"):
        k = spec.metric_names.index(spec.pick.removeprefix("objective:"))
        return done[min(front, key=lambda i: (scored[i][k], done[i].number))]
    lows = [min(scored[i][k] for i in front) for k in range(len(signs))]
    highs = [max(scored[i][k] for i in front) for k in range(len(signs))]

    def distance(i: int) -> float:
        return math.hypot(
            *[
                (scored[i][k] - lows[k]) / (highs[k] - lows[k]) if highs[k] > lows[k] else 0.0
                for k in range(len(signs))
            ]
        )

    return done[min(front, key=lambda i: (distance(i), done[i].number))]


def save_design(
    spec: StudySpec, trial: optuna.trial.FrozenTrial, storage: str | None = None
) -> str:
    """Write the trial's design beside the study file as ``<study name>_best.toml`` (the
    study's default storage) or ``<study name>_best_<storage>.toml`` (another storage: its
    SQLite file's stem, or a digest of its URL), so that a run on another storage never
    overwrites the default study's best design."""

    data = dict(spec.design_for(trial.params).source)
    meta = data.setdefault("meta", {})
    meta["name"] = f"{spec.name}_best"
    meta["source"] = f"study {spec.name}, trial {trial.number}"
    path = spec.folder / f"{spec.name}_best{storage_tag(spec, storage)}.toml"
    path.write_text(tomli_w.dumps(data), encoding="utf-8")
    return str(path)
