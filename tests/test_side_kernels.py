"""The compiled gathers of a side's result (:func:`gearopt.mesh.side_kernels.carried_rows`)
against the numpy indexing they replaced in :meth:`gearopt.mesh.side.SideCycle.assemble`
(kept here as the reference), compiled and as plain Python, on random windows: the same to
the bit (gathers and one subtraction each)."""

from __future__ import annotations

import numpy as np
import pytest

from gearopt.mesh import side_kernels

VARIANTS = ["compiled", "python"]


def kernel(variant):
    k = side_kernels.carried_rows
    return getattr(k, "py_func", k) if variant == "python" else k


def reference(held, pairs, inv, phi, lag, cs, ch, ids, carrying, edge_all, toe, root):
    """The numpy of :meth:`SideCycle.assemble` before the kernel (``(n, pairs)`` arrays)."""
    rows = np.arange(len(carrying))
    position = held // pairs
    return dict(
        position=position,
        sample_row=inv[held],
        phi=phi[inv[held]],
        lag=lag[position],
        pair=ids.ravel()[held],
        contact=np.stack([cs.ravel()[held], ch.ravel()[held]], 1),
        face=cs[rows, carrying] - toe,
        profile=ch[rows, carrying] - root,
        edge=edge_all[rows, carrying],
    )


@pytest.mark.parametrize("variant", VARIANTS)
@pytest.mark.parametrize("seed", range(6))
def test_carried_rows_are_numpys_gathers(variant, seed):
    rng = np.random.default_rng(seed)
    n, pairs = int(rng.integers(5, 40)), int(rng.integers(1, 6))
    n_rows = int(rng.integers(1, n * pairs + 1))
    inv = rng.integers(0, n_rows, n * pairs).astype(np.intp)
    phi = rng.normal(size=n_rows)
    lag = rng.normal(size=n)
    lag[rng.random(n) < 0.2] = np.inf
    cs, ch = rng.normal(size=(2, n, pairs)) * 10.0
    ids = rng.integers(-3, 4, (n, pairs)).astype(float)
    edge_all = rng.random((n, pairs)) < 0.3
    carrying = rng.integers(0, pairs, n).astype(np.intp)
    held = np.sort(rng.choice(n * pairs, int(rng.integers(0, n * pairs + 1)), replace=False))
    held = held.astype(np.intp)
    toe, root = float(rng.normal() * 50.0), float(rng.normal())
    m = len(held)
    ints, floats = np.empty((2, m), np.intp), np.empty(5 * m + 2 * n)
    edge = np.empty(n, bool)
    kernel(variant)(
        held,
        pairs,
        inv,
        phi,
        lag,
        cs.ravel(),
        ch.ravel(),
        ids.ravel(),
        carrying,
        edge_all.ravel(),
        toe,
        root,
        ints,
        floats,
        edge,
    )
    want = reference(held, pairs, inv, phi, lag, cs, ch, ids, carrying, edge_all, toe, root)
    got = dict(
        position=ints[0],
        sample_row=ints[1],
        phi=floats[:m],
        lag=floats[m : 2 * m],
        pair=floats[2 * m : 3 * m],
        contact=floats[3 * m : 5 * m].reshape(m, 2),
        face=floats[5 * m : 5 * m + n],
        profile=floats[5 * m + n :],
        edge=edge,
    )
    for name, value in want.items():
        assert got[name].dtype == value.dtype, name
        np.testing.assert_array_equal(got[name], value, err_msg=name, strict=True)
