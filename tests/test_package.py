"""andyc as a package: a wheel built from this tree installs and works without the tree (issue 19).

The wheel is installed into a new virtual environment. So that the test needs no network, that
environment finds andyc's dependencies in the test environment's site-packages through a .pth line;
a .pth line adds a folder without running the .pth files in it, so the editable install of this tree
that lives there is not seen, and the andyc that runs is the wheel's.
"""

import subprocess
import sys
import sysconfig
import venv
from pathlib import Path

import pytest

from tests.support import MODELS, ROOT


@pytest.fixture(scope="module")
def installed(tmp_path_factory):
    """(the new environment's bin folder, a work folder outside the source tree)."""
    top = tmp_path_factory.mktemp("package")
    wheels = top / "wheels"
    build = subprocess.run([sys.executable, "-m", "pip", "wheel", "--no-deps", "--no-build-isolation", "-q",
                            "-w", str(wheels), str(ROOT)], capture_output=True, text=True, cwd=top)
    assert build.returncode == 0, build.stderr
    wheel = next(wheels.glob("andyc-*.whl"))
    env = top / "env"
    venv.create(env, with_pip=False)
    bin_dir = env / "bin"
    purelib = subprocess.run([str(bin_dir / "python"), "-c", "import sysconfig; print(sysconfig.get_path('purelib'))"],
                             capture_output=True, text=True, check=True).stdout.strip()
    Path(purelib, "test_environment.pth").write_text(sysconfig.get_path("purelib") + "\n")
    install = subprocess.run([sys.executable, "-m", "pip", "--python", str(bin_dir / "python"), "install", "-q",
                              "--no-deps", "--no-index", str(wheel)], capture_output=True, text=True, cwd=top)
    assert install.returncode == 0, install.stderr
    work = top / "work"
    work.mkdir()
    (work / "pendulum.yaml").write_text((MODELS / "double_pendulum.yaml").read_text())
    return bin_dir, work


def test_the_wheel_carries_the_templates_the_schema_and_the_numerics(installed):
    bin_dir, work = installed
    where = subprocess.run([str(bin_dir / "python"), "-c", "import andyc, pathlib; p = pathlib.Path(andyc.__file__)"
                            ".parent; print(p); print(sorted(x.name for x in (p / 'templates').glob('*.*'))); "
                            "print(sorted(x.name for x in (p / 'schemas').glob('*.json'))); "
                            "print(sorted(x.name for x in (p / 'numerics').glob('*.py')))"],
                           capture_output=True, text=True, cwd=work)
    assert where.returncode == 0, where.stderr
    folder, templates, schema, numerics = where.stdout.splitlines()
    assert "site-packages" in folder and not folder.startswith(str(ROOT))
    # Every template and every file of the algorithms every build copies (andyc/numerics), as in the tree.
    assert templates == str(sorted(x.name for x in (ROOT / "andyc" / "templates").glob("*.*")))
    assert schema == str(sorted(x.name for x in (ROOT / "andyc" / "schemas").glob("*.json")))   # model, --format json
    assert numerics == str(sorted(x.name for x in (ROOT / "andyc" / "numerics").glob("*.py")))
    assert "module.py.j2" in templates and "integrator.py" in numerics and "andyc-output.schema.json" in schema


def test_check_build_and_sim_run_from_the_wheel_in_another_folder(installed):
    bin_dir, work = installed
    andyc = str(bin_dir / "andyc")
    out = {}
    for args in (["check", "pendulum.yaml"], ["build", "pendulum.yaml"],
                 ["sim", "pendulum.yaml", "--t-end", "0.1", "--out", "run.h5"], ["test", "pendulum.yaml"]):
        proc = subprocess.run([andyc, *args], capture_output=True, text=True, cwd=work)
        assert proc.returncode == 0, (args, proc.stderr)
        out[args[0]] = proc.stdout
    assert (work / "build" / "double_pendulum" / "double_pendulum.py").is_file()
    assert "100 steps" in out["sim"] and (work / "run.h5").is_file()
    assert "all hold" in out["test"]            # the model's expectations, run from the installed package
