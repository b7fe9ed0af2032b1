"""The models of issue 27, generated: a planar chain of n links and the IFToMM A02 N-four-bar.

Planar chain (n links): link i turns by q_i about z relative to link i-1 (link 1 about the world's z at
the origin); each link is a uniform rod of length L = 1 m and mass m = 1 kg along its x axis (COM at
L/2, inertia m L^2 / 12 about y and z), gravity 9.81 m/s^2 along -y. Written as andyc YAML, as an MJCF
string (MuJoCo: hinge joints, each rod's mass and inertia given explicitly, 1e-9 kg m^2 about
its own x axis, which a motion about z never turns)
and as a Pinocchio model built joint by joint (JointModelRZ).

IFToMM A02, the N-four-bar (https://www.iftomm-multibody.org/benchmark/problem/N-four-bar_mechanism/):
N + 1 vertical cranks pinned to the ground at x = 0, L, ..., N L, their tips joined by N horizontal
couplers; every bar a uniform rod of L = 1 m, m = 1 kg; gravity 9.81 m/s^2 along -y; at t = 0 the
cranks stand vertical (theta = pi/2) and the tips move at 1 m/s along +x; 20 s. Here crank k turns by
c_k about z at (k L, 0); coupler k (k = 1 .. N) turns by b_k relative to crank k-1 and its far end is
held on crank k's tip by two holonomic rows: 2N + 1 speeds, 2N rows.

The reduced exact motion: all cranks keep one angle theta (the couplers translate, parallel to the
ground), a 1-DOF system with

    kinetic energy   T = 1/2 J theta'^2,   J = m L^2 ((N + 1) / 3 + N)
    potential        V = m g L ((N + 1) / 2 + N) sin(theta)

so J theta'' = -m g L ((N + 1) / 2 + N) cos(theta), theta(0) = pi/2, theta'(0) = -1/L (tip at
(L cos theta, L sin theta) moving along +x). B0, the first crank's tip, is (L cos theta, L sin theta).
`reduced_b0` integrates this with DOP853 at rtol = atol = 1e-13.
"""

from __future__ import annotations

import numpy as np
from scipy.integrate import solve_ivp

L, MASS, GRAVITY = 1.0, 1.0, 9.81


def planar_chain_yaml(n: int) -> str:
    """The planar chain of n links as an andyc model, started at rest, stretched out at 0.3 rad per joint."""
    lines = [f"name: chain{n}", f"description: planar chain of {n} uniform rods (issue 27 benchmark)",
             f"parameters: {{L: {L}, m: {MASS}, g: {GRAVITY}}}", "gravity: [0, -g, 0]", "coordinates:"]
    lines += [f"  q{i}: {{initial: 0.3, velocity: 0}}" for i in range(1, n + 1)]
    lines.append("frames:")
    for i in range(1, n + 1):
        parent = "world" if i == 1 else f"tip{i - 1}"
        lines.append(f"  - {{name: link{i}, parent: {parent}, revolute: q{i}}}")
        lines.append(f"  - {{name: tip{i}, parent: link{i}, translation: [L, 0, 0]}}")
    lines.append("bodies:")
    lines += [f"  - {{name: rod{i}, frame: link{i}, mass: m, com: [L/2, 0, 0], inertia: [0, m*L**2/12, m*L**2/12]}}"
              for i in range(1, n + 1)]
    return "\n".join(lines) + "\n"


def planar_chain_mjcf(n: int) -> str:
    """The same chain for MuJoCo: hinge joints about z, each rod's mass and inertia given explicitly
    (`inertial`), no contacts, no joint damping or armature; RK4 at dt = 1e-3."""
    inertia = f"1e-9 {MASS * L ** 2 / 12!r} {MASS * L ** 2 / 12!r}"     # MuJoCo wants every axis > 0
    body = ""
    for i in range(n, 0, -1):
        pos = "0 0 0" if i == 1 else f"{L} 0 0"
        body = (f'<body name="link{i}" pos="{pos}"><joint name="q{i}" type="hinge" axis="0 0 1"/>'
                f'<inertial pos="{L / 2} 0 0" mass="{MASS}" diaginertia="{inertia}"/>{body}</body>')
    return (f'<mujoco model="chain{n}"><option gravity="0 {-GRAVITY} 0" timestep="0.001" integrator="RK4">'
            '<flag contact="disable"/></option>'
            f'<worldbody>{body}</worldbody></mujoco>')


