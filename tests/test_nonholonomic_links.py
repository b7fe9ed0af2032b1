"""The general nonholonomic link (ANDY eq. 4): a velocity given as an expression
of speeds and coordinates, with the position as a signal.

The Chaplygin sleigh: a knife edge that cannot slip sideways, heading th, COM a
distance a ahead of the edge. Its contact point moves with velocity
u (cos th, sin th, 0), u a quasi-velocity. Its equations of motion are known in
closed form (Neimark & Fufaev; Bloch, Nonholonomic Mechanics, section 1.7):

    du/dt = a w^2,    (I + m a^2) dw/dt = -m a u w,    w = dth/dt,

and are integrated here with scipy, independently of andyc.
"""

import numpy as np
from scipy.integrate import solve_ivp

import andyc

SLEIGH = """\
name: sleigh
parameters: {m: 2.0, a: 0.3, I: 0.05}
coordinates:
  th: {velocity: 1.5}
speeds:
  u: {initial: 0.4}          # forward speed of the knife edge
frames:
  - {name: edge, parent: world, nonholonomic: {velocity: ["u*cos(th)", "u*sin(th)", 0], in: parent}}
  - {name: heading, parent: edge, revolute: th}
bodies:
  - {name: sled, frame: heading, mass: m, com: [a, 0, 0], inertia: [0.03, 0.03, I]}
"""


def reference(t_end, m=2.0, a=0.3, I=0.05, u0=0.4, w0=1.5):
    def f(t, y):
        u, w, th, x, y_ = y
        return [a * w * w, -m * a * u * w / (I + m * a * a), w, u * np.cos(th), u * np.sin(th)]

    return solve_ivp(f, (0, t_end), [u0, w0, 0.0, 0.0, 0.0], method="DOP853", rtol=1e-12, atol=1e-12,
                     dense_output=True)


def test_chaplygin_sleigh_matches_its_equations_of_motion(tmp_path, build_dir):
    path = tmp_path / "sleigh.yaml"
    path.write_text(SLEIGH)
    model, _ = andyc.compile_model(path, build_dir)
    assert model.state_names == ("th", "th_dot", "u", "edge_x", "edge_y", "edge_z")
    run = andyc.simulate(model, 10.0, dt=1e-3, every=10)
    assert run.finished
    ref = reference(10.0).sol(run.time)
    for name, row in (("u", 0), ("th_dot", 1), ("th", 2), ("edge_x", 3), ("edge_y", 4)):
        np.testing.assert_allclose(run.column(name), ref[row], atol=1e-9, err_msg=name)
    # The edge never slips sideways, and the sleigh ends up going straight.
    assert np.max(abs(run.column("edge_z"))) == 0.0
    assert abs(run.column("th_dot")[-1]) < 0.1 * 1.5
    rel = np.max(abs(run.energy - run.energy[0])) / run.energy[0]
    assert rel < 1e-10
