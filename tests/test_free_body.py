"""A torque-free block on a floating joint (models/free_body.yaml): conservation,
the intermediate-axis (Dzhanibekov) flip, an independent integration of Euler's
equations, velocities written in the parent's axes, and quaternion normalization.

Everything here is computed from the logged state with numpy and scipy only:
the rotation matrix from the logged quaternion, the momenta, and a reference
solution of I dw/dt = -w x I w, q' = q (x) [0, w] / 2, v_b' = -w x v_b, r' = R v_b.
"""

import numpy as np
import pytest
import yaml
from scipy.integrate import solve_ivp

from andyc.runtime.options import Projection
from andyc.runtime.simulate import simulate
from tests.support import MODELS

T_END, DT = 20.0, 1e-3
MASS = 48.0
I = MASS / 12 * np.array([0.2**2 + 0.1**2, 0.3**2 + 0.1**2, 0.3**2 + 0.2**2])   # 0.2, 0.4, 0.52
V, W, POS, QUAT = ("vx", "vy", "vz"), ("wx", "wy", "wz"), ("block_x", "block_y", "block_z"), \
    ("block_qw", "block_qx", "block_qy", "block_qz")


def cols(run, names):
    return np.column_stack([run.column(n) for n in names])


def rotation(q):
    """Rotation matrices (block axes -> world) of quaternions (w, x, y, z), normalized first."""
    q = q / np.linalg.norm(q, axis=-1, keepdims=True)
    w, x, y, z = np.moveaxis(q, -1, 0)
    return np.stack([np.stack([1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)], -1),
                     np.stack([2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)], -1),
                     np.stack([2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)], -1)], -2)


def quaternion_distance(a, b):
    """max |a - b| per row, up to the sign ambiguity q ~ -q."""
    return np.minimum(abs(a - b).max(axis=1), abs(a + b).max(axis=1))


@pytest.fixture(scope="module")
def model(compiled):
    return compiled("free_body")


@pytest.fixture(scope="module")
def run(model):
    r = simulate(model, T_END, dt=DT, method="rk4", frames=["block"])
    assert r.finished
    return r


def test_inertia_and_mass_are_what_the_test_assumes(model):
    """The test's I and m agree with the compiled model's energy function."""
    p, u = model.parameter_defaults, model.input_defaults
    for k, name in enumerate(W + V):
        x = model.initial_state(p) * 0
        x[model.state_names.index("block_qw")] = 1.0
        x[model.state_names.index(name)] = 1.0
        expected = I[k] / 2 if name in W else MASS / 2
        assert model.module.energy(0.0, x, u, p, model.initial_discrete(p)) == pytest.approx(expected, rel=1e-14)
    assert model.state_names == V + W + POS + QUAT           # no coordinates: speeds and signals only
    assert (model.nq, model.nv, model.ns) == (0, 6, 7)


def test_momenta_energy_and_straight_line(run):
    w, v, q, r = cols(run, W), cols(run, V), cols(run, QUAT), cols(run, POS)
    R = rotation(q)
    L = np.einsum("nij,nj->ni", R, I * w)                   # world angular momentum
    L_drift = np.linalg.norm(L - L[0], axis=1).max() / np.linalg.norm(L[0])
    E_drift = abs(run.energy - run.energy[0]).max() / run.energy[0]
    p = MASS * np.einsum("nij,nj->ni", R, v)                # world linear momentum
    p_drift = np.linalg.norm(p - p[0], axis=1).max() / np.linalg.norm(p[0])
    line = r[0] + run.time[:, None] * p[0] / MASS
    off_line = np.linalg.norm(r - line, axis=1).max()
    travel = np.linalg.norm(r[-1] - r[0])
    print(f"\n[a] L drift {L_drift:.2e}, energy drift {E_drift:.2e}, linear momentum drift {p_drift:.2e}, "
          f"off the straight line {off_line:.2e} m over {travel:.2f} m")
    assert np.linalg.norm(L[0]) > 1.0 and travel > 10.0                # something to conserve
    assert np.linalg.norm(w - w[0], axis=1).max() > 3.0                # w_body itself changes a lot
    assert L_drift < 1e-9
    assert E_drift < 1e-9
    assert p_drift < 1e-9
    assert off_line < 1e-9
    assert abs(run.frames["block"] - r).max() < 1e-12                  # frame origin = position signals


def test_intermediate_axis_flips(run):
    w, t = cols(run, W), run.time
    wy = w[:, 1]
    cross = np.nonzero(np.sign(wy[1:]) != np.sign(wy[:-1]))[0]
    times = t[cross] - wy[cross] * DT / (wy[cross + 1] - wy[cross])
    print(f"\n[b] w_y changes sign {len(cross)} times, at t = {np.round(times, 3).tolist()} s")
    assert len(cross) == 3                           # at least two flips in 20 s; three with these numbers
    # Between flips (and before the first) the block spins about y again: |w_y| back up to
    # its start, |w_x|, |w_z| back near their small start values (the run ends mid-swing).
    for lo, hi in zip([0, *cross[:-1]], cross):
        peak = lo + np.argmax(abs(wy[lo:hi]))
        assert abs(wy[peak]) > 3.0 and np.hypot(w[peak, 0], w[peak, 2]) < 0.1
    # At a crossing (w_y = 0) the invariants 2T = sum I w^2 and |L|^2 = sum I^2 w^2
    # fix |w_x| and |w_z|: large there (the block is turning over), not small.
    T2, L2 = (I * w[0] ** 2).sum(), (I ** 2 * w[0] ** 2).sum()
    wx2 = (L2 - I[2] * T2) / (I[0] * (I[0] - I[2]))
    wz2 = (L2 - I[0] * T2) / (I[2] * (I[2] - I[0]))
    for i in cross:
        s = wy[i] / (wy[i] - wy[i + 1])
        at = w[i] + s * (w[i + 1] - w[i])
        assert abs(at[0]) == pytest.approx(np.sqrt(wx2), rel=1e-5)
        assert abs(at[2]) == pytest.approx(np.sqrt(wz2), rel=1e-5)
    print(f"    at the crossings |w_x| = {np.sqrt(wx2):.4f}, |w_z| = {np.sqrt(wz2):.4f} rad/s (from T and |L|)")


