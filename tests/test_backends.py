"""The two backends of a build's leaves, against each other: C (the system's C compiler, andyc.codegen.c_leaves,
the default where there is one) and Numba (ANDYC_BACKEND=numba, or no compiler). The same model built both
ways gives the same mass matrix, forces, energy, constraint terms, frame poses and jump functions at random
states, and the same run, to round-off: the two are independent compilations of one cse'd body."""

import numpy as np
import pytest

import andyc
from tests.support import MODELS

# a chain, a closed loop with rows in a moving frame, a hybrid model with jumps and multipliers in guards,
# a model whose inputs are expressions (its input callback stays Numba's in either backend), and a free body
# (its M has runs of zeros, which the C leaves store by loops, and a lower triangle they copy from locals)
CASES = ["double_pendulum", "swing_bar", "bouncing_ball_contact", "cart_pole", "free_body"]


@pytest.fixture(scope="module")
def both(tmp_path_factory):
    """name -> (C build, Numba build) of each case, compiled once for the module."""
    root = tmp_path_factory.mktemp("backends")
    out = {}
    with pytest.MonkeyPatch.context() as mp:
        for name in CASES:
            mp.delenv("ANDYC_BACKEND", raising=False)
            c = andyc.compile_model(MODELS / f"{name}.yaml", root / "c")[0]
            mp.setenv("ANDYC_BACKEND", "numba")
            numba = andyc.compile_model(MODELS / f"{name}.yaml", root / "numba")[0]
            out[name] = (c, numba)
    return out


def _states(model, n, seed):
    rng = np.random.default_rng(seed)
    x0 = model.initial_state(model.parameter_defaults)
    return [x0 + rng.normal(scale=0.3, size=x0.shape) for _ in range(n)]


def test_the_builds_are_of_each_backend(both):
    for c, numba in both.values():
        assert c.module.EQUATIONS.C_LIBRARY is not None
        assert (c.path.parent / c.module.EQUATIONS.C_LIBRARY).is_file()
        assert not hasattr(c.module.EQUATIONS.dynamics, "cache_hits")      # a C leaf, not a Numba cfunc
        assert numba.module.EQUATIONS.C_LIBRARY is None
        assert hasattr(numba.module.EQUATIONS.dynamics, "cache_hits")


@pytest.mark.parametrize("name", CASES)
def test_leaves_agree_at_random_states(both, name):
    c, numba = both[name]
    a, b = c.module, numba.module
    p = c.parameter_defaults
    for x in _states(c, 5, seed=len(name)):
        t = 0.37
        scale = max(1.0, np.abs(b.mass_matrix(t, x)).max())
        np.testing.assert_allclose(a.mass_matrix(t, x), b.mass_matrix(t, x), rtol=0, atol=1e-13 * scale)
        G_c, G_n = a.generalized_force(t, x), b.generalized_force(t, x)
        np.testing.assert_allclose(G_c, G_n, rtol=0, atol=1e-13 * max(1.0, np.abs(G_n).max()))
        assert a.energy(t, x) == pytest.approx(b.energy(t, x), rel=1e-14, abs=1e-13)
        np.testing.assert_allclose(a.frame_poses(t, x), b.frame_poses(t, x), rtol=0, atol=1e-13)
        if c.nc:
            u, d = c.input_defaults, c.initial_discrete(p)
            out_c = [np.zeros(c.nh), np.zeros(c.nc), np.zeros((c.nc, c.nv)), np.zeros(c.nc)]
            out_n = [np.zeros(c.nh), np.zeros(c.nc), np.zeros((c.nc, c.nv)), np.zeros(c.nc)]
            a.constraints(t, x, u, p, d, *out_c)
            b.constraints(t, x, u, p, d, *out_n)
            for y, z in zip(out_c, out_n):
                np.testing.assert_allclose(y, z, rtol=0, atol=1e-12 * max(1.0, np.abs(z).max(initial=0.0)))
        for k in range(c.nj):
            assert a.guard(k, t, x) == pytest.approx(b.guard(k, t, x), rel=1e-13, abs=1e-13)
            assert a.enabled(k, t, x) == pytest.approx(b.enabled(k, t, x), rel=1e-13, abs=1e-13)


@pytest.mark.parametrize("name", CASES)
def test_runs_agree(both, name):
    c, numba = both[name]
    method = "projection" if c.nc else "rk4"
    run_c = andyc.simulate(c, 1.0, dt=1e-3, method=method, progress=False)
    run_n = andyc.simulate(numba, 1.0, dt=1e-3, method=method, progress=False)
    assert run_c.status == run_n.status
    assert run_c.time.shape == run_n.time.shape
    scale = max(1.0, np.abs(run_n.state).max())
    np.testing.assert_allclose(run_c.state, run_n.state, rtol=0, atol=1e-10 * scale)
    np.testing.assert_array_equal(run_c.flow, run_n.flow)
    for column, values in run_n.events.items():
        if np.asarray(values).dtype.kind == "f":
            np.testing.assert_allclose(run_c.events[column], values, rtol=0, atol=1e-10 * scale)


