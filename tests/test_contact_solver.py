"""The compiled contact problem (andyc.numerics.contact_solver) against its pure-Python twin
(andyc.independent.contact_problem) on random problems, against closed forms, and against the problem's conditions
themselves, checked here from the math (w = w0 + W P; bilateral rows w = 0; 0 <= w_n _|_ P_n >= 0; Coulomb's
cone |P_t| <= mu P_n, no slip inside it, P_t = -mu P_n w_t / |w_t| on its edge)."""

import math

import numba
import numpy as np
import pytest

from andyc.numerics import contact_solver as cs
from andyc.independent import contact_problem as cp

G, H = 9.81, 1e-3


def solve(W, w0, kind, mu, state=None, direction=None, P=None):
    """The compiled solver on blocks `kind` laid out in order; returns (P, state, direction, sweeps, verified)."""
    kind = np.asarray(kind, dtype=np.int64)
    sizes = np.maximum(kind, 1)
    first = np.concatenate([[0], np.cumsum(sizes)[:-1]]).astype(np.int64)
    m, nb = len(w0), len(kind)
    state = np.full(nb, cs.NONE, np.int64) if state is None else np.array(state, dtype=np.int64)
    direction = np.zeros((nb, 2)) if direction is None else np.array(direction, dtype=float)
    P = np.zeros(m) if P is None else np.array(P, dtype=float)
    work = np.empty(cs.work_shape(m))
    sweeps, verified = cs.solve(np.ascontiguousarray(W, dtype=float), np.asarray(w0, dtype=float), kind, first,
                                np.asarray(mu, dtype=float), state, direction, P, work)
    return P, state, direction, sweeps, verified


def blocks_of(kind, mu):
    """The Python twin's blocks for the same layout."""
    out, r = [], 0
    for k, u in zip(kind, mu):
        size = max(int(k), 1)
        out.append(cp.Block(int(k), tuple(range(r, r + size)), float(u)))
        r += size
    return out


def check_conditions(W, w0, kind, mu, P, rel=1e-10):
    """Every condition of the problem at P, to `rel` of max(1, |w0|) on velocities and of |P| on impulses."""
    w = w0 + W @ P
    tol_w = rel * max(1.0, np.max(np.abs(w0)))
    tol_p = rel * max(1e-300, np.max(np.abs(P)))
    r = 0
    for k, u in zip(kind, mu):
        size = max(int(k), 1)
        n = r
        r += size
        if k == cs.BILATERAL:
            assert abs(w[n]) <= tol_w
            continue
        assert P[n] >= -tol_p and w[n] >= -tol_w
        assert P[n] <= tol_p or abs(w[n]) <= tol_w            # complementarity
        if k == cs.NORMAL:
            continue
        Pt, slip = P[n + 1:n + size], w[n + 1:n + size]
        assert np.linalg.norm(Pt) <= u * P[n] + tol_p          # in the cone
        speed = np.linalg.norm(slip)
        if speed > tol_w:                                      # slipping: on the cone's edge, against the slip
            assert np.linalg.norm(Pt + u * P[n] * slip / speed) <= tol_p + 2 * u * P[n] * tol_w / speed


def test_constants_are_the_python_twins():
    for name in ("BILATERAL", "NORMAL", "PLANAR", "SPATIAL", "OPEN", "STICK", "SLIP_POS", "SLIP_NEG", "SLIDE",
                 "SCAN", "SWEEPS", "SWEEP_TOL"):
        assert getattr(cs, name) == getattr(cp, name), name


