"""Synthetic runs built from small arrays (no model is compiled), for the tests of andyc.plot's figures and
animations: each kind of run a plot treats apart (plain, planar and spatial frames, a quaternion, constraints,
inputs, a hybrid walker), with arrays a test can compare what is drawn against."""

import numpy as np

from andyc.runtime.run import Run


def make_run(state_names, nq, nv, state, frames=None, t_end=2.0, **fields) -> Run:
    """A run of `state` (N, nx) sampled evenly over [0, t_end], energy 1 + 0.01 sin t."""
    t = np.linspace(0.0, t_end, state.shape[0])
    return Run(model="synthetic", spec_sha256="0" * 64, method="rk4", dt=t[1] - t[0], nq=nq, nv=nv, rtol=1e-8,
               atol=1e-10, t_end=t_end, parameters={}, inputs={}, state_names=state_names, time=t, state=state,
               energy=1.0 + 0.01 * np.sin(t), frames=frames or {}, **fields)


def plain_run(n=30) -> Run:
    """Two coordinates, two speeds; no frames, signals, flows or constraints."""
    t = np.linspace(0.0, 2.0, n)
    return make_run(["q1", "q2", "q1_dot", "q2_dot"], 2, 2, np.column_stack([t, -t, np.ones(n), -np.ones(n)]))


def planar_run(n=201) -> Run:
    """A double pendulum swinging in the world x-y plane: upper (at the origin, parent world) -> elbow
    -> lower (at the elbow: their paths coincide) -> tip, 1 m links, sampled every 0.01 s."""
    t = np.linspace(0.0, 2.0, n)
    th1, th2 = 0.8 * np.cos(2 * t), 0.5 * np.sin(3 * t)
    upper = np.zeros((n, 3))
    elbow = np.stack([np.sin(th1), -np.cos(th1), 0 * t], axis=1)
    tip = elbow + np.stack([np.sin(th1 + th2), -np.cos(th1 + th2), 0 * t], axis=1)
    state = np.column_stack([th1, th2, np.gradient(th1, t), np.gradient(th2, t)])
    return make_run(["th1", "th2", "th1_dot", "th2_dot"], 2, 2, state,
                    frames={"upper": upper, "elbow": elbow, "lower": elbow.copy(), "tip": tip},
                    frame_parents={"upper": "world", "elbow": "upper", "lower": "elbow", "tip": "lower"})


def spatial_run(n=101) -> Run:
    """A spherical double pendulum: arm hung from the world 1 m from the origin (a world link),
    tip 0.5 m below it, both moving in x, y and z."""
    t = np.linspace(0.0, 2.0, n)
    a, b = 0.6 * np.sin(2 * t), 0.4 * np.cos(2 * t)
    arm = np.stack([np.sin(a) * np.cos(b), np.sin(a) * np.sin(b), -np.cos(a)], axis=1)
    tip = arm + 0.5 * np.stack([np.sin(b), 0 * t, -np.cos(b)], axis=1)
    state = np.column_stack([a, b, np.gradient(a, t), np.gradient(b, t)])
    return make_run(["a", "b", "a_dot", "b_dot"], 2, 2, state, frames={"arm": arm, "tip": tip},
                    frame_parents={"arm": "world", "tip": "arm"})


def quaternion_run(n=50) -> Run:
    """A free body (no coordinates: speeds and signals only): a unit quaternion, a position, and
    one other signal; its frame and a marker on it (coincident paths) move in 3-D."""
    t = np.linspace(0.0, 2.0, n)
    half = 0.5 * t
    quaternion = np.stack([np.cos(half), 0.6 * np.sin(half), 0.8 * np.sin(half), 0 * t], axis=1)
    position = np.stack([np.cos(t), np.sin(t), -0.1 * t**2], axis=1)
    speeds = np.column_stack([np.sin(t), np.cos(t), t**2, -t, np.ones(n), 2 * t])
    names = ["wx", "wy", "wz", "vx", "vy", "vz", "body_qw", "body_qx", "body_qy", "body_qz",
             "body_x", "body_y", "body_z", "spin"]
    state = np.column_stack([speeds, quaternion, position, 3 * t])
    return make_run(names, 0, 6, state, frames={"body": position, "marker": position.copy()})


def constrained_run(n=50) -> Run:
    """Two multipliers; one position residual, two velocity residuals (the second exactly zero)."""
    t = np.linspace(0.0, 2.0, n)
    return make_run(["q", "q_dot"], 1, 1, np.column_stack([np.sin(t), np.cos(t)]),
                    multiplier_names=["lam_a", "lam_b"],
                    multipliers=np.column_stack([np.linspace(-1, 1, n), np.ones(n)]),
                    residual_position=np.column_stack([-1e-12 * (1 + t)]),
                    residual_velocity=np.column_stack([1e-13 * np.cos(t), np.zeros(n)]))


