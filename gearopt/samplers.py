"""The study file's Optuna sampler, seeded per worker and per run."""

from __future__ import annotations

import numpy as np
import optuna

from gearopt.studyfile import StudySpec

__all__ = ["sampler_for"]


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
        return optuna.samplers.TPESampler(seed=seed, multivariate=True, constant_liar=True)
    if spec.sampler == "random":
        return optuna.samplers.RandomSampler(seed=seed)
    if spec.sampler == "nsga2":
        return optuna.samplers.NSGAIISampler(seed=seed)
    return optuna.samplers.QMCSampler(seed=seed)