def planar_chain_pinocchio(n: int):
    """The same chain as a Pinocchio model (JointModelRZ joints, rods' inertias about their COM)."""
    import pinocchio as pin
    model = pin.Model()
    model.gravity.linear = np.array([0.0, -GRAVITY, 0.0])
    parent = 0
    for i in range(1, n + 1):
        placement = pin.SE3(np.eye(3), np.array([0.0 if i == 1 else L, 0.0, 0.0]))
        parent = model.addJoint(parent, pin.JointModelRZ(), placement, f"q{i}")
        inertia = np.diag([0.0, MASS * L ** 2 / 12, MASS * L ** 2 / 12])
        model.appendBodyToJoint(parent, pin.Inertia(MASS, np.array([L / 2, 0.0, 0.0]), inertia), pin.SE3.Identity())
    return model


def nfourbar_yaml(n: int) -> str:
    """The IFToMM A02 N-four-bar as an andyc model (projection method, energy correction)."""
    lines = [f"name: nfourbar{n}", f"description: IFToMM A02 N-four-bar, N = {n} (issue 27 benchmark)",
             f"parameters: {{L: {L}, m: {MASS}, g: {GRAVITY}}}", "gravity: [0, -g, 0]",
             "conserves_energy: true", "coordinates:"]
    for k in range(n + 1):
        lines.append(f"  c{k}: {{initial: pi/2, velocity: -1}}")
        if k < n:
            lines.append(f"  b{k + 1}: {{initial: -pi/2, velocity: 1}}")     # coupler horizontal: c + b = 0
    lines.append("frames:")
    for k in range(n + 1):
        lines.append(f"  - {{name: crank{k}, parent: world, translation: [{k}*L, 0, 0], revolute: c{k}}}")
        lines.append(f"  - {{name: tip{k}, parent: crank{k}, translation: [L, 0, 0]}}")
    for k in range(1, n + 1):
        lines.append(f"  - {{name: coupler{k}, parent: tip{k - 1}, revolute: b{k}}}")
        lines.append(f"  - {{name: coupler{k}_end, parent: coupler{k}, translation: [L, 0, 0]}}")
    lines.append("bodies:")
    rod = "mass: m, com: [L/2, 0, 0], inertia: [0, m*L**2/12, m*L**2/12]"
    lines += [f"  - {{name: crank{k}_rod, frame: crank{k}, {rod}}}" for k in range(n + 1)]
    lines += [f"  - {{name: coupler{k}_rod, frame: coupler{k}, {rod}}}" for k in range(1, n + 1)]
    lines.append("constraints:")
    for k in range(1, n + 1):
        lines.append(f"  - {{name: loop{k}, holonomic: [coupler{k}_end.x - tip{k}.x, coupler{k}_end.y - tip{k}.y]}}")
    lines.append("simulate: {method: projection}")
    return "\n".join(lines) + "\n"


def reduced_b0(n: int, times) -> np.ndarray:
    """B0 = (x, y) of the first crank's tip at `times` from the reduced 1-DOF motion (module docstring)."""
    inertia = MASS * L ** 2 * ((n + 1) / 3 + n)
    moment = MASS * GRAVITY * L * ((n + 1) / 2 + n)
    sol = solve_ivp(lambda t, y: [y[1], -moment / inertia * np.cos(y[0])], (0.0, max(times)),
                    [np.pi / 2, -1.0 / L], method="DOP853", rtol=1e-13, atol=1e-13, t_eval=sorted(times),
                    dense_output=False)
    theta = dict(zip(sol.t, sol.y[0]))
    return np.array([[L * np.cos(theta[t]), L * np.sin(theta[t])] for t in times])
