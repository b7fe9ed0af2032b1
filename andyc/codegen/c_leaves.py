"""The leaves in C: the `c` backend of a build.

The same cse'd bodies as the Numba leaves of <name>_equations.py (andyc.codegen.leaves), printed as C99
functions with the C signatures of andyc_numerics/model.py's LEAVES (t a double, k an int64_t, every array a
row-major `double *`), into <name>_leaves.c; the system's C compiler makes <name>_leaves_<key>_<cpu>.so of it
(a large model's in parts, compiled side by side: PART_BYTES), which <name>_equations.py loads (andyc_numerics/model.py: c_leaves). The algorithms take a leaf by its C
address either way, so they compile once for both backends.

Why a second backend: Numba types and optimizes a leaf at about a millisecond per operation, and more than
linearly as a leaf grows (issue 27's N-four-bar: 27 s at N = 10, 6 min at N = 20), where a C compiler takes
a fraction of that; and a warm run then loads no leaf from Numba's cache. A model whose expressions have
no C (a function SymPy's C printer does not know), or a machine without a C compiler, gets the Numba leaves.

Names cannot break out: every local of a leaf is a generated identifier (q_..., p_..., c12, f3_...: see
andyc.symbolic), and no text of the model file reaches the C source but through them.
"""

from __future__ import annotations

import concurrent.futures
import functools
import os
import platform
import re
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

from sympy import S, Symbol, cos, default_sort_key, sin
from sympy.printing.c import C99CodePrinter

from andyc.codegen.printer import Unwrapped, finite_literal
from andyc.numerics.layout import RETURNS

# What the compiler is asked for: position-independent code for a shared library; no contraction of a*b + c
# into a fused multiply-add, so that the C leaves round as the Numba ones do (results equal to ~1e-15).
FLAGS = ("-O2", "-fPIC", "-shared", "-ffp-contract=off", "-fno-math-errno")
# ... and for this machine's processor, as Numba compiles its leaves (for the host CPU). On x86-64 this is what
# made the C leaves slower than Numba's: the baseline's SSE2 has two-operand arithmetic only, so a leaf's long
# straight line of products needs a register copy for every third instruction (the swing bar's dynamics: 1113
# instructions, 174 of them movapd) where AVX's three-operand form needs none (873): 9 % of the swing bar's RK4
# step. The library is then keyed by the processor (andyc.numerics.compiler.library_file). A compiler that
# does not know the flag compiles without it.
NATIVE = ("-march=native",)
# ... and, with GCC on x86-64 Linux, glibc's vector math (libmvec): the sines and cosines of a leaf's coordinates are
# taken in one loop (vector_trig), which GCC calls libmvec's 2-, 4- or 8-wide sin and cos for. A planar chain of
# 16 links spent a quarter of its RK4 step in 64 scalar sincos calls, which take 200 ns per 16 angles on this
# project's machine against 50 ns for the vector loop; libmvec rounds to within 4 ulp (scalar sin: 1 ulp), so the
# leaves stay equal to the Numba ones to ~1e-15. `-z defs` makes a vector function libmvec lacks a build error,
# not a failure to load; a system without libmvec compiles without these flags.
VECTOR = ("-fopenmp-simd", "-DANDYC_VECTOR_MATH", "-Wl,-z,defs")
VECTOR_LIBS = ("-lmvec",)
VECTOR_LEAST = 4        # the fewest angles worth a vector loop: 2 or 3 cost as much as scalar sincos calls
# A large model's leaves are compiled in parts, side by side on the processors this process may use: one part per
# PART_BYTES of C, at most MAX_PARTS (the parts depend on the source alone, not on the machine, so that a build's
# files are the same everywhere). A compiler per part also bounds the memory by the part's: GCC's time and memory
# on a leaf grow faster than its size (register allocation: a third of g1's 40 s).
PART_BYTES = 200_000
MAX_PARTS = 4


class NoC(Exception):
    """The model's leaves cannot be written in C (the reason); the build uses the Numba leaves."""


