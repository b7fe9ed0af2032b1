"""A build is reused by meaning (issue 19): comments, key order, whitespace, parameter defaults and
initial values leave the compiled equations (and Numba's cache of them) untouched, and the new
values are used; an edit of an equation rebuilds; two models of one name never share a build."""

import os
import shutil

import numpy as np
import pytest

import andyc
from andyc.codegen.buildfiles import equations_path, written_constant
from andyc.outputs import OutputError
from andyc.pipeline import unchanged
from andyc.runtime.compiled import compilations
from andyc.spec.meaning import meaning_sha256
from tests.support.cli import run_python

PENDULUM = """\
name: cached_pendulum
description: A point mass on a massless link.
parameters:
  L: 1.0
  m: 1.0
  g: 9.81
coordinates:
  theta: {initial: 0.5}
gravity: [0, -g, 0]
frames:
  - {name: link, parent: world, revolute: theta, axis: z}
  - {name: tip, parent: link, translation: [L, 0, 0]}
bodies:
  - {name: bob, frame: tip, mass: m}
"""

# The same model: comments, another order of the keys (not of the parameters: that is their index in p) and layout, other defaults, another initial value and
# description; the equations are the same.
EDITED = """\
# a comment that was not there
name: cached_pendulum
description: "Edited: the same pendulum."
coordinates:
  theta:
    initial: 0.25 + 0.5      # another initial value
gravity: [0, -g, 0]
frames:
  - {name: link, parent: world, revolute: theta, axis: z}
  - {parent: link, name: tip, translation: [L, 0, 0]}
bodies: [{name: bob, frame: tip, mass: m}]
parameters: {L: 1.5, m: 2.0, g: 9.81}
"""


def _stamps(folder):
    return {p.name: p.stat().st_mtime_ns for p in folder.rglob("*") if p.is_file() and p.name.endswith(
        ("_equations.py", ".nbi", ".nbc", "_leaves.c", ".so"))}


def _leaves_compiled(model, result) -> bool:
    """Whether this build compiled the model's leaves: by the C compiler (its library, andyc.codegen.c_leaves),
    or by Numba."""
    library = model.module.EQUATIONS.C_LIBRARY
    if library is not None:
        return (model.path.parent / library).is_file() and result.timings.get("cc", 0.0) > 0
    return result.compiled > 0


def test_runtime_data_edits_reuse_the_build_and_an_equation_edit_rebuilds(tmp_path):
    # A long path: the build's constants stay one line each however long (written_constant reads lines).
    path, build = tmp_path / ("a_folder_with_a_long_name_" * 5) / "pendulum.yaml", tmp_path / "build"
    path.parent.mkdir()
    path.write_text(PENDULUM)
    first, result = andyc.compile_model(path, build)
    assert not result.skipped and _leaves_compiled(first, result)
    folder = result.module_path.parent
    stamps = _stamps(folder)
    assert any(name.endswith((".nbc", ".so")) for name in stamps)

    path.write_text(EDITED)
    edited, again = andyc.compile_model(path, build)
    assert again.skipped and again.compiled == 0 and again.build_key == result.build_key
    assert _stamps(folder) == stamps                      # neither the equations nor Numba's cache touched
    # The new values are what the module and a run use.
    assert list(edited.parameter_defaults) == [1.5, 2.0, 9.81]
    assert edited.module.initial_state()[0] == 0.75
    assert edited.module.DESCRIPTION == "Edited: the same pendulum."
    compiled_before = compilations(edited)
    run = andyc.simulate(edited, 1.0, dt=1e-3)
    assert compilations(edited) == compiled_before        # compile_model compiled (loaded) all that a run needs
    # Against the closed form's invariant: energy m g L sin(theta) + m (L theta')^2 / 2 at the new values.
    theta, omega = run.state[-1]
    energy = 2.0 * 9.81 * 1.5 * np.sin(theta) + 2.0 * (1.5 * omega) ** 2 / 2
    assert abs(energy - 2.0 * 9.81 * 1.5 * np.sin(0.75)) < 1e-6

    path.write_text(EDITED.replace("gravity: [0, -g, 0]", "gravity: [0, -2*g, 0]"))
    remade, rebuilt = andyc.compile_model(path, build)
    assert not rebuilt.skipped and rebuilt.build_key != result.build_key and _leaves_compiled(remade, rebuilt)

    # The same bytes again: the build is found without reading the model, and a warm `andyc sim`
    # imports neither SymPy nor SciPy (nor the schema's and templates' libraries).
    # The model's path is recorded relative to the build (no path of the machine that built it in the module).
    files = written_constant(rebuilt.module_path, "SPEC_FILES")
    assert files == [os.path.relpath(path.resolve(), rebuilt.module_path.parent.resolve())] and not files[0].startswith("/")
    assert unchanged(path, build).build_key == rebuilt.build_key
    script = ("import sys\nfrom andyc.cli import main\ntry:\n"
              f"    main(['sim', {str(path)!r}, '--build-dir', {str(build)!r}, '--t-end', '0.1', '--out', 'run.csv'])\n"
              "except SystemExit as exc:\n    assert exc.code in (0, None), exc.code\n"
              "print(sorted(m for m in ('sympy', 'scipy.integrate', 'jinja2', 'jsonschema') if m in sys.modules))")
    proc = run_python(script, cwd=tmp_path)
    assert proc.returncode == 0, proc.stderr
    assert proc.stdout.splitlines()[-1] == "[]" and (tmp_path / "run.csv").exists()
    path.write_text(path.read_text() + "# one more comment\n")
    assert unchanged(path, build) is None and andyc.build(path, build).skipped   # other bytes: read, not derived


