"""IFToMM A01 (docs/reference-cases.md §5): a long-horizon pendulum against its closed form.

Exact solution, with phi the angle from the downward vertical and
k = sin(phi0 / 2): sin(phi / 2) = k sn(K - w0 t, k), w0 = sqrt(g / L), where
K is the complete elliptic integral of the first kind (scipy's ellipj/ellipk
take m = k^2). Released at rest from x = -1: x = L sin(phi), y = -L cos(phi).
"""

import numpy as np
import pytest
from scipy.special import ellipj, ellipk

import andyc

G, L = 9.81, 1.0
PUBLISHED = {  # docs/reference-cases.md §5, six decimals
    0.5: (-0.391049, -0.920370),
    10.0: (-0.275087, -0.961419),
    100.0: (-0.181513, -0.983388),
    1000.0: (0.683230, -0.730203),
    2000.0: (0.814603, -0.580019),
}
DT = 1e-3  # RK4 step; measured error against the closed form at t = 2000 s: 7e-9 (8e-10 at 5e-4)


def exact_position(t):
    k = np.sin(np.pi / 4)
    m = k * k
    sn, _, _, _ = ellipj(ellipk(m) - np.sqrt(G / L) * np.asarray(t), m)
    phi = -2 * np.arcsin(k * sn)          # negative: the mass starts on the -x side
    return np.stack([L * np.sin(phi), -L * np.cos(phi)], axis=-1)


def test_closed_form_matches_published_numbers():
    """Guards the reference itself: the formula reproduces the published table and period."""
    for t, xy in PUBLISHED.items():
        assert np.allclose(exact_position(t), xy, atol=6e-7)
    period = 4 * ellipk(0.5) / np.sqrt(G / L)
    assert period == pytest.approx(2.367841947576, abs=1e-11)


@pytest.fixture(scope="module")
def run(compiled):
    model = compiled("pendulum_a01")
    every = int(round(0.5 / DT))  # log every 0.5 s: all published times are on the grid
    return andyc.simulate(model, 2000.0, dt=DT, every=every, frames=["tip"])


@pytest.mark.parametrize("t", sorted(PUBLISHED))
def test_positions_within_1e6_of_closed_form(run, t):
    assert run.finished
    i = int(np.argmin(abs(run.time - t)))
    assert run.time[i] == pytest.approx(t, abs=1e-9)
    xy = run.frames["tip"][i, :2]
    assert np.max(abs(xy - exact_position(t))) < 1e-6
    assert np.max(abs(xy - np.array(PUBLISHED[t]))) < 1e-6


def test_energy_held_over_2000_s(run):
    # E(0) = 0 (released at rest at the pivot's height); compare with m g L.
    assert np.max(abs(run.energy - run.energy[0])) < 1e-8 * G * L