def test_c_outputs_zero_runs_and_copies(tmp_path):
    """andyc.codegen.c_leaves.c_lines writes the zeros of a body first (a run of at least 4 consecutive
    elements as a loop) and an output that copies another from its value: compiled, the function stores what
    SymPy evaluates each output to, in every element, whatever the array held."""
    import ctypes
    from types import SimpleNamespace

    import sympy as sp

    from andyc.codegen import c_leaves

    cc = c_leaves.compiler()
    if cc is None:
        pytest.skip("no C compiler")
    x0, x1, c0 = sp.symbols("x0 x1 c0", real=True)
    values = {x0: 0.7, x1: -1.3}
    outputs = {0: c0 + 1, 1: sp.Integer(0), 8: sp.sin(x0) * x1, 13: x1}
    outputs.update({i: sp.Integer(0) for i in (2, 3, 4, 5, 6, 7, 11, 12)})  # with M[1], M[10]: 1..7, 10..12
    copies = {9: 0, 10: 1, 14: 8, 15: 13}           # M[9] = M[0] (an expression), M[10] = M[1] (zero), ...
    body = SimpleNamespace(exprs=[("c0", x0 * x1)] + [(f"M[{i}]", e) for i, e in outputs.items()]
                           + [(f"M[{i}]", sp.Symbol(f"M[{j}]")) for i, j in copies.items()])
    lines = c_leaves.c_lines(["x0 = x[0]", "x1 = x[1]"], body, None, 4)
    text = "\n".join(["#include <math.h>", "#include <stdint.h>", "void f(double *x, double *M) {", *lines, "}"])
    assert "for (int64_t _z = 1; _z <= 7; _z++) M[_z] = 0.0;" in text and "M[10] = 0.0;" in text and "= M[" not in text
    source = tmp_path / "f.c"
    source.write_text(text)
    library = ctypes.CDLL(str(c_leaves.compile_library(source, tmp_path, "f_leaves_0", cc)))
    x, M = np.array([0.7, -1.3]), np.full(16, np.nan)
    pointer = ctypes.POINTER(ctypes.c_double)
    library.f(x.ctypes.data_as(pointer), M.ctypes.data_as(pointer))
    expected = {i: float(e.subs(c0, x0 * x1).subs(values)) for i, e in outputs.items()}
    expected.update({i: expected[j] for i, j in copies.items()})
    np.testing.assert_allclose(M, [expected[i] for i in range(16)], rtol=1e-15, atol=0)


def test_a_compiler_without_march_native_compiles_without_it(tmp_path):
    """The C leaves ask for this processor (-march=native, as Numba compiles for the host); a compiler that
    refuses the flag (some clang builds) compiles them without it, rather than the build falling back to Numba."""
    import ctypes
    import os
    import stat

    from andyc.codegen import c_leaves

    cc = c_leaves.compiler()
    if cc is None or os.name != "posix":
        pytest.skip("no C compiler, or no shell to wrap it in")
    wrapper = tmp_path / "cc-without-march"
    wrapper.write_text('#!/bin/sh\nfor a in "$@"; do case "$a" in -march=*) echo "error: unknown argument: $a" >&2; '
                       f'exit 1;; esac; done\nexec {cc} "$@"\n')
    wrapper.chmod(wrapper.stat().st_mode | stat.S_IEXEC)
    source = tmp_path / "f.c"
    source.write_text("double energy(double t) { return 2.0 * t; }\n")
    library = c_leaves.compile_library(source, tmp_path, "f_leaves_0", str(wrapper))
    function = ctypes.CDLL(str(library)).energy
    function.restype, function.argtypes = ctypes.c_double, [ctypes.c_double]
    assert function(1.25) == 2.5
    source.write_text("double energy(double t) { return 2.0 * ; }\n")     # any other error is the compiler's
    with pytest.raises(c_leaves.NoC, match="failed"):
        c_leaves.compile_library(source, tmp_path, "f_leaves_1", str(wrapper))


