"""The rocking block (Housner 1963, "The behavior of inverted pendulum structures during earthquakes", BSSA 53(2),
403-417; issue 21, item 4), models/rocking_block.yaml, against closed forms and an independent quadrature.

A rectangular block, half-width b, half-height h (R = sqrt(b^2 + h^2), alpha = atan(b/h), I_O = 4 m R^2 / 3 about
a bottom corner), rocks on its two bottom corners, unilateral contacts that stick and do not bounce. About one
corner, at tilt th in [0, alpha),

    I_O th'' = -m g R sin(alpha - th)                                          

and energy gives th'(th)^2 = k (cos(alpha - th) - cos(alpha - A)), k = 2 m g R / I_O, for the amplitude A (the
centre's height is R cos(alpha - th)). The time from the amplitude to level (a quarter of the free-rocking period
T(A) at that amplitude) is

    T(A) / 4 = int_0^A dth / sqrt(k (cos(alpha - th) - cos(alpha - A))).

Its integrand is infinite at th = A (as 1 / sqrt(A - th)); with th = A - s^2 and cos x - cos y =
2 sin((y + x) / 2) sin((y - x) / 2) it becomes the smooth

    T(A) / 4 = int_0^sqrt(A) 2 s ds / sqrt(2 k sin(alpha - A + s^2 / 2) sin(s^2 / 2)),

which scipy.integrate.quad takes to round-off (the difference of cosines is never formed: no cancellation near
s = 0). At the level pose the other corner strikes; keeping the angular momentum about it (the striking corner's
impulse has no moment there, the lifting one none at all) gives Housner's ratio th'+ = r th'-,
r = 1 - (3/2) sin^2 alpha: about the striking corner O', before the impact H = I_G w + m r_O'G x (w x r_OG) =
w m R^2 (1/3 + cos 2 alpha) (r_O'G and r_OG, both of length R, are 2 alpha apart), after it I_O w+ = (4/3) m R^2 w+,
so r = (1 + 3 cos 2 alpha) / 4 = 1 - (3/2) sin^2 alpha. So the block is released at th0 and strikes first at T(th0)/4; after impact n it
leaves at r^n th'_1 (th'_1 from energy at th0), rises to the amplitude A_n of that energy and strikes again
2 T(A_n)/4 later. The half-cycles shrink geometrically (A_n ~ r^(2n), T ~ sqrt(A)), so the impacts accumulate at
a finite time, where the block rests on both corners.
"""

from __future__ import annotations

import numpy as np
import pytest

import andyc
from tests.support.references import G, M, RATIO, TH0, impact_times, quarter_period


@pytest.fixture(scope="module")
def rocking(compiled):
    model = compiled("rocking_block")
    run = andyc.simulate(model, 5.0, dt=1e-3, method="projection", frames=["left_corner", "right_corner"],
                         progress=False)
    return model, run


def test_the_impact_ratio_is_housners(rocking):
    _, run = rocking
    assert run.finished
    names = run.event_names()
    # the corners strike in turn: right first (the block starts on its left corner)
    assert names[:4] == ["right_impact", "left_impact", "right_impact", "left_impact"]
    before, after = run.events["state_before"][:-1, 5], run.events["state_after"][:-1, 5]     # th_dot
    assert len(before) > 40
    assert np.max(np.abs(after / before - RATIO)) < 1e-12
    # each impact moves the pivot: the corner that strikes closes sticking, the other lifts off (modes: left, right)
    assert [run.event_modes(k) for k in range(4)] == [[0, 1], [1, 0], [0, 1], [1, 0]]


def test_the_free_rocking_period_matches_the_quadrature(rocking):
    _, run = rocking
    times = impact_times(16)
    # release to the first strike: a quarter of the free-rocking period at th0; then half-periods at each amplitude
    assert abs(run.events["time"][0] - times[0]) < 1e-8
    assert abs(4 * run.events["time"][0] - 4 * quarter_period(TH0)) < 1e-8       # the full cycle at th0
    assert np.max(np.abs(run.events["time"][:16] - times)) < 1e-8


def test_no_corner_pulls_or_sinks_and_the_block_comes_to_rest(rocking):
    model, run = rocking
    p = model.parameters(None)
    u, d = model.input_defaults, model.initial_discrete(p)
    events = zip(run.events["time"][:-1], run.events["state_before"][:-1], run.events["state_after"][:-1])
    for t, before, after in events:
        # the impulses at the corners, from M (v+ - v-) = A^T Lam (normal and tangential rows): no corner pulls
        Mass = model.module.mass_matrix(t, before, u, p, d)
        phi, c, A, kappa = np.empty(model.nh), np.empty(model.nc), np.empty((model.nc, model.nv)), np.empty(model.nc)
        model.module.constraints(t, before, u, p, d, phi, c, A, kappa)
        impulse = np.linalg.lstsq(A.T, Mass @ (after[3:] - before[3:]), rcond=None)[0]
        normal = impulse[list(model.contact_rows)]
        assert np.all(normal >= -1e-12 * max(1.0, np.max(np.abs(normal))))
    # the last impact, at the accumulation point, sets both corners at rest: a change the size of the speed
    # the remaining (infinitely many) impacts would have taken away
    assert np.max(np.abs(run.events["state_after"][-1, 3:] - run.events["state_before"][-1, 3:])) < 1e-6
    for corner in ("left_corner", "right_corner"):
        assert np.min(run.frames[corner][:, 1]) > -1e-12
    # the impacts accumulate where the series of half-periods ends; from there it rests on both corners
    t_inf = impact_times(400)[-1]
    assert 0 <= t_inf - run.events["time"][-1] < 1e-6
    resting = run.time > t_inf
    assert np.all(run.contact_modes[resting] == 1)       # both corners closed, sticking
    assert np.max(np.abs(run.column("th")[resting])) < 1e-12
    assert np.allclose(run.normal_forces[resting], M * G / 2, rtol=0, atol=1e-9)


def test_dop853_locates_the_short_rocks_too(rocking):
    # SciPy's adaptive steps grow past the late half-cycles as the compiled rk4 steps do: a corner lifted by the
    # other's impact starts on its open side there as well (andyc.runtime.contacts.open_side)
    model, _ = rocking
    run = andyc.simulate(model, 5.0, dt=1e-2, method="DOP853", rtol=1e-12, atol=1e-12, progress=False)
    assert run.finished
    assert np.max(np.abs(run.events["time"][:16] - impact_times(16))) < 1e-8
    assert 0 <= impact_times(400)[-1] - run.events["time"][-1] < 1e-6
    assert list(run.contact_modes[-1]) == [1, 1] and abs(run.column("th")[-1]) < 1e-12
