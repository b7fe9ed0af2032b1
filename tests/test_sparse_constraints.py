"""The sparse constrained solve (andyc/numerics/sparse_rows.py, chosen by andyc/symbolic/sparse_rows.py) against the
dense one (andyc/numerics/linalg.py), both from one build (andyc_numerics/model.new_model's `constrained`): the
accelerations, the multipliers and the projected states agree to rounding at random states and at singular poses
(where the dense path takes its SVD); and the IFToMM A02 N-four-bar follows its reduced exact motion."""

import dataclasses
import sys

import numpy as np
import pytest

import andyc
from andyc.runtime.compiled import work
from andyc.symbolic.sparse_rows import DENSE, SPARSE, choose, dense_operations, envelope, supports
from tests.support import ROOT

sys.path.insert(0, str(ROOT / "bench"))
from large_models import nfourbar_yaml, reduced_b0  # noqa: E402

TOL = 1e-12


def variants(model) -> dict:
    """"dense" and "sparse": the model's compiled Model with each constrained solve."""
    E, numerics = model.module.EQUATIONS, model.numerics
    return {k: numerics.model.new_model(E, numerics.stubs, k) for k in (DENSE, SPARSE)}


def evaluate(model, ref, x, e0):
    """(dx/dt, multipliers, the state projected (position, velocity, energy E(x) + e0)) of flow 0 at x, and the
    statuses. (A small e0: the energy step scales with it over 2T on the manifold, which may be small.)"""
    dyn = model.numerics.dynamics
    e0 += model.module.energy(0.0, x)
    p, u = model.parameter_defaults, model.input_defaults
    d = model.initial_discrete(p)
    w = work(model)
    xdot, lam = np.zeros(model.nx), np.zeros(model.nc)
    projected = np.concatenate([x, np.zeros(model.nw)])     # the work slots after the state (W = 0)
    status = (dyn.rhs_mode_into(ref, w.ref, 0.0, x, u, p, d, 0, xdot, 0),
              dyn.multipliers(ref, w.ref, 0.0, x, u, p, d, 0, lam),
              dyn.project(ref, w.ref, 0.0, projected, u, p, d, 0, True, e0, 0.0))
    return xdot, lam, projected, status


def assert_same(model, x, e0=0.0):
    (a, la, xa, sa), (b, lb, xb, sb) = (evaluate(model, ref, x, e0) for ref in variants(model).values())
    assert sa == sb == (0, 0, 0)
    for dense, sparse in ((a, b), (la, lb), (xa, xb)):
        assert np.abs(dense - sparse).max() <= TOL * max(1.0, np.abs(dense).max())


@pytest.fixture(scope="module")
def nfourbar(compiled, build_dir):
    path = build_dir / "nfourbar3.yaml"
    path.write_text(nfourbar_yaml(3))
    return compiled(path)


TWIN = """name: twin_fourbars
description: two separate parallelogram four-bars (their loops' rows form two blocks of the Gram matrix)
parameters: {L: 1, m: 1, g: 9.81}
gravity: [0, -g, 0]
coordinates:
  a0: {initial: pi/2, velocity: -1}
  a1: {initial: -pi/2, velocity: 1}
  a2: {initial: pi/2, velocity: -1}
  b0: {initial: pi/2, velocity: -1}
  b1: {initial: -pi/2, velocity: 1}
  b2: {initial: pi/2, velocity: -1}
frames:
  - {name: ca, parent: world, revolute: a0}
  - {name: ca_tip, parent: ca, translation: [L, 0, 0]}
  - {name: ka, parent: ca_tip, revolute: a1}
  - {name: ka_end, parent: ka, translation: [L, 0, 0]}
  - {name: ra, parent: world, translation: [L, 0, 0], revolute: a2}
  - {name: ra_tip, parent: ra, translation: [L, 0, 0]}
  - {name: cb, parent: world, translation: [3*L, 0, 0], revolute: b0}
  - {name: cb_tip, parent: cb, translation: [L, 0, 0]}
  - {name: kb, parent: cb_tip, revolute: b1}
  - {name: kb_end, parent: kb, translation: [L, 0, 0]}
  - {name: rb, parent: world, translation: [4*L, 0, 0], revolute: b2}
  - {name: rb_tip, parent: rb, translation: [L, 0, 0]}
bodies:
"""
TWIN += "".join(f"  - {{name: {f}_rod, frame: {f}, mass: m, com: [L/2, 0, 0], inertia: [0, m*L**2/12, m*L**2/12]}}\n"
                for f in ("ca", "ka", "ra", "cb", "kb", "rb"))