class _Printer(Unwrapped, C99CodePrinter):
    """C99 printer: every number a double literal (no integer division), unknown functions refused."""

    def _print_Rational(self, expr):
        return finite_literal(expr)

    def _print_Integer(self, expr):
        return finite_literal(expr)

    def _print_Float(self, expr):
        return finite_literal(expr)

    def _print_Pow(self, expr):
        """Small integer powers as products, in the order of Numba's integer power (square and multiply),
        so that both backends round alike; x**0.5 as sqrt."""
        base, n = expr.base, expr.exp
        if n.is_Integer and 0 < abs(int(n)) <= 16:
            b, k, factors = f"({self._print(base)})", abs(int(n)), []
            while k:
                if k & 1:
                    factors.append(b)
                k >>= 1
                if k:
                    b = f"({b}*{b})"
            product = "*".join(factors) if len(factors) > 1 else factors[0]
            return product if int(n) > 0 else f"(1.0/({product}))"
        return super()._print_Pow(expr)


_PRINTER = _Printer({"strict": True})     # one for every expression: making one costs more than most prints


def to_c(expr) -> str:
    if expr is S.Zero:          # what the printer gives (see printer.to_code)
        return "0.0"
    try:
        return _PRINTER.doprint(expr)
    except Exception as exc:        # SymPy raises PrintMethodNotImplementedError (or others) for what has no C
        raise NoC(f"no C for {type(expr).__name__}: {exc}") from None


def compiler() -> str | None:
    """The C compiler a build uses: $CC, else cc, gcc or clang on PATH; None when there is none, or when
    ANDYC_BACKEND=numba asks for the Numba leaves (ANDYC_BACKEND=c, or unset: the C compiler if there is one)."""
    if os.environ.get("ANDYC_BACKEND", "c").lower() == "numba":
        return None
    for name in filter(None, (os.environ.get("CC"), "cc", "gcc", "clang")):
        found = shutil.which(name)
        if found:
            return found
    return None


def c_lines(unpack: list[str], body, returns: str | None, indent: int) -> list[str]:
    """A body in C: the inputs it reads, its cse'd locals, then its outputs (array elements) and what it returns.

    Every output is a store of a local or a number, after every local (so no store comes before a read of
    the inputs). Two kinds of output are written otherwise than as they come, to the same numbers: the zeros
    first, a run of consecutive elements of one array as a loop (which the compiler makes a memset); and an
    output that copies another (the mass matrix's lower triangle, `M[j n + i] = M[i n + j]`) from its value,
    held in a local (_out<k>) where it is not a number or a local already, rather than read back from the
    array. Thousands of single stores of zero (the N-four-bar's M and constraint Jacobian at N = 20: 5153), and
    reads of an array after them, made the C compiler's dead-store and alias analysis quadratic in the size of
    a leaf: three quarters of its time at N = 20."""
    pad = " " * indent
    lines = [f"{pad}const double {line};" for line in unpack]
    trig, exprs = vector_trig({line.split(" = ")[0] for line in unpack}, body.exprs, pad)
    lines += trig
    outputs = [(target, expr) for target, expr in exprs if "[" in target]
    given = dict(outputs)
    copied = {str(e) for _, e in outputs if e.is_Symbol and str(e) in given}
    resolved = {t: given[str(e)] if e.is_Symbol and str(e) in given else e for t, e in outputs}
    zeros = [t for t, e in resolved.items() if e == 0]
    value = {}                      # output -> the code of its value, for the outputs another copies
    stores = []
    for target, expr in exprs:
        if "[" not in target:
            lines.append(f"{pad}const double {target} = {to_c(expr)};")
        elif resolved[target] == 0:
            continue
        elif expr.is_Symbol and str(expr) in given:
            stores.append(f"{pad}{target} = {value[str(expr)]};")
        else:
            code = to_c(expr)
            if target in copied and not expr.is_Atom:
                local = f"_out{len(value)}"
                lines.append(f"{pad}const double {local} = {code};")
                code = local
            value[target] = code
            stores.append(f"{pad}{target} = {code};")
    lines += _zero_stores(zeros, pad) + stores
    if returns is not None:
        lines.append(f"{pad}return {returns};")
    return lines


