"""The Prony law of fem.core.viscoelastic: its recursion against direct quadrature of the
hereditary integral, its creep compliance against g * dJ = 1 and the standard linear solid's
closed forms, and its refusal of bad parameters."""
from itertools import pairwise

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.integrate import quad

from fem.core.viscoelastic import Prony, hereditary
from fem.verify.closed_forms import sls_creep, sls_relaxation
from fingertip.errors import InputError


@st.composite
def laws(draw, most=3):
    """A Prony law of 1-`most` terms: weights summing to 0.05-0.95, times 1 ms - 10 s, a decade apart
    at least (distinct retardation gaps)."""
    n = draw(st.integers(1, most))
    share = np.array(draw(st.lists(st.floats(0.05, 1.0), min_size=n, max_size=n)))
    total = draw(st.floats(0.05, 0.95))
    first = draw(st.floats(-3.0, 1.0 - (n - 1)))
    tau = 10.0 ** (first + np.arange(n) + np.array(draw(st.lists(st.floats(0.0, 0.5), min_size=n, max_size=n))))
    return Prony(tuple(total * share / share.sum()), tuple(tau))


@settings(max_examples=100, deadline=None)
@given(law=laws(), gaps=st.lists(st.floats(1e-3, 2.0), min_size=1, max_size=6), data=st.data())
def test_recursion_equals_quadrature_of_a_piecewise_linear_input(law, gaps, data):
    """y(t_k) = g_inf x(t_k) + sum g_i [exp(-(t_k - t_0)/tau_i) x_0 + int exp(-(t_k - s)/tau_i) x'(s) ds]
    by adaptive quadrature over each linear piece, at every sample: within 1e-9 of max |x|."""
    t = np.r_[0.0, np.cumsum(gaps)] + data.draw(st.floats(0.0, 1.0))
    x = np.array(data.draw(st.lists(st.floats(-1.0, 1.0), min_size=len(t), max_size=len(t))))
    got = law.relax(t, x)
    slope = np.diff(x) / np.diff(t)
    for k in range(len(t)):
        want = law.g_inf * x[k]
        for g, tau in zip(law.g, law.tau_s):
            want += g * np.exp(-(t[k] - t[0]) / tau) * x[0]
            want += g * sum(slope[j] * quad(lambda s, end=t[k], tau=tau: np.exp(-(end - s) / tau), t[j], t[j + 1],
                                            epsabs=1e-13)[0] for j in range(k))
        assert abs(got[k] - want) <= 1e-9 * max(1.0, np.abs(x).max()), (k, got[k], want)


@settings(max_examples=100, deadline=None)
@given(law=laws(), t=st.floats(1e-3, 30.0))
def test_creep_compliance_inverts_the_relaxation(law, t):
    """g(t) J(0) + int_0^t g(t - s) J'(s) ds = 1 (a unit step of stress through J, then g) to 1e-9;
    J(0) = 1, J(inf) = 1 / g_inf."""
    _, j, lam = law.retardation()
    assert law.creep_compliance(0.0) == pytest.approx(1.0, abs=1e-12)
    assert law.creep_compliance(1e9) == pytest.approx(1.0 / law.g_inf, rel=1e-12)
    def slope(s):
        return float(np.sum(j / lam * np.exp(-s / lam)))

    edges = np.unique(np.clip(np.r_[0.0, np.sort(np.r_[law.tau_s, lam]), t], 0.0, t))
    integral = sum(quad(lambda s: law.relaxation(t - s) * slope(s), a, b, epsabs=1e-14, limit=200)[0]
                   for a, b in pairwise(edges))
    assert law.relaxation(t) + integral == pytest.approx(1.0, abs=1e-9)


def test_standard_linear_solid_closed_forms():
    """One term: g(t), J(t) (retardation time tau / g_inf) and the responses to a step strain and a
    step stress (the first sample a step from rest) equal the closed forms to 1e-12."""
    law = Prony(g=(0.6,), tau_s=(0.1,))
    t = np.linspace(0.0, 1.0, 11)
    np.testing.assert_allclose(law.relaxation(t), sls_relaxation(t, 0.4, 0.1), rtol=1e-12)
    np.testing.assert_allclose(law.creep_compliance(t), sls_creep(t, 0.4, 0.1), rtol=1e-12)
    np.testing.assert_allclose(law.retardation()[2], [0.25], rtol=1e-12)
    step = np.ones((len(t), 2))
    np.testing.assert_allclose(law.relax(t, 3.0 * step), 3.0 * sls_relaxation(t, 0.4, 0.1)[:, None] * step, rtol=1e-12)
    np.testing.assert_allclose(law.creep(t, step), sls_creep(t, 0.4, 0.1)[:, None] * step, rtol=1e-12)
    np.testing.assert_allclose(hereditary(t, np.zeros(len(t)), 1.0, [1.0], [0.1]), 0.0)


@pytest.mark.parametrize("g, tau, message", [
    ((0.5, 0.6), (0.1, 1.0), "sum below 1"),
    ((0.5,), (0.1, 1.0), "one weight g per relaxation time"),
    ((0.0,), (0.1,), "must be > 0"),
    ((0.2, 0.2), (0.1, 0.1), "distinct"),
    ((0.2,), (float("nan"),), "distinct and > 0 s"),
])
def test_bad_parameters_are_input_errors(g, tau, message):
    with pytest.raises(InputError, match=message):
        Prony(g, tau)