TWIN += """constraints:
  - {name: loop_a, holonomic: [ka_end.x - ra_tip.x, ka_end.y - ra_tip.y]}
  - {name: loop_b, holonomic: [kb_end.x - rb_tip.x, kb_end.y - rb_tip.y]}
simulate: {method: projection}
"""


def test_supports_and_envelope_follow_the_tree_and_the_loops():
    # a chain 0 <- 1 <- 2 and a root 3: row 0 on speed 2 reaches its ancestors; row 1 on 3 alone
    parent, order = [-1, 0, 1, -1], [2, 3, 1, 0]
    support = supports([{2}, {3}, {1, 3}], parent, order)
    assert support == [[2, 1, 0], [3], [3, 1, 0]]
    first, block = envelope([0, 1, 2], support)
    assert first == [0, 1, 0] and block == [0, 0, 0]            # row 2 meets both: one block
    first, block = envelope([0, 1], support)
    assert first == [0, 1] and block == [0, 1]                  # disjoint supports: two blocks


def test_the_choice_follows_the_operation_counts():
    # the N-four-bar's patterns (speeds c0, b1, c1, ..., b_N, c_N; loop k on c_{k-1}, b_k, c_k)
    for n, expected in ((1, DENSE), (3, DENSE), (5, SPARSE), (20, SPARSE)):
        nv = 2 * n + 1
        parent = [-1 if i % 2 == 0 else i - 1 for i in range(nv)]
        M = [({i + 1} if i % 2 == 0 and i + 1 < nv else {i - 1} if i % 2 else set()) for i in range(nv)]
        A = [s for k in range(1, n + 1) for s in ({2 * k - 2, 2 * k - 1, 2 * k},) * 2]
        order = [i for i in range(nv) if i % 2] + [i for i in range(nv) if i % 2 == 0]
        solve = choose(M, A, (parent, order), [list(range(2 * n))], False)
        assert solve.chosen == expected
        assert solve.operations[DENSE] == dense_operations(nv, 2 * n)
    with pytest.raises(ValueError):
        choose(M, A, None, [list(range(2 * n))], False, force=SPARSE)


def test_nfourbar_sparse_equals_dense_at_random_states(nfourbar):
    rng = np.random.default_rng(27)
    x0 = nfourbar.initial_state(nfourbar.parameter_defaults)
    for _ in range(5):
        assert_same(nfourbar, x0 + rng.normal(scale=0.5, size=x0.size), e0=1e-3 * rng.normal())


def test_nfourbar_singular_pose_takes_the_least_norm_solve(nfourbar):
    """All bars horizontal: every loop's x row vanishes (the rows are redundant), the dense path takes its SVD; the
    sparse one its block's, with the same least-norm multipliers (zero on the vanished rows)."""
    nq = nfourbar.nq
    x = np.zeros(nfourbar.nx)
    x[nq:nq + nq] = [0.7 if i % 2 == 0 else -0.7 for i in range(nq)]
    x[nq + 1] += 0.01                                   # off the velocity constraint: the projection corrects it
    lam = evaluate(nfourbar, variants(nfourbar)[DENSE], x, 0.0)[1]
    phi, c, A, kappa = (np.zeros(nfourbar.nh), np.zeros(nfourbar.nc), np.zeros((nfourbar.nc, nq)),
                        np.zeros(nfourbar.nc))
    p = nfourbar.parameter_defaults
    nfourbar.module.constraints(0.0, x, nfourbar.input_defaults, p, nfourbar.initial_discrete(p), phi, c, A, kappa)
    assert np.linalg.matrix_rank(A) < nfourbar.nc
    assert np.abs(lam[0::2]).max() < 1e-12 < np.abs(lam[1::2]).min()
    assert_same(nfourbar, x, e0=1e-3)
    x[:nq] = 1e-9                                       # near it: below the rank tolerance still
    assert_same(nfourbar, x, e0=1e-3)


def test_nfourbar_follows_the_reduced_motion(nfourbar):
    """With the sparse solve (chosen from N = 5 on; N = 3 builds faster), through its singular poses."""
    times = (0.5, 1.0, 12.5, 20.0)
    sparse = dataclasses.replace(nfourbar, ref=variants(nfourbar)[SPARSE])
    run = andyc.simulate(sparse, 20.0, dt=1e-3, method="projection", every=500, frames=["tip0"], progress=False)
    exact = reduced_b0(3, times)
    for k, t in enumerate(times):
        i = int(np.argmin(abs(run.time - t)))
        assert abs(run.time[i] - t) < 1e-9
        assert np.abs(run.frames["tip0"][i, :2] - exact[k]).max() < 1e-6