def vector_trig(inputs: set[str], exprs: list, pad: str, least: int = VECTOR_LEAST) -> tuple[list[str], list]:
    """The sines (and the cosines) of a body's inputs in one loop each, and the body reading them there.

    Every sin(a) whose argument reads the leaf's inputs only (`inputs`, the unpacked names, and t) is a candidate;
    when a function has at least `least` distinct such arguments, they go into an array `_sin` that a
    `#pragma omp simd` loop maps to their sines in place, and the body's sin(a) become the array's elements
    (alike for cos). Returns (the lines, the body's (target, expr) rewritten).
    The arguments are in SymPy's sort order, so that the same model writes the same C (a loop's lanes and
    its remainder may round differently)."""
    readable = inputs | {"t"}
    found = {sin: set(), cos: set()}
    for _, expr in exprs:
        for call in expr.atoms(sin, cos):
            symbols = call.args[0].free_symbols     # (none: a number, which the C compiler folds)
            if symbols and all(str(s) in readable for s in symbols):
                found[call.func].add(call.args[0])
    lines, names = [], {}
    for function, arguments in found.items():
        if len(arguments) < least:
            continue
        array = f"_{function.__name__}"
        arguments = sorted(arguments, key=default_sort_key)
        lines += [f"{pad}double {array}[{len(arguments)}] = {{{', '.join(to_c(a) for a in arguments)}}};",
                  f"{pad}#pragma omp simd",
                  f"{pad}for (int64_t _i = 0; _i < {len(arguments)}; _i++) {array}[_i] = {function.__name__}({array}[_i]);"]
        # (the body reads the array's elements: copied into locals, a large leaf spilled them again, and
        # talos_full's forward dynamics ran 4 % slower than with scalar calls)
        names.update({function(argument): Symbol(f"{array}[{i}]") for i, argument in enumerate(arguments)})
    if not names:
        return [], exprs
    return lines, [(target, expr.xreplace(names)) for target, expr in exprs]


def _zero_stores(targets: list[str], pad: str, run: int = 4) -> list[str]:
    """Stores of 0.0 into `targets` (array elements `A[i]`): a loop over each run of at least `run` consecutive
    elements of one array, single stores for the rest."""
    by_array: dict[str, list[int]] = {}
    for target in targets:
        array, index = target[:-1].split("[")
        by_array.setdefault(array, []).append(int(index))
    lines = []
    for array, indices in by_array.items():
        indices.sort()
        k = 0
        while k < len(indices):
            end = k
            while end + 1 < len(indices) and indices[end + 1] == indices[end] + 1:
                end += 1
            if end - k + 1 >= run:
                lines.append(f"{pad}for (int64_t _z = {indices[k]}; _z <= {indices[end]}; _z++) {array}[_z] = 0.0;")
            else:
                lines += [f"{pad}{array}[{i}] = 0.0;" for i in indices[k:end + 1]]
            k = end + 1
    return lines


def signature(name: str, args: str) -> str:
    """The C prototype of leaf `name` over the Python argument list `args` ("k, t, x, u, p, d, lam")."""
    params = []
    for arg in (a.strip() for a in args.split(",")):
        params.append(f"double {arg}" if arg == "t" else f"int64_t {arg}" if arg == "k" else f"double *{arg}")
    return f"{'double' if name in RETURNS else 'void'} {name}({', '.join(params)})"


def render(name: str, functions: list[dict], parts: int = 1) -> str:
    """The text of <name>_leaves.c: every leaf of `functions` (Leaves.functions) that has C; with parts > 1, each
    inside `#if ANDYC_PART == k` of the part k it is compiled in (compile_library), the parts of about equal
    size (the largest leaf first, into the smallest part so far)."""
    out = [f"/* GENERATED by andyc -- DO NOT EDIT. The leaves of {name}, in C (andyc/codegen/c_leaves.py). */",
           "#include <math.h>", "#include <stdint.h>", "",
           "#if defined(ANDYC_VECTOR_MATH) && defined(__GNUC__) && !defined(__clang__)",
           "/* a loop over sin or cos calls libmvec's vector versions (c_leaves.py: VECTOR) */",
           'double sin(double) __attribute__((__simd__("notinbranch")));',
           'double cos(double) __attribute__((__simd__("notinbranch")));',
           "#endif", ""]
    texts = [[signature(f["name"], f["args"]) + " {", *f["c"], "}"] for f in functions if f.get("c") is not None]
    part, load = {}, [0] * max(1, parts)
    for i in sorted(range(len(texts)), key=lambda i: -sum(map(len, texts[i]))):
        part[i] = load.index(min(load))
        load[part[i]] += sum(map(len, texts[i]))
    for i, text in enumerate(texts):
        out += [f"#if !defined(ANDYC_PART) || ANDYC_PART == {part[i]}", *text, "#endif", ""] if parts > 1 else [*text, ""]
    return "\n".join(out)


