"""Linearization about a steady motion of a nonholonomic flow, and the sweep of its eigenvalues.

The reference is the rolling disk (models/rolling_disk.yaml): its lean about upright straight rolling obeys
lambda^2 = (m g r - (C + m r^2) C W^2 / A) / (A + m r^2), derived by hand in
andyc.independent.closed_forms (Routh; Neimark & Fufaev), so upright rolling is stable for
W > sqrt(A m g r / (C (C + m r^2))) = sqrt(g / (3 r)) for a thin uniform disk.
"""

import csv
import math

import numpy as np
import pytest

import andyc
from andyc.analysis.eigensweep import essential, sweep
from andyc.analysis.linearization import linearize_at
from andyc.independent.closed_forms import rolling_disk_critical_spin, rolling_disk_lean_rate2
from andyc.symbolic.linearize import LinearizeError
from tests.support import MODELS
from tests.support.cli import invoke

DISK = MODELS / "rolling_disk.yaml"


@pytest.fixture(scope="module")
def disk():
    return andyc.derive(andyc.load(DISK))


def _closed(model, spin, **overrides):
    p = {name: float(default) for name, (_, default) in model.spec.parameters.items()} | overrides
    m, r, g = p["m"], p["r"], p["g"]
    return rolling_disk_lean_rate2(m, r, g, m * r * r / 4, m * r * r / 2, spin), p


@pytest.mark.parametrize("spin", [3.0, 20.0])
def test_the_lean_eigenvalues_about_upright_rolling_equal_the_closed_form(disk, spin):
    lin = linearize_at(disk, {"th": 0.0, "phi_dot": spin})
    assert lin.cyclic == ("x", "y", "phi")      # detected: phi appears in the kinematics but cancels
    lam2, p = _closed(disk, spin)
    assert lin.x[5] == pytest.approx(p["r"] * spin, rel=1e-15)     # x_dot completed from the rolling rows
    R, _ = essential(lin.A)
    expected = np.sort_complex(np.array([-1, 1]) * np.sqrt(complex(lam2)))
    np.testing.assert_allclose(np.sort_complex(np.linalg.eigvals(R)), expected, rtol=1e-10, atol=1e-10)
    # every other eigenvalue of the full A is zero (heading, rolling speed, the yaw first integral)
    rest = np.linalg.eigvals(lin.A)
    rest = rest[np.argsort(np.abs(rest))][:3]
    assert np.abs(rest).max() < 1e-6


def test_the_sweep_locates_the_critical_speed_of_upright_rolling(disk, tmp_path):
    """The critical spin from the sweep equals the closed form to 1e-8 (measured ~1e-14), at two radii."""
    for r in (0.05, 0.2):
        sw = sweep(disk, "phi_dot", np.linspace(2.0, 20.0, 7), at={"th": 0.0}, parameters={"r": r})
        _, p = _closed(disk, 0.0, r=r)
        exact = rolling_disk_critical_spin(p["m"], r, p["g"], p["m"] * r * r / 4, p["m"] * r * r / 2)
        assert exact == pytest.approx(math.sqrt(p["g"] / (3 * r)), rel=1e-15)
        assert len(sw.changes) == 1
        change = sw.changes[0]
        assert (change.before, change.after, change.kind) == (1, 0, "real")
        assert change.value == pytest.approx(exact, rel=1e-8)
        assert list(sw.unstable) == [int(v < exact) for v in sw.values]


def test_cli_sweep_prints_writes_and_plots(tmp_path):
    result = invoke("linearize", str(DISK), "--at", "th=0", "--sweep", "phi_dot=4:12:5", "-o", str(tmp_path))
    assert result.exit_code == 0, result.output
    line = next(x for x in result.output.splitlines() if x.startswith("stability changes at phi_dot = "))
    assert float(line.split("= ")[1].split(":")[0]) == pytest.approx(math.sqrt(9.81 / 0.15), rel=1e-8)
    rows = list(csv.reader(open(tmp_path / "rolling_disk_sweep_phi_dot.csv")))
    assert rows[0][:2] == ["phi_dot", "unstable"] and len(rows) == 6
    assert [int(r[1]) for r in rows[1:]] == [1, 1, 1, 0, 0]      # 4, 6, 8 below sqrt(g/(3 r)) = 8.087
    assert (tmp_path / "rolling_disk_sweep_phi_dot.png").stat().st_size > 10_000


@pytest.mark.parametrize("args, message", [
    (["--at", "th=0.1", "--at", "phi_dot=10"],
     "the point is no steady motion of flow 'default': d(th_dot)/dt = "),
    (["--at", "th=0", "--at", "th_dot=1"],
     "th (speed 1) moves but appears in them (cyclic here: x, y, phi); set th_dot=0 with --at"),
    (["--at", "th=0", "--cyclic", "x,psi"],
     "psi is not cyclic in flow 'default' (cyclic coordinates appear in none of its equations; these are: x, y, "
     "phi); leave it out of --cyclic"),
    (["--at", "th=0", "--cyclic", "x,y"], "phi moves in a steady motion but is not cyclic"),
    (["--at", "th=0", "--sweep", "speed=1:2:3"], "nothing named 'speed' to sweep (--sweep); parameters: m, r, g"),
])
def test_cli_steady_motion_errors_say_what_and_how(args, message):
    result = invoke("linearize", str(DISK), *args)
    assert result.exit_code == 1, result.output
    assert message in result.output, result.output
    assert "Traceback" not in result.output


def test_cli_a_malformed_sweep_is_a_usage_error():
    result = invoke("linearize", str(DISK), "--sweep", "phi_dot=4:12")
    assert result.exit_code == 2
    assert "--sweep 'phi_dot=4:12': not NAME=FROM:TO:COUNT" in result.output


def test_a_flow_without_rows_sweeps_too(disk):
    """An unconstrained flow: the cart-pole's upright point is unstable at every pole mass (one positive
    eigenvalue, sqrt of the closed form's A[3, 1]), so nothing changes."""
    model = andyc.derive(andyc.load(MODELS / "cart_pole.yaml"))
    sw = sweep(model, "m", [0.05, 0.1, 0.2], at={"th": 0.0})
    assert list(sw.unstable) == [1, 1, 1] and sw.changes == []
    with pytest.raises(LinearizeError, match="nothing named 'mass' to sweep"):
        sweep(model, "mass", [1.0, 2.0])