def reference_rhs(t, y):
    w, q, vb = y[:3], y[3:7], y[7:10]
    dw = -np.cross(w, I * w) / I
    dq = np.r_[-q[1:] @ w, q[0] * w + np.cross(q[1:], w)] / 2
    return np.r_[dw, dq, -np.cross(w, vb), rotation(q) @ vb]


def test_matches_an_independent_integration_of_eulers_equations(run):
    """Tolerance 1e-9 (w, rad/s; q) and 1e-8 (position, m). Measured: ~3e-11 and ~4e-12.
    RK4 at 1e-3 s has a global error ~5e-11 in w here (halving the step moves w by 4.6e-11),
    and DOP853 at rtol = atol = 1e-12 ~1e-11 (against rtol 1e-13); both grow with time,
    because near the separatrix the flip times are sensitive to small errors. 1e-9 leaves
    a margin of ~30 over the two and is still far below any modelling error (a wrong sign or
    inertia changes w by O(1) within the first flip)."""
    w, q, v, r = cols(run, W), cols(run, QUAT), cols(run, V), cols(run, POS)
    y0 = np.r_[w[0], q[0], v[0], r[0]]
    sol = solve_ivp(reference_rhs, (0.0, T_END), y0, method="DOP853", rtol=1e-12, atol=1e-12, t_eval=run.time)
    assert sol.success
    Y = sol.y.T
    err_w = abs(Y[:, :3] - w).max()
    err_q = quaternion_distance(Y[:, 3:7], q).max()
    err_v = abs(Y[:, 7:10] - v).max()
    err_r = abs(Y[:, 10:] - r).max()
    print(f"\n[c] andyc rk4 vs DOP853: w {err_w:.1e} rad/s, q {err_q:.1e}, v_body {err_v:.1e} m/s, "
          f"position {err_r:.1e} m")
    assert err_w < 1e-9
    assert err_q < 1e-9
    assert err_v < 1e-9
    assert err_r < 1e-8


def test_velocities_in_parent_axes_give_the_same_world_motion(run, compiled, tmp_path):
    data = yaml.safe_load((MODELS / "free_body.yaml").read_text())
    data["name"] = "free_body_parent"        # its own build folder
    data["frames"][0]["floating"]["in"] = "parent"
    s = data["speeds"]
    R0 = rotation(np.array(data["frames"][0]["floating"]["quaternion"], dtype=float))
    v0 = R0 @ [s[n]["initial"] for n in V]
    w0 = R0 @ [s[n]["initial"] for n in W]
    for names, vec in ((V, v0), (W, w0)):
        for n, value in zip(names, vec):
            s[n] = {"initial": float(value)}
    path = tmp_path / "free_body_parent.yaml"
    path.write_text(yaml.safe_dump(data, sort_keys=False))
    world = simulate(compiled(path), T_END, dt=DT, method="rk4")
    assert world.finished
    q_b, q_p = cols(run, QUAT), cols(world, QUAT)
    err_q = quaternion_distance(q_b, q_p).max()
    err_r = abs(cols(run, POS) - cols(world, POS)).max()
    # The speeds are the world velocities now: w_world = R w_body, and v_world constant.
    R = rotation(q_b)
    err_w = abs(np.einsum("nij,nj->ni", R, cols(run, W)) - cols(world, W)).max()
    v_spread = abs(cols(world, V) - v0).max()
    print(f"\n[d] in: parent vs in: body: quaternion {err_q:.1e}, position {err_r:.1e} m, "
          f"R w_body - w_world {err_w:.1e} rad/s, v_world - v0 {v_spread:.1e} m/s")
    assert err_q < 1e-9
    assert err_r < 1e-9
    assert err_w < 1e-9
    assert v_spread < 1e-9


def test_quaternion_norm(run, model):
    free = simulate(model, T_END, dt=DT, method="rk4", projection=Projection(normalize=False))
    drift = abs(np.linalg.norm(cols(free, QUAT), axis=1) - 1).max()
    kept = abs(np.linalg.norm(cols(run, QUAT), axis=1) - 1).max()
    print(f"\n[e] |q| - 1 over {T_END:g} s: {drift:.1e} without normalization, {kept:.1e} with it")
    assert kept < 1e-12
    assert drift < 1e-9            # RK4 alone already keeps |q| close to 1 at this step
    assert drift > kept            # and the projection does something