def parts_for(functions: list[dict]) -> int:
    """How many parts render splits the C of `functions` into: one per PART_BYTES, at most MAX_PARTS or one per
    leaf."""
    sizes = [sum(map(len, f["c"])) for f in functions if f.get("c") is not None]
    return max(1, min(MAX_PARTS, len(sizes), sum(sizes) // PART_BYTES))


def _processors() -> int:
    try:
        return len(os.sched_getaffinity(0))
    except AttributeError:          # (not on every platform)
        return os.cpu_count() or 1


def library_stem(name: str, key: str) -> str:
    """The shared library's name but for the processor (andyc.numerics.compiler.library_file adds it): one per
    build key, since a process that loaded one keeps it (dlopen caches by path) and a rebuild must not look like
    the library it replaced."""
    return f"{name}_leaves_{key[:16]}"


@functools.cache
def _vector_math(cc: str) -> bool:
    """Whether `cc` links a library with VECTOR and libmvec here: x86-64 Linux, and a two-line probe that builds
    (once per process), so that a machine without libmvec does not compile a large leaf twice to find out."""
    if not (sys.platform.startswith("linux") and platform.machine() in ("x86_64", "AMD64")):
        return False
    with tempfile.TemporaryDirectory() as tmp:
        source = Path(tmp) / "probe.c"
        source.write_text("#include <math.h>\ndouble f(double x) { return sin(x); }\n")
        proc = subprocess.run([cc, *FLAGS, *VECTOR, "-o", str(Path(tmp) / "probe.so"), str(source), *VECTOR_LIBS,
                               "-lm"], capture_output=True, text=True)
    return proc.returncode == 0


def _flag_sets(cc: str) -> list[tuple[tuple, tuple]]:
    """The (flags, libraries) a build tries in turn: with vector math (where _vector_math) and -march=native,
    without vector math, then the baseline; the first that compiles makes the library."""
    sets = [((*FLAGS, *NATIVE), ()), (FLAGS, ())]
    if _vector_math(cc):
        sets.insert(0, ((*FLAGS, *NATIVE, *VECTOR), VECTOR_LIBS))
    return sets


def compile_library(source: Path, folder: Path, stem: str, cc: str) -> Path:
    """Compile the C file `source` (in the parts render made of it) into the shared library of `stem` for this
    machine (library_file), in `folder`, written whole (andyc.outputs), and remove the libraries of other builds of the
    model (those of this build for other processors stay); the library's path. NoC with the compiler's message
    when it fails. The parts compile side by side, each into an object file, then link into the library."""
    from andyc.numerics.compiler import library_file
    from andyc.outputs import write_atomic

    parts = 1 + max(map(int, re.findall(r"^#if !defined\(ANDYC_PART\) \|\| ANDYC_PART == (\d+)$",
                                        source.read_text(encoding="utf-8", errors="replace"), re.M)), default=0)
    target = folder / library_file(stem)
    with write_atomic(target) as tmp, tempfile.TemporaryDirectory(dir=folder) as scratch:
        for flags, libs in _flag_sets(cc):        # (each but the last for what this machine may lack)
            if parts == 1:
                proc = subprocess.run([cc, *flags, "-o", str(tmp), str(source), *libs, "-lm"],
                                      capture_output=True, text=True)
            else:
                objects = [Path(scratch) / f"part{k}.o" for k in range(parts)]
                compile_flags = [f for f in flags if f != "-shared" and not f.startswith("-Wl,")]
                # (each thread waits on its compiler)
                with concurrent.futures.ThreadPoolExecutor(min(parts, _processors())) as pool:
                    procs = list(pool.map(lambda k: subprocess.run(
                        [cc, *compile_flags, f"-DANDYC_PART={k}", "-c", "-o", str(objects[k]), str(source)],
                        capture_output=True, text=True), range(parts)))
                proc = next((p for p in procs if p.returncode != 0), None) or subprocess.run(
                    [cc, *flags, "-o", str(tmp), *map(str, objects), *libs, "-lm"], capture_output=True, text=True)
            if proc.returncode == 0:
                break
        if proc.returncode != 0:
            raise NoC(f"{cc} failed on {source}: {proc.stderr.strip()[:2000]}")
    for old in folder.glob(f"{stem.rsplit('_', 1)[0]}_*.so"):
        if not old.name.startswith(f"{stem}_"):
            old.unlink(missing_ok=True)
    return target
