"""The command line, as a user runs it: exit codes, files written, messages."""

import h5py
import pytest

import andyc
from tests.support import MODELS
from tests.support.cli import andyc_cli, run_python


def test_version():
    proc = andyc_cli("--version")
    assert proc.returncode == 0 and andyc.__version__ in proc.stdout


def test_build_then_up_to_date(tmp_path):
    first = andyc_cli("build", MODELS / "double_pendulum.yaml", "--build-dir", tmp_path)
    assert first.returncode == 0, first.stderr
    assert "built; derive" in first.stdout and "operations" in first.stdout
    assert (tmp_path / "double_pendulum" / "double_pendulum.py").exists()
    second = andyc_cli("build", MODELS / "double_pendulum.yaml", "--build-dir", tmp_path)
    assert "up to date" in second.stdout


def test_sim_writes_h5_and_csv_and_plot_draws_them(tmp_path, shipped_build):
    h5, csv, png = tmp_path / "run.h5", tmp_path / "run.csv", tmp_path / "run.png"
    proc = andyc_cli("sim", MODELS / "double_pendulum.yaml", "--t-end", 2, "--dt", 1e-3, "--every", 10,
                     "--set", "m2=0.7", "--frames", "tip", "--out", h5, "--out", csv, "--build-dir", shipped_build)
    assert proc.returncode == 0, proc.stderr
    assert "2000 steps" in proc.stdout and "energy" in proc.stdout
    with h5py.File(h5) as f:
        assert f["time"].shape == (201,)
        assert list(f["frames"]) == ["tip"]
        assert '"m2": 0.7' in f.attrs["parameters"]
    assert csv.read_text().startswith("# model: double_pendulum")
    proc = andyc_cli("plot", h5, "-o", png)
    assert proc.returncode == 0, proc.stderr
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n" and png.stat().st_size > 10_000


@pytest.mark.parametrize("args, message", [
    (["--set", "nope=1"], "unknown parameter 'nope'"),
    (["--set", "m2"], "'m2' is not NAME=NUMBER"),
    (["--method", "euler"], "'euler' is not one of"),
    (["--frames", "hand"], "unknown frame(s) hand"),
    (["--out", "run.txt"], "unknown run file type '.txt'"),
])
def test_sim_usage_errors_exit_2_with_a_message(args, message, shipped_build, tmp_path):
    proc = andyc_cli("sim", MODELS / "double_pendulum.yaml", "--t-end", 0.01, "--build-dir", shipped_build, *args, cwd=tmp_path)
    assert proc.returncode == 2
    assert message in proc.stderr and "Traceback" not in proc.stderr


@pytest.mark.parametrize("args", [["--version"], ["check", str(MODELS / "double_pendulum.yaml")]])
def test_version_and_check_import_neither_numba_nor_scipy_nor_matplotlib(args):
    """Start-up: these commands need neither the compiler nor the integrators nor the plots."""
    code = ("import sys\nfrom andyc.cli import main\ntry:\n    main(sys.argv[1:])\nexcept SystemExit as exc:\n"
            "    code = exc.code\nprint(sorted(m for m in ('numba', 'scipy', 'matplotlib', 'h5py') if m in sys.modules))\n"
            "sys.exit(code)\n")
    proc = run_python(code, *args)
    assert proc.returncode == 0, proc.stderr
    assert proc.stdout.strip().splitlines()[-1] == "[]"