def test_the_meaning_ignores_runtime_data_but_not_an_expression():
    import yaml

    base = yaml.safe_load(PENDULUM)
    assert meaning_sha256(base) == meaning_sha256(yaml.safe_load(EDITED))
    # The order of the parameters is their index in p: it is part of the meaning.
    for edit in ({"inputs": {"F": "sin(t)"}}, {"frames": base["frames"][:1]}, {"gravity": [0, 0, "-g"]},
                 {"parameters": {"g": 9.81, "m": 1.0, "L": 1.0}}):
        assert meaning_sha256({**base, **edit}) != meaning_sha256(base)
    # An input's default is runtime data; an input's expression is an equation.
    assert meaning_sha256({**base, "inputs": {"F": 1.0}}) == meaning_sha256({**base, "inputs": {"F": 2.0}})


def test_two_models_of_one_name_never_share_a_build_folder(tmp_path):
    build = tmp_path / "build"
    first, second = tmp_path / "a.yaml", tmp_path / "b.yaml"
    first.write_text(PENDULUM)
    second.write_text(PENDULUM.replace("mass: m", "mass: 2*m"))
    result = andyc.build(first, build)
    key = written_constant(equations_path(build, "cached_pendulum"), "BUILD_KEY")
    with pytest.raises(OutputError, match=r"holds the build of 'cached_pendulum' from .*a\.yaml.*b\.yaml has the "
                                          r"same name.*--force"):
        andyc.build(second, build)
    assert written_constant(equations_path(build, "cached_pendulum"), "BUILD_KEY") == key == result.build_key
    assert written_constant(result.module_path, "SOURCE_PATH") == os.path.join("..", "..", "a.yaml")
    replaced = andyc.build(second, build, force=True)
    assert replaced.build_key != key
    assert written_constant(result.module_path, "SOURCE_PATH") == os.path.join("..", "..", "b.yaml")


