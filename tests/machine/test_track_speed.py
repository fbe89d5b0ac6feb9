"""The temperature model of `machine track` (issue 22 section 3): the nested leave-one-cycle-out
ridge reuses one SVD per training set across the strengths instead of solving C^2 x 25
systems; its leave-one-out errors, chosen strengths, predictions and coefficients equal the
direct dual-form computation (tests/machine/ridge_reference.py) to rounding, with fewer or
more sensors than cycles and constant sensors."""

import numpy as np
import pytest

import importlib

from ridge_reference import choose_lambda, loo_errors, nested_loo, predict, ridge

tr = importlib.import_module("gagekit.machine.tracking.track")  # the module (the package exports the function)


def _case(C, S, G=6, n=10, seed=0, constant=False):
    rng = np.random.default_rng(seed)
    T = 20 + rng.normal(size=(C, S)).cumsum(axis=0)
    if constant:
        T[:, 0] = 21.5
    P = T[:, : min(S, G)] @ rng.normal(size=(min(S, G), G)) * 1e-3 + rng.normal(scale=1e-4, size=(C, G))
    m = rng.normal(size=(3 * n, G))
    resid = [(m @ P[c]).reshape(-1, 3) + rng.normal(scale=1e-4, size=(n, 3)) for c in range(C)]
    return T, P, m, resid


@pytest.mark.parametrize("C, S, constant", [(4, 2, False), (8, 3, False), (7, 12, False), (9, 4, True), (12, 1, False)])
def test_fast_ridge_equals_the_direct_computation(C, S, constant):
    T, P, m, resid = _case(C, S, constant=constant, seed=C * 31 + S)
    idx = list(range(1, C))
    np.testing.assert_allclose(tr._loo_errors(T, P, m, resid, idx), loo_errors(T, P, m, resid, idx), rtol=1e-9, atol=1e-15)
    assert tr._choose_lambda(T, P, m, resid, idx) == choose_lambda(T, P, m, resid, idx)
    for lam in (1e-3, 1.0, 1e3):
        fast, ref = tr._ridge(T, P, lam), ridge(T, P, lam)
        for a, b in zip(fast, ref):
            np.testing.assert_allclose(a, b, rtol=1e-9, atol=1e-14)
        np.testing.assert_allclose(tr._predict_groups(fast, T[0] + 0.5), predict(ref, T[0] + 0.5), rtol=1e-9, atol=1e-14)


def test_nested_leave_one_cycle_out_equals_the_direct_computation():
    C, S = 10, 3
    T, P, m, resid = _case(C, S, seed=5)

    class _Cyc:  # the fields _temperature_model reads
        temperatures = {f"temp_{k}": T[:, k] for k in range(S)}
        cycle_ids = list(range(1, C + 1))

    got = tr._temperature_model(_Cyc, list(P), [f"g{k}" for k in range(P.shape[1])], m, resid)
    want = nested_loo(T, P, m, resid)
    assert [x["lambda"] for x in got["leave_one_cycle_out"]] == [w[0] for w in want]
    np.testing.assert_allclose([x["mean"] for x in got["leave_one_cycle_out"]], [w[1] for w in want], rtol=1e-9)
