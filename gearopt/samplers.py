"""The study file's Optuna sampler, seeded per worker and per run."""

from __future__ import annotations

import numpy as np
import optuna
from optuna.trial import TrialState

from gearopt.studyfile import StudySpec

__all__ = ["FixedSpaceTPE", "sampler_for", "search_space"]


def sampler_for(spec: StudySpec, stream: int = 0, previous: int = 0) -> optuna.samplers.BaseSampler:
    """The study file's sampler.

    Parameters
    ----------
    spec
        The study file.
    stream
        A worker's number: offsets the seed, so that workers sampling side by side do not
        suggest the same designs.
    previous
        The trials the study held when the run opened it (given designs waiting excluded):
        mixed into the seed, so that a continued study does not draw its earlier runs' designs
        again. A fresh study's seed is the study file's plus the stream.

    Returns
    -------
    optuna.samplers.BaseSampler
        Unseeded when the study file gives no seed.
    """
    seed = None if spec.seed is None else (spec.seed + stream) % 2**32
    if seed is not None and previous:
        seed = int(np.random.SeedSequence([spec.seed, previous, stream]).generate_state(1)[0])
    if spec.sampler == "tpe":
        return FixedSpaceTPE(
            search_space=search_space(spec), seed=seed, multivariate=True, constant_liar=True
        )
    if spec.sampler == "random":
        return optuna.samplers.RandomSampler(seed=seed)
    if spec.sampler == "nsga2":
        return optuna.samplers.NSGAIISampler(seed=seed)
    return optuna.samplers.QMCSampler(seed=seed)


def search_space(spec: StudySpec) -> dict[str, optuna.distributions.BaseDistribution]:
    """The study's searched keys as the Optuna distributions their trials suggest, sorted by
    key (as Optuna's intersection search space lists them)."""
    space: dict[str, optuna.distributions.BaseDistribution] = {}
    for d in spec.search:
        if d.choices:
            space[d.key] = optuna.distributions.CategoricalDistribution(list(d.choices))
        else:
            space[d.key] = optuna.distributions.FloatDistribution(d.low, d.high, log=d.log)
    return dict(sorted(space.items()))


class FixedSpaceTPE(optuna.samplers.TPESampler):
    """Optuna's TPE on the study file's search space, known beforehand, rather than inferred
    at every ask (the intersection of the finished trials' parameters: one more read of the
    storage per trial, which re-reads every trial another worker is running, for the same
    answer once a trial is finished). Until then the relative search space is empty, as
    Optuna's intersection is, so a seed gives the designs Optuna's own TPE gives."""

    def __init__(self, *, search_space: dict, **options) -> None:
        super().__init__(**options)
        self.space = {k: v for k, v in search_space.items() if not v.single()}
        self.finished = False

    def infer_relative_search_space(self, study, trial) -> dict:
        if not self.finished:
            states = (TrialState.COMPLETE, TrialState.PRUNED)
            self.finished = bool(study.get_trials(deepcopy=False, states=states))
            if not self.finished:
                return {}
        return dict(self.space)