def random_problem(seed):
    """A random problem of up to 40 rows: mixed blocks; W = A M^-1 A^T of random A and SPD M. Seeds % 3: 0, as
    many speeds as rows or more (W positive definite); 1, fewer speeds than rows (at least 3); 2, as 1, and some
    rows copies (scaled) of another block's (redundant contacts). w0 = A v (the rows' velocities at a random v,
    consistent however redundant). Returns (W, w0, kind, mu, whether W is positive definite)."""
    rng = np.random.default_rng(seed)
    kind = rng.choice([cs.BILATERAL, cs.NORMAL, cs.PLANAR, cs.SPATIAL], size=int(rng.integers(1, 15)),
                      p=[0.1, 0.2, 0.3, 0.4])
    while np.maximum(kind, 1).sum() > 40:
        kind = kind[:-1]
    sizes = np.maximum(kind, 1)
    m = int(sizes.sum())
    definite = seed % 3 == 0
    nv = m + int(rng.integers(0, 5)) if definite else max(3, int(rng.integers(m // 3, m + 1)))
    A = rng.normal(size=(m, nv))
    owner = np.repeat(np.arange(len(kind)), sizes)
    if seed % 3 == 2 and len(kind) > 1:
        pairs = rng.choice(m, 2 * min(int(rng.integers(1, 4)), m // 2), replace=False).reshape(-1, 2)
        for i, j in pairs:                      # (distinct rows, of two blocks: no local problem singular)
            if owner[i] != owner[j]:
                A[i] = A[j] * rng.uniform(0.5, 2.0)
    B = rng.normal(size=(nv, nv))
    W = A @ np.linalg.solve(B @ B.T + nv * np.eye(nv), A.T)
    W = 0.5 * (W + W.T)
    w0 = A @ rng.normal(size=nv)
    mu = rng.uniform(0.1, 1.0, size=len(kind))
    return W, w0, kind.astype(np.int64), mu, definite and np.linalg.matrix_rank(A) == m


def test_random_problems_against_the_python_twin():
    """250 random problems (random_problem): on each the Python twin verifies (at least 200), the compiled solver
    verifies too, and both answers satisfy every condition (checked here). Where W is positive definite the
    impulses agree to 1e-9 relative, and the states and slip directions are the same; elsewhere the impulses
    are not unique, the velocities w = w0 + W P agree to 1e-9 and the states do but for at most two problems
    (where the impulses are not unique, neither need the active set be: roundings may tip a contact that carries
    nothing in one solution, and in 1250 more problems one did so after 421 and 456 sweeps). Where the twin
    does not verify, the compiled solver's answer, when it verifies (it also tries the solution closest to the
    Gauss-Seidel answer where the active set's rows are dependent), satisfies every condition too."""
    both = definite = extra = other = 0
    for seed in range(250):
        W, w0, kind, mu, pd = random_problem(seed)
        ref = cp.solve(W, w0, blocks_of(kind, mu))
        P, state, direction, sweeps, verified = solve(W, w0, kind, mu)
        if not ref.verified:
            if verified:
                check_conditions(W, w0, kind, mu, P)
                extra += 1
            continue
        both += 1
        assert verified, seed
        check_conditions(W, w0, kind, mu, P)
        check_conditions(W, w0, kind, mu, ref.P)
        scale = max(1.0, np.max(np.abs(w0)))
        assert np.max(np.abs(W @ (P - ref.P))) <= 1e-9 * scale, seed
        if pd:
            definite += 1
            assert np.max(np.abs(P - ref.P)) <= 1e-9 * np.max(np.abs(ref.P)), seed
        if list(state) != ref.states:
            assert not pd, seed
            other += 1
            continue
        for k in np.nonzero((state == cs.SLIDE) & (kind == cs.SPATIAL))[0]:
            assert np.allclose(direction[k], ref.directions[k], rtol=0, atol=1e-9), seed
    print(f"both verified: {both} (W definite: {definite}; other states: {other}); the compiled solver alone: "
          f"{extra}")
    assert both >= 200 and definite >= 60 and other <= 2


@pytest.mark.parametrize("seed", [0, 1, 2, 4, 8])
def test_warm_start_takes_no_sweep(seed):
    """Started from the states (and slip directions, and impulses) a solve found, a second solve verifies them at
    once (sweeps 0) with the same impulses, states and directions."""
    W, w0, kind, mu, _ = random_problem(seed)
    P, state, direction, sweeps, verified = solve(W, w0, kind, mu)
    assert verified and sweeps > 0
    again = solve(W, w0, kind, mu, state, direction, P)
    assert again[3:] == (0, True)
    assert np.allclose(again[0], P, rtol=0, atol=1e-12 * np.max(np.abs(P)))
    assert np.array_equal(again[1], state) and np.array_equal(again[2], direction)


def test_a_wrong_guess_falls_back_to_the_sweeps():
    """A guess that does not verify (every contact open, where they are pressed) costs the sweeps, with the
    answer of a solve without it."""
    W, w0, kind, mu, _ = random_problem(0)
    cold = solve(W, w0, kind, mu)
    guess = np.where(kind == cs.BILATERAL, cs.STICK, cs.OPEN)
    warm = solve(W, w0, kind, mu, guess)
    assert warm[4] and warm[3] == cold[3] > 0
    assert np.array_equal(warm[0], cold[0]) and np.array_equal(warm[1], cold[1])


@pytest.mark.parametrize("w0, P, state", [(-2.0, 0.8, cs.STICK), (0.5, 0.0, cs.OPEN), (0.0, 0.0, cs.OPEN)])
def test_one_frictionless_contact(w0, P, state):
    """P = max(0, -w0 / W): an approaching contact takes the impulse that stops it, a leaving one none."""
    out = solve(np.array([[2.5]]), np.array([w0]), [cs.NORMAL], [0.0])
    assert out[0][0] == pytest.approx(P, rel=1e-15, abs=0) and out[1][0] == state and out[4]


@pytest.mark.parametrize("mu", [0.7, 0.5, 0.3])
def test_point_mass_on_an_incline(mu):
    """A point mass m at rest on an incline of th = 0.5 (tan th = 0.546), one step h of gravity: rows (normal,
    up the slope), W = I / m, w0 = -g h (cos th, sin th). mu >= tan th sticks: P = m g h (cos th, sin th)
    exactly; mu < tan th slides down (slip after -g h (sin th - mu cos th) < 0: SLIP_NEG) with P_t = mu P_n."""
    m, th = 2.0, 0.5
    w0 = -G * H * np.array([math.cos(th), math.sin(th)])
    P, state, _, _, verified = solve(np.eye(2) / m, w0, [cs.PLANAR], [mu])
    assert verified
    Pn = m * G * H * math.cos(th)
    if mu >= math.tan(th):
        assert state[0] == cs.STICK
        assert np.allclose(P, m * G * H * np.array([math.cos(th), math.sin(th)]), rtol=1e-15, atol=0)
    else:
        assert state[0] == cs.SLIP_NEG
        assert np.allclose(P, [Pn, mu * Pn], rtol=1e-15, atol=0)
        slip = w0[1] + P[1] / m
        assert slip == pytest.approx(-G * H * (math.sin(th) - mu * math.cos(th)), rel=1e-12)


def test_spatial_point_mass_slides_along_its_slip():
    """A unit-mass point (W = I) approaching at 1 and slipping at s = (3, -4): P_n = 1, the friction -mu P_n s / |s|
    (an isotropic tangential inertia keeps the slip's direction: the secant method's first guess), slip after
    s (1 - mu / 5); SLIDE along s / |s|."""
    mu = 0.5
    P, state, direction, _, verified = solve(np.eye(3), np.array([-1.0, 3.0, -4.0]), [cs.SPATIAL], [mu])
    assert verified and state[0] == cs.SLIDE
    assert np.allclose(P, [1.0, -mu * 0.6, mu * 0.8], rtol=0, atol=1e-15)
    assert np.allclose(direction[0], [0.6, -0.8], rtol=0, atol=1e-15)


def test_spatial_slide_with_an_anisotropic_inertia():
    """Tangential inverse inertias 1 and 4 (W = diag(2, 1, 4)): the slip turns under the friction, so the known
    answer is built backwards: for a direction d and a slip after lam d, w0_t = lam d + mu P_n T d with P_n = -w0_n
    / 2. The solver finds P = P_n (1, -mu d)."""
    mu, lam, angle = 0.4, 0.7, 2.2
    d = np.array([math.cos(angle), math.sin(angle)])
    T = np.diag([1.0, 4.0])
    Pn = 1.5
    w0 = np.array([-2.0 * Pn, *(lam * d + mu * Pn * T @ d)])
    P, state, direction, _, verified = solve(np.diag([2.0, 1.0, 4.0]), w0, [cs.SPATIAL], [mu])
    assert verified and state[0] == cs.SLIDE
    assert np.allclose(P, [Pn, *(-mu * Pn * d)], rtol=0, atol=1e-12)
    assert np.allclose(direction[0], d, rtol=0, atol=1e-12)


@pytest.mark.parametrize("kind", [cs.PLANAR, cs.SPATIAL])
def test_no_friction_on_tangent_rows(kind):
    """mu = 0 on a contact with tangent rows: no tangential impulse, the slip left as it comes (the Python twin
    leaves the planar one unverified and raises on the spatial one: it checks the slip against a direction the
    zero friction does not have, NaN in space)."""
    w0 = np.array([-1.0, 0.3, -0.2][:kind])               # (kind: the block's rows)
    P, state, direction, _, verified = solve(np.eye(kind), w0, [kind], [0.0])
    assert verified and np.array_equal(P, [1.0] + [0.0] * (kind - 1)) and np.array_equal(direction, [[0.0, 0.0]])


def test_a_slide_guess_needs_a_unit_direction():
    """A warm start's sliding spatial contact with direction (0, 0) would give it no friction: refused (the
    sweeps run), and the answer is the cold solve's."""
    w0 = np.array([-1.0, 3.0, -4.0])
    cold = solve(np.eye(3), w0, [cs.SPATIAL], [0.5])
    warm = solve(np.eye(3), w0, [cs.SPATIAL], [0.5], [cs.SLIDE], [[0.0, 0.0]])
    assert warm[3] == cold[3] > 0 and warm[4] and np.array_equal(warm[0], cold[0])


def box_on_four_corners(v, gravity=(0.0, 0.0, -G)):
    """A box (mass 2, half sizes 0.3, 0.2, 0.1, its centre of mass at its centre) flat on the ground on its four
    bottom corners with spatial friction, moving at v (linear, angular: 6 speeds) for one step h of gravity (in the
    ground's frame: a tilted one is a slope): (W, w0, A, M^-1, v_free): 12 rows (normal z, tangents x, y per
    corner) on 6 speeds, W of rank 6."""
    m, (a, b, c) = 2.0, (0.3, 0.2, 0.1)
    inertia = m / 3 * np.array([b * b + c * c, a * a + c * c, a * a + b * b])
    Minv = np.diag(1 / np.array([m, m, m, *inertia]))
    rows = []
    for x, y in ((a, b), (-a, b), (-a, -b), (a, -b)):
        r = np.array([x, y, -c])
        for e in np.eye(3)[[2, 0, 1]]:                         # (normal z first, then tangents x, y)
            rows.append(np.concatenate([e, np.cross(r, e)]))   # e . (v + omega x r)
    A = np.array(rows)
    v_free = np.asarray(v, dtype=float) + H * np.array([*gravity, 0, 0, 0])
    return A @ Minv @ A.T, A @ v_free, A, Minv, v_free


def test_box_resting_on_four_redundant_corners():
    """The box at rest: 12 rows on 6 speeds; the impulses are not unique, and the least-norm ones share the
    weight equally: P_n = m g h / 4 at each corner, no friction, the box left at rest."""
    W, w0, A, Minv, v_free = box_on_four_corners(np.zeros(6))
    assert np.linalg.matrix_rank(W) == 6
    P, state, _, _, verified = solve(W, w0, [cs.SPATIAL] * 4, [0.5] * 4)
    assert verified and list(state) == [cs.STICK] * 4
    assert np.allclose(P, np.tile([2.0 * G * H / 4, 0.0, 0.0], 4), rtol=0, atol=1e-15)
    assert np.max(np.abs(v_free + Minv @ A.T @ P)) <= 1e-15


def test_box_sliding_on_four_redundant_corners():
    """The box sliding along x at 1 m/s (mu = 0.3): every corner slides along x; the friction pitches the box,
    its normal impulses shift to the front, and after the step it moves along x at 1 - mu g h with no other
    speed (1e-12); every condition holds."""
    mu = 0.3
    W, w0, A, Minv, v_free = box_on_four_corners([1.0, 0, 0, 0, 0, 0])
    P, state, direction, _, verified = solve(W, w0, [cs.SPATIAL] * 4, [mu] * 4)
    assert verified and list(state) == [cs.SLIDE] * 4
    assert np.allclose(direction, [[1.0, 0.0]] * 4, rtol=0, atol=1e-12)
    check_conditions(W, w0, [cs.SPATIAL] * 4, [mu] * 4, P)
    v = v_free + Minv @ A.T @ P
    assert np.allclose(v, [1.0 - mu * G * H, 0, 0, 0, 0, 0], rtol=0, atol=1e-12)
    assert P[0] > P[3] and P[9] > P[6]          # (the front corners, x = +a, carry more)


def diagonal_slope(th):
    """box_on_four_corners at rest on a slope of th whose fall line runs along the diagonal (1, 1) of its base."""
    gravity = G * np.array([-math.sin(th) / math.sqrt(2), -math.sin(th) / math.sqrt(2), -math.cos(th)])
    return box_on_four_corners(np.zeros(6), gravity)


def test_box_held_on_a_diagonal_slope_shares_the_friction_as_its_cones_allow():
    """The box held (the last step's states: every corner sticking) on a slope of 0.3 rad along the diagonal of
    its base, mu just above tan 0.3: the friction takes gravity's whole tangential part, along x and y at once.
    The downhill corner carries the most, the uphill one the least (the centre of mass is c above the base), so
    split evenly the uphill corner's share would leave its cone. Each corner's share in both tangential
    directions follows mu P_n, its cone (contact_solver._weighted): every corner then uses the same fraction of its
    cone, the total's, |P_t| / (mu P_n) = m g sin th / (mu m g cos th) = tan th / mu (by hand), and the box is left
    at rest (1e-15)."""
    th, mu = 0.3, math.tan(0.3) + 1e-3
    W, w0, A, Minv, v_free = diagonal_slope(th)
    P, state, _, _, verified = solve(W, w0, [cs.SPATIAL] * 4, [mu] * 4, [cs.STICK] * 4)
    assert verified and list(state) == [cs.STICK] * 4
    check_conditions(W, w0, [cs.SPATIAL] * 4, [mu] * 4, P)
    assert np.max(np.abs(v_free + Minv @ A.T @ P)) <= 1e-15
    normal, friction = P[0::3], P.reshape(4, 3)[:, 1:]
    assert np.argmax(normal) == 2 and np.argmin(normal) == 0        # the downhill corner (-a, -b), the uphill (a, b)
    assert np.linalg.norm(friction.sum(axis=0) / 4) > mu * normal[0]  # an even split leaves the uphill corner's cone
    share = np.linalg.norm(friction, axis=1) / (mu * normal)
    assert np.allclose(share, math.tan(th) / mu, rtol=1e-12, atol=0)
    assert np.allclose(friction[:, 0], friction[:, 1], rtol=1e-12, atol=0)     # straight up the fall line


@pytest.mark.xfail(strict=True, reason="a cold solve (no states from a last step) of a box held within 1e-3 of its "
                   "cones' edge: Gauss-Seidel ends with every corner sliding and the answer unverified (500 sweeps), "
                   "the box left moving at 1e-9 m/s; from 3e-3 on it is verified, and warm (the states of a step "
                   "before, as a run has them after its first step) it is exact")
def test_box_held_on_a_diagonal_slope_cold():
    th, mu = 0.3, math.tan(0.3) + 1e-3
    W, w0, A, Minv, v_free = diagonal_slope(th)
    P, state, _, _, verified = solve(W, w0, [cs.SPATIAL] * 4, [mu] * 4)
    assert verified and np.max(np.abs(v_free + Minv @ A.T @ P)) <= 1e-15


def test_no_rows():
    assert solve(np.zeros((0, 0)), np.zeros(0), np.zeros(0, np.int64), np.zeros(0))[3:] == (0, True)


@numba.njit
def _twice(W, w0, kind, first, mu, state, direction, P, work):
    """Two solves from compiled code: cold, then warm from the first's states."""
    for k in range(state.shape[0]):
        state[k] = cs.NONE
    cold = cs.solve(W, w0, kind, first, mu, state, direction, P, work)
    warm = cs.solve(W, w0, kind, first, mu, state, direction, P, work)
    return cold[0], cold[1], warm[0], warm[1]


def test_callable_from_compiled_code():
    """cs.solve called from an njit function (nopython): the same answer as from Python, then the warm start."""
    W, w0, kind, mu, _ = random_problem(4)
    first = np.concatenate([[0], np.cumsum(np.maximum(kind, 1))[:-1]]).astype(np.int64)
    m, nb = len(w0), len(kind)
    state, direction, P = np.zeros(nb, np.int64), np.zeros((nb, 2)), np.zeros(m)
    out = _twice(W, w0, kind, first, mu, state, direction, P, np.empty(cs.work_shape(m)))
    ref = solve(W, w0, kind, mu)
    assert out == (ref[3], True, 0, True)
    assert np.allclose(P, ref[0], rtol=0, atol=1e-12 * np.max(np.abs(P))) and np.array_equal(state, ref[1])


@numba.njit
def _many(count, W, w0, kind, first, mu, state, direction, P, work):
    """`count` cold solves and as many warm ones, from compiled code."""
    sweeps = 0
    for _ in range(count):
        sweeps += _twice(W, w0, kind, first, mu, state, direction, P, work)[0]
    return sweeps


def test_no_allocation_inside():
    """From compiled code the solver allocates nothing (Numba's runtime counts its allocations): 10 cold and warm
    solves allocate what one pair does (what Numba takes for the arrays passed in from Python, if anything)."""
    nrt = pytest.importorskip("numba.core.runtime._nrt_python")     # (Numba's own tests count so)
    W, w0, kind, mu, _ = random_problem(5)
    first = np.concatenate([[0], np.cumsum(np.maximum(kind, 1))[:-1]]).astype(np.int64)
    m, nb = len(w0), len(kind)
    args = (W, w0, kind, first, mu, np.zeros(nb, np.int64), np.zeros((nb, 2)), np.zeros(m),
            np.empty(cs.work_shape(m)))
    _many(1, *args)
    enabled = nrt.memsys_stats_enabled()
    nrt.memsys_enable_stats()
    try:
        counts = []
        for count in (1, 10):
            before = nrt.memsys_get_stats_alloc()
            _many(count, *args)
            counts.append(nrt.memsys_get_stats_alloc() - before)
    finally:
        if not enabled:
            nrt.memsys_disable_stats()
    assert counts[0] == counts[1]