def contact_run(n=41) -> Run:
    """A ball on the ground contact (issue 21): falling while open (flow 0) until t = 1, then resting on it,
    closed (flow 1), its multiplier (the normal force) m g = 9.81 N there and a stray -3 while open (the run
    reports 0 for an open contact's force)."""
    t = np.linspace(0.0, 2.0, n)
    closed = t >= 1.0
    y = np.where(closed, 0.0, 4.905 * (1.0 - t ** 2))
    return make_run(["y", "y_dot"], 1, 1, np.column_stack([y, np.gradient(y, t)]),
                    flow=closed.astype(np.int64), flow_names=["open", "ground"], jump_names=["ground_impact"],
                    multiplier_names=["normal_force"], multipliers=np.where(closed, 9.81, -3.0)[:, None],
                    residual_position=np.zeros((n, 1)), residual_velocity=np.zeros((n, 1)),
                    contact_names=["ground"], contact_rows=[0])


def friction_contact_run(n=41) -> Run:
    """A block sliding on the ground with friction mu = 0.5 (issue 21): slipping forwards (flow 2) until t = 1, then
    sticking (flow 1); multipliers normal force 9.81 and friction (the stick row's, 0.25 while it sticks, NaN while
    it slips: the run reports -mu lam_n = -4.905 then)."""
    t = np.linspace(0.0, 2.0, n)
    sticking = t >= 1.0
    x = np.where(sticking, 0.5, t - 0.5 * t ** 2)
    return make_run(["x", "x_dot"], 1, 1, np.column_stack([x, np.gradient(x, t)]),
                    flow=np.where(sticking, 1, 2).astype(np.int64),
                    flow_names=["open", "floor_stick", "floor_slip_pos", "floor_slip_neg"], jump_names=["floor_stop"],
                    multiplier_names=["normal", "friction"],
                    multipliers=np.column_stack([np.full(n, 9.81), np.where(sticking, 0.25, np.nan)]),
                    residual_position=np.zeros((n, 1)), residual_velocity=np.zeros((n, 2)),
                    contact_names=["floor"], contact_rows=[0], contact_stick_rows=[1], contact_mu=[0.5],
                    slip_speeds=np.where(sticking, 0.0, 1.0 - t)[:, None])


def inputs_run(n=40, changing=True) -> Run:
    """Inputs u (a ramp, or constant) and v (constant)."""
    t = np.linspace(0.0, 2.0, n)
    u = 0.5 * t if changing else np.full(n, 0.5)
    return make_run(["q", "q_dot"], 1, 1, np.column_stack([t, np.ones(n)]), input_names=["u", "v"],
                    input_values=np.column_stack([u, np.full(n, -2.0)]))


def hybrid_run(n=201) -> Run:
    """A planar two-legged stick walker: flows stance1/stance2 swapped by strike2 at t = 0.5 and
    strike1 at t = 1.2, strike2 again at 1.7; discrete fx (stance foot) and a step count. Frames:
    hip (parent world), foot1 and foot2 (parent hip; the stance foot on the ground y = 0), marker
    (parent 'knee', not logged)."""
    t = np.linspace(0.0, 2.0, n)
    event_times = np.array([0.5, 1.2, 1.7])
    flow = np.searchsorted(event_times, t, side="right") % 2
    steps = np.searchsorted(event_times, t, side="right").astype(float)
    fx = 0.4 * steps
    hip = np.stack([0.4 * t, 1.0 - 0.02 * np.sin(np.pi * t) ** 2, 0 * t], axis=1)
    swing = np.stack([0.8 * t, 0.05 * np.abs(np.sin(2 * np.pi * t)), 0 * t], axis=1)
    stance = np.stack([fx, 0 * t, 0 * t], axis=1)
    foot1 = np.where((flow == 0)[:, None], stance, swing)
    foot2 = np.where((flow == 1)[:, None], stance, swing)
    state = np.column_stack([hip[:, 0], hip[:, 1], np.gradient(hip[:, 0], t), np.gradient(hip[:, 1], t)])
    discrete = np.column_stack([fx, steps])
    k = np.searchsorted(t, event_times)
    events = {"time": event_times, "jump": np.array([0, 1, 0], np.int32),
              "from_flow": np.array([0, 1, 0], np.int32), "to_flow": np.array([1, 0, 1], np.int32),
              "state_before": state[k - 1], "state_after": state[k], "discrete_after": discrete[k]}
    return make_run(["x", "y", "x_dot", "y_dot"], 2, 2, state,
                    frames={"hip": hip, "foot1": foot1, "foot2": foot2, "marker": hip + [0.1, -0.5, 0.0]},
                    flow=flow, flow_names=["stance1", "stance2"], discrete_names=["fx", "steps"], discrete=discrete,
                    jump_names=["strike2", "strike1"], events=events,
                    frame_parents={"hip": "world", "foot1": "hip", "foot2": "hip", "marker": "knee"},
                    display={"ground": {"axis": 1, "height": 0.0}})