def test_a_singular_block_alone_takes_the_svd(compiled, build_dir):
    """Two separate four-bars: their rows form two blocks; with one lying flat (its x row vanishes) only that block
    takes the SVD, and the result is still the dense SVD path's."""
    path = build_dir / "twin_fourbars.yaml"
    path.write_text(TWIN)
    model = compiled(path)
    assert model.module.EQUATIONS.FLOW_ENVELOPE[0, 1].tolist() == [0, 0, 2, 2]     # two blocks: rows 0-1, 2-3
    nq = model.nq
    x = np.zeros(model.nx)
    x[:nq] = [0.0, 0.0, 0.0, 1.2, -1.2, 1.2]             # a flat, b at a generic pose
    x[nq:] = [0.7, -0.7, 0.7, -0.4, 0.4, -0.4]
    lam = evaluate(model, variants(model)[DENSE], x, 0.0)[1]
    assert abs(lam[0]) < 1e-12 < min(abs(lam[1]), abs(lam[2]), abs(lam[3]))
    assert_same(model, x, e0=1e-3)
    x[:3] = 1e-11                                        # near it: far below the rank tolerance
    assert_same(model, x, e0=1e-3)


@pytest.mark.parametrize("name, singular", [("fourbar", [0.0, 0.0, 0.0]), ("slider_crank", None)])
def test_shipped_models_sparse_equals_dense(compiled, name, singular):
    model = compiled(name)
    assert len(model.module.EQUATIONS.ROW_PTR)                  # the sparse solve applies (chosen or not)
    rng = np.random.default_rng(3)
    x0 = model.initial_state(model.parameter_defaults)
    for _ in range(5):
        assert_same(model, x0 + rng.normal(scale=0.5, size=x0.size), e0=1e-3 * rng.normal())
    if singular is not None:                                    # the flat four-bar: its loop loses a rank
        x = x0.copy()
        x[:model.nq] = singular
        assert_same(model, x, e0=1e-3)


CHAIN_PINNED = """name: chain_pinned
parameters: {g: 9.81, m: 1.0, L: 0.5}
coordinates: {q1: {initial: 0.3}, q2: {initial: 0.2}, q3: {initial: 0.1}}
gravity: [0, -g, 0]
frames:
  - {name: l1, parent: world, revolute: q1}
  - {name: j2, parent: l1, translation: [L, 0, 0]}
  - {name: l2, parent: j2, revolute: q2}
  - {name: j3, parent: l2, translation: [L, 0, 0]}
  - {name: l3, parent: j3, revolute: q3}
  - {name: tip, parent: l3, translation: [L, 0, 0]}
bodies: [{name: b1, frame: j2, mass: m}, {name: b2, frame: j3, mass: m}, {name: b3, frame: tip, mass: m}]
constraints:
  - {name: hold, holonomic: tip.y + 1.2}
hybrid:
  flows: [{name: swing}, {name: held, constraints: [hold]}]
  jumps:
    - {name: catch, from: swing, to: held, guard: tip.y + 1.2, direction: falling, impact: plastic, enabled: t < 0.9}
    - {name: release, from: held, to: swing, guard: t - 1, direction: rising}
"""


@pytest.mark.parametrize("name, method", [("fourbar", "projection"), ("chain_pinned", "rk4"), ("rolling_disk", "rk4")])
def test_trajectories_sparse_equal_dense(compiled, name, method, tmp_path_factory):
    """The whole run with each solve, forced: the four-bar through its flat (singular) configuration (projected: RK4
    alone drifts there, amplifying any rounding), a chain caught at its tip, held and let go (flows with and without
    rows; its plastic impact keeps the dense map), nonholonomic rows: within 1e-12. (A model with contacts keeps the
    dense solve: its rows join the flows' at run time; andyc.codegen.generate.)"""
    if name == "chain_pinned":
        path = tmp_path_factory.mktemp("chain") / "chain_pinned.yaml"
        path.write_text(CHAIN_PINNED)
        name = path
    model = compiled(name)
    runs = [andyc.simulate(dataclasses.replace(model, ref=ref), 2.0, dt=1e-3, method=method, every=100,
                           progress=False)
            for ref in variants(model).values()]
    assert runs[0].time.shape == runs[1].time.shape and runs[0].status == runs[1].status == "finished"
    assert np.abs(runs[0].state - runs[1].state).max() <= TOL * max(1.0, np.abs(runs[0].state).max())
