"""Lumped receptor model (thesis 8.4): exact integration, SA vs RA by the damping, silence during
withdrawal, the weak spring under force drive."""
import math

import numpy as np
import pytest

from fem.receptors.dynamics import (
    LumpedReceptor,
    measure_time_course,
    phases,
    ramp_and_hold,
    silence_delay,
)
from fingertip.errors import InputError

RAMP, HOLD, RELEASE = 0.1, 1.0, 0.1


def stimulus():
    return ramp_and_hold(1.0, RAMP, HOLD, RELEASE, dt_s=1e-3)


def test_exact_against_closed_form_ramp():
    """Ramp at speed v: r = v tau (1 - exp(-t / tau)); hold: r decays as exp(-t / tau)."""
    t, x = stimulus()
    tau = 0.05
    r = LumpedReceptor(tau).respond(t, x)["extension"]
    v = 1.0 / RAMP
    ramp, hold, _, _ = phases(t, RAMP, HOLD, RELEASE)
    tr = t[ramp] - 0.1
    np.testing.assert_allclose(r[ramp], v * tau * (1 - np.exp(-tr / tau)), rtol=1e-10)
    r_end = v * tau * (1 - math.exp(-RAMP / tau))
    th = t[hold] - 0.1 - RAMP
    np.testing.assert_allclose(r[hold], r_end * np.exp(-th / tau), rtol=1e-9)


def test_rapidly_adapting_silent_in_hold_and_withdrawal():
    t, x = stimulus()
    out = LumpedReceptor(tau_s=0.01).respond(t, x)
    ramp, hold, release, after = phases(t, RAMP, HOLD, RELEASE)
    rate = out["rate"]
    assert rate[ramp].max() == pytest.approx(0.01 * 1.0 / RAMP, rel=1e-3)     # r -> tau * speed
    late_hold = hold & (t > 0.1 + RAMP + 10 * 0.01)
    assert rate[late_hold].max() < 1e-4 * rate.max()
    assert rate[release].max() == 0.0 and rate[after].max() == 0.0
    assert out["extension"][release].min() < -0.9 * 0.01 / RELEASE             # compressed, not firing


def test_slowly_adapting_sustains_the_hold_and_falls_silent_in_withdrawal():
    """tau = 5 s: the rate at the end of a 1 s hold is exp(-1/5) of the ramp peak; in withdrawal it
    falls with the skin and is zero from t0 = tau ln(1 + r_h / (v tau)) on (80 ms of the 100 ms
    withdrawal here: this model's SA is silent only in the last part of the withdrawal and after
    it, never with an off-response)."""
    t, x = stimulus()
    tau = 5.0
    out = LumpedReceptor(tau_s=tau).respond(t, x)
    ramp, hold, release, after = phases(t, RAMP, HOLD, RELEASE)
    rate = out["rate"]
    peak = rate[ramp | hold].max()
    end_hold = rate[hold][-1]
    assert end_hold / peak == pytest.approx(math.exp(-HOLD / tau), rel=2e-3)
    t0 = silence_delay(tau, end_hold, 1.0 / RELEASE)
    start = 0.1 + RAMP + HOLD
    assert 0.5 * RELEASE < t0 < RELEASE
    assert rate[release & (t > start + t0 + 1e-3)].max() == 0.0
    assert rate[release & (t < start + 0.5 * t0)].min() > 0.0
    assert rate[after].max() == 0.0
    # SA vs RA is the damping alone: the SA responds in the hold, the RA does not
    ra = LumpedReceptor(tau_s=0.01).respond(t, x)["rate"]
    assert rate[hold].min() > 0.5 * peak and ra[hold][-1] < 1e-6 * peak


def test_force_drive_weak_spring_creeps_and_compresses_the_receptor():
    """Force drive: in the hold the skin creeps towards F / k_w while the receptor relaxes; after
    release the weak spring pushes back through the dashpot: r = -k x < 0, silent."""
    t, f = ramp_and_hold(1.0, RAMP, 3.0, RELEASE, rest_s=1.0)
    k = 0.2
    model = LumpedReceptor(tau_s=0.1, k_ratio=k)
    out = model.respond(t, f, drive="force")
    ramp, hold, release, after = phases(t, RAMP, 3.0, RELEASE)
    skin, r = out["skin"], out["extension"]
    np.testing.assert_allclose(r + k * skin, f, atol=1e-12)                    # F = k_r r + k_w x
    assert skin[hold][-1] == pytest.approx(1.0 / k, rel=0.02)                  # creep to F / k_w
    assert np.all(np.diff(skin[hold]) > 0)
    assert np.all(r[after] < 0) and out["rate"][release | after].max() == 0.0
    np.testing.assert_allclose(r[after], -k * skin[after], rtol=1e-9)


def test_measure_time_course_and_bad_input():
    d = measure_time_course([0.0, 0.25, 0.5, 1.0], [0.5, 1.0], [2.0, 8.0])
    np.testing.assert_allclose(d, [0.0, 1.0, 2.0, 8.0])
    with pytest.raises(InputError):
        LumpedReceptor(tau_s=0.0)
    with pytest.raises(InputError):
        LumpedReceptor(1.0).respond([0.0, 0.0, 1.0], [0.0, 1.0, 1.0])
    with pytest.raises(InputError):
        LumpedReceptor(1.0).respond([0.0, 1.0], [0.0, 1.0], drive="velocity")
    with pytest.raises(InputError):
        ramp_and_hold(ramp_s=0.0)
