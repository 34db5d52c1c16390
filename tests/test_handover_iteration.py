"""The hand-over's iteration on the bracket (:meth:`gearopt.mesh.handover.HandOver.take_iteration`)
driven by lag curves known in closed form, as the mesh cycle drives it (the lags asked for by
:attr:`~gearopt.mesh.handover.HandOver.asked`, one step at a time): the hand-over it settles
lies in a bracket narrower than :data:`~gearopt.mesh.handover.TOLERANCE_RAD` around the
curves' crossing, and the lag there is the greater of the lower lags at the bracket's ends.

The cases: two smooth lags (a crossing of continuous curves), a leaving lag with a kink at the
crossing's side (edge contact), a leaving lag that steps across the incoming one (its least
clearance jumping to another part of the flank: only D's sign tells the root), the same with
the incoming lag stepping, and a leaving pair off the flanks (+inf) before the step.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from gearopt.mesh import handover_kernels
from gearopt.mesh.handover import ITERATIONS, TOLERANCE_RAD, HandOver

PITCH = 2.0 * math.pi / 16.0
STEP = PITCH / 10.0
LO, HI = 0.2, 0.2 + STEP


def incoming(x):
    """A smooth incoming lag (rad), of the pair a pitch behind."""
    return 6.45e-3 - 4.6e-4 * (x - 0.21) + 3e-3 * (x - 0.21) ** 2


CASES = {
    # name: (leaving lag, the crossing, the lag there)
    "smooth": (lambda x: incoming(x) + 2e-4 * (x - 0.2137) + 5e-3 * (x - 0.2137) ** 2, 0.2137),
    "kink": (lambda x: incoming(x) + np.where(x < 0.2161, 3e-5, 4e-4) * (x - 0.2161), 0.2161),
    "leaving_steps": (
        lambda x: incoming(x) + np.where(x < 0.21630781, -1.5e-6, 2.3e-6),
        0.21630781,
    ),
    "off_flanks": (lambda x: np.where(x < 0.2088, incoming(x) - 2e-6, np.inf), 0.2088),
}


def settle(leaving, incoming_lag):
    """The iteration from the secant guess, as the mesh cycle runs it: ``(ho, rounds)``."""
    d_lo = float(leaving(LO) - incoming_lag(LO))
    d_hi = float(leaving(HI) - incoming_lag(HI))
    ends = [((0.0, 0.0), (0.0, 0.0))] * 2
    ho = HandOver(LO, HI, d_lo, d_hi, ends, STEP)
    rows = ho.iteration_rows(ho.x0, PITCH)
    rounds = 0
    while True:
        rounds += 1
        got = {}
        for v, tag in rows:
            lag = leaving if tag[1] == 0 else (lambda u: incoming_lag(u + PITCH))
            got[tag] = float(lag(v))
        xs = ho.take_iteration(got)
        if xs is None:
            return ho, rounds
        rows = ho.iteration_rows(xs, PITCH)


@pytest.mark.parametrize("name", sorted(CASES))
def test_iteration_brackets_the_crossing(name):
    leaving, root = CASES[name]
    ho, rounds = settle(leaving, incoming)
    a, b = ho.bracket[:2]
    assert ho.done and rounds < ITERATIONS
    assert b - a <= TOLERANCE_RAD
    assert a <= root <= b or abs(ho.x - root) <= TOLERANCE_RAD
    # the lag: the greater of the lower lags at the ends, sampled (not the interpolated one)
    low = [min(float(leaving(x)), incoming(x)) for x in (a, b)]
    assert ho.lag == pytest.approx(max(low), abs=1e-13)


def test_incoming_step():
    """The incoming lag steps, the leaving one is smooth: the same bracket on the step."""
    root = 0.2149

    def stepping(x):
        return incoming(x) + np.where(x < root, 1.8e-6, -2.1e-6)

    ho, _ = settle(incoming, stepping)
    a, b = ho.bracket[:2]
    assert b - a <= TOLERANCE_RAD and a <= root <= b
    low = [min(incoming(x), float(stepping(x))) for x in (a, b)]
    assert ho.lag == pytest.approx(max(low), abs=1e-13)


@pytest.mark.skipif(not handover_kernels.ENABLED, reason="the kernels run as plain Python")
@pytest.mark.parametrize("name", sorted(CASES))
def test_the_compiled_step_is_the_python_step(name, monkeypatch):
    """The compiled step (:func:`gearopt.mesh.handover_kernels.iteration_step`) settles every
    case where its plain Python does, to the bit."""
    leaving, _ = CASES[name]
    compiled_ho, compiled_rounds = settle(leaving, incoming)
    monkeypatch.setattr(handover_kernels, "iteration_step", handover_kernels.iteration_step.py_func)
    python_ho, python_rounds = settle(leaving, incoming)
    assert compiled_rounds == python_rounds
    assert (compiled_ho.x, compiled_ho.lag) == (python_ho.x, python_ho.lag)
    assert compiled_ho.bracket == python_ho.bracket