def test_sines_of_four_or_more_inputs_are_taken_in_one_vector_loop(tmp_path):
    """andyc.codegen.c_leaves.vector_trig: a body with the sines of at least four inputs takes them in one
    `omp simd` loop (so GCC calls libmvec's vector sin on x86-64 Linux), fewer stay scalar calls; compiled,
    every output equals SymPy's value to 4 ulp, whichever way each sine was taken."""
    import ctypes
    import platform
    import subprocess
    import sys
    from types import SimpleNamespace

    import sympy as sp

    from andyc.codegen import c_leaves

    cc = c_leaves.compiler()
    if cc is None:
        pytest.skip("no C compiler")
    q = sp.symbols("q0:6", real=True)
    values = {s: 0.3 + 1.7 * i for i, s in enumerate(q)}
    outputs = [sp.sin(q[i]) * sp.cos(q[i]) + sp.sin(q[i] + q[5]) for i in range(5)] + [sp.cos(q[0] - q[1])]
    body = SimpleNamespace(exprs=[(f"M[{i}]", e) for i, e in enumerate(outputs)])
    unpack = [f"{s} = x[{i}]" for i, s in enumerate(q)]
    lines = c_leaves.c_lines(unpack, body, None, 4)
    text = "\n".join(lines)
    assert text.count("#pragma omp simd") == 2                 # sin of 10 arguments, cos of 6
    assert "double _sin[10]" in text and "double _cos[6]" in text
    assert "sin(q0)" not in text and "cos(q0 - q1)" not in text

    few = SimpleNamespace(exprs=[("M[0]", sp.sin(q[0]) + sp.cos(q[1]))])
    assert "omp" not in "\n".join(c_leaves.c_lines(unpack, few, None, 4))

    source = tmp_path / "f.c"
    source.write_text(c_leaves.render("f", [{"name": "f", "args": "x, M", "c": lines}]))
    library_path = c_leaves.compile_library(source, tmp_path, "f_leaves_0", cc)
    x, M = np.array([float(values[s]) for s in q]), np.full(6, np.nan)
    pointer = ctypes.POINTER(ctypes.c_double)
    ctypes.CDLL(str(library_path)).f(x.ctypes.data_as(pointer), M.ctypes.data_as(pointer))
    expected = [float(e.subs(values)) for e in outputs]
    np.testing.assert_allclose(M, expected, rtol=1e-15, atol=1e-15)
    version = subprocess.run([cc, "--version"], capture_output=True, text=True).stdout
    if "Free Software Foundation" in version and sys.platform.startswith("linux") and platform.machine() == "x86_64":
        assert b"_ZGV" in library_path.read_bytes(), "GCC on x86-64 Linux should call libmvec's vector sin"


def test_a_large_source_compiles_in_parts_side_by_side_into_one_library(tmp_path, monkeypatch):
    """andyc.codegen.c_leaves: C of more than PART_BYTES splits into parts (at most MAX_PARTS, the largest leaf
    first into the smallest part), each compiled on its own (`-c -DANDYC_PART=k`) and linked into one library
    whose every function computes what its C says; a small source stays one compilation."""
    import ctypes
    import os
    import stat

    from andyc.codegen import c_leaves

    cc = c_leaves.compiler()
    if cc is None or os.name != "posix":
        pytest.skip("no C compiler, or no shell to wrap it in")
    log = tmp_path / "calls.txt"
    wrapper = tmp_path / "cc-logged"
    wrapper.write_text(f'#!/bin/sh\necho "$@" >> {log}\nexec {cc} "$@"\n')
    wrapper.chmod(wrapper.stat().st_mode | stat.S_IEXEC)
    # five leaves energy_<i>(t) = (i + 1) t, of sizes 5, 1, 1, 1, 1 (padding lines): two parts of equal size
    functions = [{"name": f"energy_{i}", "args": "t", "c": [f"    /* {'x' * 100} */"] * (5 if i == 0 else 1)
                  + [f"    return {i + 1}.0 * t;"]} for i in range(5)]
    monkeypatch.setattr(c_leaves, "signature", lambda name, args: f"double {name}(double t)")
    monkeypatch.setattr(c_leaves, "PART_BYTES", 500)
    assert c_leaves.parts_for(functions) == 2
    text = c_leaves.render("f", functions, 2)
    guards = [line for line in text.splitlines() if line.startswith("#if !defined(ANDYC_PART)")]
    assert guards == [f"#if !defined(ANDYC_PART) || ANDYC_PART == {k}" for k in (0, 1, 1, 1, 1)]
    source = tmp_path / "f.c"
    source.write_text(text)
    library = ctypes.CDLL(str(c_leaves.compile_library(source, tmp_path, "f_leaves_0", str(wrapper))))
    for i in range(5):
        function = getattr(library, f"energy_{i}")
        function.restype, function.argtypes = ctypes.c_double, [ctypes.c_double]
        assert function(1.5) == 1.5 * (i + 1)
    calls = log.read_text().splitlines()
    parts = {next(a for a in call.split() if a.startswith("-DANDYC_PART=")) for call in calls if " -c " in call}
    assert parts == {"-DANDYC_PART=0", "-DANDYC_PART=1"}
    assert any(" -c " not in call and "part0.o" in call and "part1.o" in call for call in calls)     # the link

    log.unlink()
    monkeypatch.setattr(c_leaves, "PART_BYTES", 10_000)
    assert c_leaves.parts_for(functions) == 1
    source.write_text(c_leaves.render("f", functions, 1))
    assert "ANDYC_PART" not in source.read_text()
    c_leaves.compile_library(source, tmp_path, "f_leaves_1", str(wrapper))
    calls = log.read_text().splitlines()
    assert calls and not any(" -c " in call or "ANDYC_PART" in call for call in calls)
