"""The two backends of a build's leaves, against each other: C (the system's C compiler, andyc.codegen.c_leaves,
the default where there is one) and Numba (ANDYC_BACKEND=numba, or no compiler). The same model built both
ways gives the same mass matrix, forces, energy, constraint terms, frame poses and jump functions at random
states, and the same run, to round-off: the two are independent compilations of one cse'd body."""

import numpy as np
import pytest

import andyc
from tests.support import MODELS

# a chain, a closed loop with rows in a moving frame, a hybrid model with jumps and multipliers in guards,
# and a model whose inputs are expressions (its input callback stays Numba's in either backend)
CASES = ["double_pendulum", "swing_bar", "bouncing_ball_contact", "cart_pole"]


@pytest.fixture(scope="module")
def both(tmp_path_factory):
    """name -> (C build, Numba build) of each case, compiled once for the module."""
    root = tmp_path_factory.mktemp("backends")
    out = {}
    with pytest.MonkeyPatch.context() as mp:
        for name in CASES:
            mp.delenv("ANDYC_BACKEND", raising=False)
            c = andyc.compile_model(MODELS / f"{name}.yaml", root / "c")[0]
            mp.setenv("ANDYC_BACKEND", "numba")
            numba = andyc.compile_model(MODELS / f"{name}.yaml", root / "numba")[0]
            out[name] = (c, numba)
    return out


def _states(model, n, seed):
    rng = np.random.default_rng(seed)
    x0 = model.initial_state(model.parameter_defaults)
    return [x0 + rng.normal(scale=0.3, size=x0.shape) for _ in range(n)]


def test_the_builds_are_of_each_backend(both):
    for c, numba in both.values():
        assert c.module.EQUATIONS.C_LIBRARY is not None
        assert (c.path.parent / c.module.EQUATIONS.C_LIBRARY).is_file()
        assert not hasattr(c.module.EQUATIONS.dynamics, "cache_hits")      # a C leaf, not a Numba cfunc
        assert numba.module.EQUATIONS.C_LIBRARY is None
        assert hasattr(numba.module.EQUATIONS.dynamics, "cache_hits")


@pytest.mark.parametrize("name", CASES)
def test_leaves_agree_at_random_states(both, name):
    c, numba = both[name]
    a, b = c.module, numba.module
    p = c.parameter_defaults
    for x in _states(c, 5, seed=len(name)):
        t = 0.37
        scale = max(1.0, np.abs(b.mass_matrix(t, x)).max())
        np.testing.assert_allclose(a.mass_matrix(t, x), b.mass_matrix(t, x), rtol=0, atol=1e-13 * scale)
        G_c, G_n = a.generalized_force(t, x), b.generalized_force(t, x)
        np.testing.assert_allclose(G_c, G_n, rtol=0, atol=1e-13 * max(1.0, np.abs(G_n).max()))
        assert a.energy(t, x) == pytest.approx(b.energy(t, x), rel=1e-14, abs=1e-13)
        np.testing.assert_allclose(a.frame_poses(t, x), b.frame_poses(t, x), rtol=0, atol=1e-13)
        if c.nc:
            u, d = c.input_defaults, c.initial_discrete(p)
            out_c = [np.zeros(c.nh), np.zeros(c.nc), np.zeros((c.nc, c.nv)), np.zeros(c.nc)]
            out_n = [np.zeros(c.nh), np.zeros(c.nc), np.zeros((c.nc, c.nv)), np.zeros(c.nc)]
            a.constraints(t, x, u, p, d, *out_c)
            b.constraints(t, x, u, p, d, *out_n)
            for y, z in zip(out_c, out_n):
                np.testing.assert_allclose(y, z, rtol=0, atol=1e-12 * max(1.0, np.abs(z).max(initial=0.0)))
        for k in range(c.nj):
            assert a.guard(k, t, x) == pytest.approx(b.guard(k, t, x), rel=1e-13, abs=1e-13)
            assert a.enabled(k, t, x) == pytest.approx(b.enabled(k, t, x), rel=1e-13, abs=1e-13)


@pytest.mark.parametrize("name", CASES)
def test_runs_agree(both, name):
    c, numba = both[name]
    method = "projection" if c.nc else "rk4"
    run_c = andyc.simulate(c, 1.0, dt=1e-3, method=method, progress=False)
    run_n = andyc.simulate(numba, 1.0, dt=1e-3, method=method, progress=False)
    assert run_c.status == run_n.status
    assert run_c.time.shape == run_n.time.shape
    scale = max(1.0, np.abs(run_n.state).max())
    np.testing.assert_allclose(run_c.state, run_n.state, rtol=0, atol=1e-10 * scale)
    np.testing.assert_array_equal(run_c.flow, run_n.flow)
    for column, values in run_n.events.items():
        if np.asarray(values).dtype.kind == "f":
            np.testing.assert_allclose(run_c.events[column], values, rtol=0, atol=1e-10 * scale)