@pytest.mark.parametrize("backend", ["c", "numba"])
def test_a_new_model_compiles_only_its_own_functions(tmp_path, monkeypatch, backend):
    """The algorithms are compiled once for every model (andyc/numerics, cached by content): a model never
    built before compiles its leaves (by the C compiler, or by Numba), and nothing of the integrator,
    projection or solves."""
    monkeypatch.setenv("ANDYC_BACKEND", backend)
    first, second = tmp_path / "a.yaml", tmp_path / "b.yaml"
    first.write_text(PENDULUM)
    second.write_text(PENDULUM.replace("cached_pendulum", "other_pendulum").replace("mass: m", "mass: 3*m"))
    andyc.compile_model(first, tmp_path / "build")
    model, result = andyc.compile_model(second, tmp_path / "build")
    leaves = [name for name, value in vars(model.module.EQUATIONS).items() if hasattr(value, "address")]
    assert sorted(leaves) == ["dynamics", "energy", "frame_poses", "power"]      # what a pendulum needs
    assert (model.module.EQUATIONS.C_LIBRARY is not None) == (backend == "c")
    assert _leaves_compiled(model, result)
    assert result.compiled == (0 if backend == "c" else len(leaves))     # Numba: the leaves, and nothing else
    run = andyc.simulate(model, 0.5, dt=1e-3)
    theta, omega = run.state[-1]        # m g L sin(theta) + m (L theta')^2 / 2 at m = 3, the changed equation
    assert abs(3 * 9.81 * np.sin(theta) + 3 * omega ** 2 / 2 - 3 * 9.81 * np.sin(0.5)) < 1e-6


def test_a_leaf_refuses_an_array_it_would_read_wrongly(compiled):
    """The algorithms call a leaf through its C address (andyc_numerics/model.py `call`), which reads its arrays
    as contiguous: a strided array is a typing error, never a silent misread (SciPy's Radau passes columns)."""
    from numba.core.errors import TypingError

    model = compiled("double_pendulum")
    w = andyc.runtime.compiled.work(model)
    x = np.zeros((model.nx, 2))
    x[:, 0] = model.initial_state(model.parameter_defaults)
    with pytest.raises(TypingError):
        model.numerics.dynamics.rhs_mode_into(model.ref, w.ref, 0.0, x[:, 0], model.input_defaults,
                                              model.parameter_defaults, model.module.DISCRETE_DEFAULTS, 0,
                                              w.xdot, 0)


def test_the_c_leaves_are_compiled_for_this_processor(tmp_path, monkeypatch):
    """The C leaves are compiled for the host's processor (-march=native, andyc/codegen/c_leaves.py), so their
    library is named for it: the build folder on a machine of another processor is not up to date, and its
    build (of the same key) compiles that machine's library beside the first, which stays."""
    from andyc.codegen import c_leaves
    from andyc.numerics import compiler
    from andyc.pipeline import build

    if c_leaves.compiler() is None:
        pytest.skip("no C compiler: the Numba leaves")
    path = tmp_path / "pendulum.yaml"
    path.write_text(PENDULUM)
    result = build(path, tmp_path / "build")
    folder = result.module_path.parent
    here = sorted(p.name for p in folder.glob("*.so"))
    assert here == [compiler.library_file(written_constant(equations_path(tmp_path / "build", "cached_pendulum"),
                                                           "C_LEAVES"))]
    assert compiler.host_cpu() in here[0]
    assert unchanged(path, tmp_path / "build") is not None

    monkeypatch.setattr(compiler, "host_cpu", lambda: "othercpu-00000000")
    assert unchanged(path, tmp_path / "build") is None          # not this processor's library
    again = build(path, tmp_path / "build")
    assert not again.skipped and again.build_key == result.build_key and again.timings["cc"] > 0
    there = sorted(p.name for p in folder.glob("*.so"))
    assert len(there) == 2 and here[0] in there and any("othercpu-00000000" in name for name in there)
    assert build(path, tmp_path / "build").skipped


def test_a_build_moved_with_its_model_is_still_its_build(tmp_path):
    """The build records its model's path relative to itself: a project folder moved (or cloned elsewhere) with
    its builds keeps them; the same build beside another model file of that name is not taken for its build."""
    first = tmp_path / "one"
    (first / "build").mkdir(parents=True)
    (first / "m.yaml").write_text(PENDULUM)
    built = andyc.build(first / "m.yaml", first / "build")
    assert not built.skipped
    moved = tmp_path / "two"
    shutil.copytree(first, moved)
    shutil.rmtree(first)
    found = unchanged(moved / "m.yaml", moved / "build")
    assert found is not None and found.build_key == built.build_key
    (tmp_path / "elsewhere").mkdir()
    (tmp_path / "elsewhere" / "m.yaml").write_text(PENDULUM)
    assert unchanged(tmp_path / "elsewhere" / "m.yaml", moved / "build") is None
