"""Frame rotations in runs: each logged frame's orientation (own axes -> world) as a unit quaternion
w, x, y, z per sample, generated from the symbolic rotations like the origins; in the Run, the HDF5 and
CSV run files, and the module's frame_rotations. Checked against rotations written by hand."""

import h5py
import numpy as np

import andyc
from andyc.runtime.run import unit_quaternions
from andyc.runtime.runfiles import read_h5


def _about_z(angle):
    """The unit quaternion of a rotation by `angle` about z, (N, 4): (cos a/2, 0, 0, sin a/2)."""
    return np.stack([np.cos(angle / 2), 0 * angle, 0 * angle, np.sin(angle / 2)], axis=1)


def _same_rotation(q, expected, tol=1e-12):
    """q and expected (N, 4) are the same rotations sample by sample: equal up to one sign per sample."""
    sign = np.where(np.einsum("ij,ij->i", q, expected) < 0, -1.0, 1.0)
    return np.max(np.abs(q - sign[:, None] * expected)) <= tol


def _matrix(q):
    """The rotation matrix of the unit quaternion w, x, y, z (the textbook formula)."""
    w, x, y, z = q
    return np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
                     [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
                     [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)]])


def test_double_pendulum_links_turn_about_z_by_q1_and_q1_plus_q2(compiled, tmp_path):
    run = andyc.simulate(compiled("double_pendulum"), 3.0, dt=1e-3, every=10, frames="all")
    q1, q2 = run.column("q1"), run.column("q2")
    assert set(run.frame_rotations) == {"upper", "elbow", "lower", "tip"}
    for name, angle in (("upper", q1), ("elbow", q1), ("lower", q1 + q2), ("tip", q1 + q2)):
        assert run.frame_rotations[name].shape == (len(run.time), 4)
        assert _same_rotation(run.frame_rotations[name], _about_z(angle)), name
    # a logged rotation is continuous in time: no sample flips the sign of the one before
    for q in run.frame_rotations.values():
        assert np.all(np.einsum("ij,ij->i", q[1:], q[:-1]) > 0)
    # the run files carry them; a run file from before rotations were logged still reads, without them
    run.save(tmp_path / "run.h5")
    run.save(tmp_path / "run.csv")
    back = read_h5(tmp_path / "run.h5")
    assert all(np.array_equal(back.frame_rotations[n], q) for n, q in run.frame_rotations.items())
    lines = [ln for ln in (tmp_path / "run.csv").read_text().splitlines() if not ln.startswith("#")]
    columns = lines[0].split(",")
    table = np.loadtxt(lines[1:], delimiter=",")
    for k, axis in enumerate("wxyz"):
        assert np.array_equal(table[:, columns.index(f"lower.q{axis}")], run.frame_rotations["lower"][:, k])
    with h5py.File(tmp_path / "run.h5", "a") as f:
        del f["frame_rotations"]
    old = read_h5(tmp_path / "run.h5")
    assert old.frame_rotations == {} and set(old.frames) == set(run.frames)


def test_floating_body_rotation_is_its_quaternion_state(compiled):
    """A floating frame's rotation is the quaternion its state integrates (normalized: RK4 drifts off |q| = 1),
    and the module's frame_rotations is that quaternion's matrix."""
    model = compiled("free_body")
    run = andyc.simulate(model, 2.0, dt=1e-3, every=50, frames="all")
    names = [f"block_{c}" for c in ("qw", "qx", "qy", "qz")]
    state = np.stack([run.column(n) for n in names if n in run.state_names], axis=1)
    assert state.shape[1] == 4, run.state_names
    state /= np.linalg.norm(state, axis=1)[:, None]
    assert _same_rotation(run.frame_rotations["block"], state)
    assert np.allclose(np.linalg.norm(run.frame_rotations["block"], axis=1), 1.0, rtol=0, atol=1e-14)
    module, r = model.module, len(run.time) // 2
    x, u, d = run.state[r], run.input_values[r], run.discrete[r]
    p = np.array(list(run.parameters.values()))
    R = module.frame_rotations(run.time[r], x, u, p, d)[module.FRAMES.index("block")]
    assert np.max(np.abs(R - _matrix(state[r]))) <= 1e-12


def test_unit_quaternions_of_half_turns_and_beyond():
    """Rotations about an axis by angles through and past pi: SciPy's conversion, then the sign of each sample
    taken nearest the one before: the quaternion (cos a/2, sin a/2 n) continued past a = pi, not folded back."""
    angle = np.linspace(0.0, 4 * np.pi, 401)
    n = np.array([1.0, 2.0, 2.0]) / 3.0
    q = np.concatenate([np.cos(angle / 2)[:, None], np.sin(angle / 2)[:, None] * n], axis=1)
    R = np.array([_matrix(s) for s in q])
    assert np.max(np.abs(unit_quaternions(R) - q)) <= 1e-12
    assert unit_quaternions(np.zeros((0, 3, 3))).shape == (0, 4)
