"""Mutation testing of andyc's jitted numerics, with mutmut's own mutation operators.

`make mutation` runs mutmut 3, which leaves out every decorated function: its trampolines (a Python function
that picks the original or a mutant at run time) cannot be called from Numba-compiled code. Most of
`andyc/numerics` is such code. This script takes the same operators (`mutmut.mutation.mutators`) to the
functions decorated with `@jit` (andyc.numerics.compiler) and tests each mutant the plain way: the mutated
source is written into a copy of the tree, the module's tests run there, and the file is put back.

Every mutant compiles the numerics it reaches afresh (Numba's cache of andyc's numerics is keyed by their
content, so a mutant never reads another's compiled code): tens of seconds each. So the mutants are drawn at
random (--sample, --seed) and the score is reported with its 95 % (Wilson) interval; --sample 0 runs them all.

    python bench/mutate_jitted.py --list                       the mutants per module, and each module's tests
    python bench/mutate_jitted.py --sample 60 --jobs 2         a random 60 of all, two at a time
    python bench/mutate_jitted.py --module linalg.py --sample 0

Results go to build/mutation-jitted/results.jsonl (one line a mutant: a rerun with the same seed goes on
where it stopped) and build/mutation-jitted/report.md (per module: killed, of which by a compile error,
survived, timed out; each survivor's diff). A mutant that Numba refuses to compile is counted as killed (as
mutmut counts one a type checker refuses) and shown apart.
"""

from __future__ import annotations

import argparse
import difflib
import hashlib
import json
import math
import os
import random
import shutil
import subprocess
import sys
import time
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import libcst as cst
from libcst.metadata import MetadataWrapper, PositionProvider
from mutmut.mutation.mutators import mutation_operators

ROOT = Path(__file__).resolve().parents[1]
NUMERICS = ROOT / "andyc" / "numerics"
OUT = ROOT / "build" / "mutation-jitted"
COPIED = ("andyc", "tests", "models", "bench", "docs", "pyproject.toml", "README.md")   # what the tests read

# The tests that exercise each module's compiled functions, cheapest first (with -x a killed mutant stops at
# the first failure, so the fast, sharp tests go first). A module not listed gets DEFAULT_TESTS.
DEFAULT_TESTS = ["tests/test_stage_times.py", "tests/test_closed_form.py", "tests/test_constrained_runs.py"]
TESTS = {
    "linalg.py": ["tests/test_dense_solves.py", "tests/test_constrained_runs.py", "tests/test_sparse_constraints.py"],
    "dense_solves.py": ["tests/test_dense_solves.py", "tests/test_contact_solver.py"],
    "dynamics.py": ["tests/test_baumgarte_decay.py", "tests/test_constrained_runs.py", "tests/test_closed_form.py",
                    "tests/test_hybrid_runtime.py", "tests/test_spatial_friction.py", "tests/test_contacts.py"],
    "integrator.py": ["tests/test_stage_times.py", "tests/test_closed_form.py", "tests/test_hybrid_runtime.py",
                      "tests/test_constrained_runs.py"],
    "contact_solver.py": ["tests/test_contact_solver.py", "tests/test_joint_friction.py"],
    "timestepping.py": ["tests/test_moreau_time.py", "tests/test_moreau.py", "tests/test_joint_friction.py"],
    "tangents.py": ["tests/test_sensitivities.py"],
    "slipping.py": ["tests/test_spatial_friction.py", "tests/test_friction.py"],
    "sparse_rows.py": ["tests/test_sparse_constraints.py"],
    "active.py": ["tests/test_contacts.py", "tests/test_hybrid_runtime.py"],
    "inputs.py": ["tests/test_inputs.py"],
    "batch.py": ["tests/test_sweep_batch.py"],
    "api.py": ["tests/test_runtime.py", "tests/test_closed_form.py"],
    "model.py": ["tests/test_stage_times.py", "tests/test_closed_form.py"],
}
COMPILE_ERRORS = ("numba.core.errors", "TypingError", "LoweringError", "UnsupportedError")


def _jitted(function: cst.FunctionDef) -> bool:
    """Whether `function` is decorated with @jit, @jit(...), @njit or @cfunc(...)."""
    for decorator in function.decorators:
        node = decorator.decorator.func if isinstance(decorator.decorator, cst.Call) else decorator.decorator
        if isinstance(node, cst.Name) and node.value in ("jit", "njit", "cfunc"):
            return True
    return False


class _Mutations(cst.CSTVisitor):
    """Every mutation mutmut's operators make inside the jitted functions of one module: (function node, line,
    original node, mutated node). Decorators, annotations, docstrings and lines marked `# pragma: no mutate`
    are left alone, as mutmut leaves them."""

    METADATA_DEPENDENCIES = (PositionProvider,)

    def __init__(self, lines: list[str]):
        self.lines, self.function, self.found, self.spans = lines, None, [], {}

    def visit_FunctionDef(self, node):
        if self.function is None:
            if not _jitted(node):
                return False
            self.function = node
            first = self.get_metadata(PositionProvider, node.decorators[0]).start.line   # (the def's span omits them)
            self.spans[node] = (first, self.get_metadata(PositionProvider, node).end.line)
        return True

    def leave_FunctionDef(self, node):
        if self.function is node:
            self.function = None

    def on_visit(self, node):
        if isinstance(node, (cst.Decorator, cst.Annotation)):
            return False
        if isinstance(node, cst.SimpleStatementLine) and len(node.body) == 1 and isinstance(node.body[0], cst.Expr) \
                and isinstance(node.body[0].value, (cst.SimpleString, cst.ConcatenatedString)):
            return False                                # a docstring
        if not super().on_visit(node):
            return False
        if self.function is not None:
            line = self.get_metadata(PositionProvider, node).start.line
            if "pragma: no mutate" not in self.lines[line - 1]:
                for kind, operator in mutation_operators:
                    if isinstance(node, kind):
                        self.found.extend((self.function, line, node, mutated) for mutated in operator(node))
        return True


def mutants(path: Path) -> list[dict]:
    """The mutants of one module: {name, module, function, line, edit}; materialize() makes the mutated file."""
    code = path.read_text()
    module = cst.parse_module(code)
    visitor = _Mutations(code.splitlines())
    MetadataWrapper(module, unsafe_skip_copy=True).visit(visitor)
    for function, span in visitor.spans.items():            # the splice below must give back the file unmutated
        assert _splice(code.splitlines(True), module.code_for_node(function), span) == code, function.name.value
    counts, out = {}, []
    for function, line, original, mutated in visitor.found:
        name = function.name.value
        counts[name] = counts.get(name, 0) + 1
        out.append({"name": f"{path.stem}.{name}__{counts[name]}", "module": path.name, "function": name,
                    "line": line, "edit": (path, module, function, visitor.spans[function], original, mutated)})
    return out


def _splice(lines: list[str], text: str, span: tuple[int, int]) -> str:
    """The file of `lines` with the lines of span (first decorator .. end, 1-based) replaced by a function's
    text (libcst's code for the node: its leading blank lines dropped, as the span has none)."""
    first, last = span
    return "".join(lines[:first - 1] + text.lstrip("\n").splitlines(True) + lines[last:])


def materialize(mutant: dict) -> dict:
    """The mutant with its whole mutated file (source) and the diff, made by replacing the function's lines
    only (a whole module's regeneration per mutant would take minutes over thousands)."""
    path, module, function, span, original, mutated = mutant["edit"]
    lines = path.read_text().splitlines(True)
    source = _splice(lines, module.code_for_node(function.deep_replace(original, mutated)), span)
    diff = "".join(difflib.unified_diff(lines, source.splitlines(True), n=1))
    return {**{k: v for k, v in mutant.items() if k != "edit"}, "source": source,
            "diff": "\n".join(diff.splitlines()[2:])}


def all_mutants(modules: list[str] | None) -> list[dict]:
    paths = sorted(NUMERICS.glob("*.py")) if not modules else [NUMERICS / m for m in modules]
    return [m for p in paths for m in mutants(p)]


class Worker:
    """One copy of the tree in which mutants are tested one at a time; its caches are emptied between them."""

    def __init__(self, base: Path, index: int):
        self.root = base / f"tree{index}"
        # copied afresh each time (an interrupted run may have left a mutant in place); the shipped models'
        # builds (build/tests: reused by meaning) only once
        for name in COPIED + ("build/tests",):
            source, target = ROOT / name, self.root / name
            if target.exists() and name in COPIED:
                shutil.rmtree(target) if target.is_dir() else target.unlink()
            if source.exists() and not target.exists():
                target.parent.mkdir(parents=True, exist_ok=True)
                if source.is_dir():
                    shutil.copytree(source, target, ignore=shutil.ignore_patterns("__pycache__"))
                else:
                    shutil.copy2(source, target)
        self.cache = base / f"cache{index}"

    def test(self, tests: list[str], timeout: float, module: str | None = None, source: str | None = None):
        """(outcome, seconds, tail of the output): outcome 'survived', 'killed', 'compile' (killed by a
        compile error), 'crashed' (killed by a signal: a segmentation fault), 'timeout', or 'error N' (pytest's
        own failure, not counted); the module's file is restored afterwards."""
        target = self.root / "andyc" / "numerics" / module if module else None
        original = target.read_text() if target else None
        shutil.rmtree(self.cache, ignore_errors=True)
        env = dict(os.environ, ANDYC_CACHE_DIR=str(self.cache), NUMBA_CACHE_DIR=str(self.cache / "numba"),
                   PYTHONDONTWRITEBYTECODE="1")
        try:
            if target:
                target.write_text(source)
            start = time.monotonic()
            try:
                done = subprocess.run([sys.executable, "-m", "pytest", "-x", "-q", "-p", "no:cacheprovider",
                                       "-p", "no:randomly", *tests], cwd=self.root, env=env, capture_output=True,
                                      text=True, timeout=timeout)
            except subprocess.TimeoutExpired:
                return "timeout", time.monotonic() - start, ""
            seconds, output = time.monotonic() - start, done.stdout + done.stderr
        finally:
            if target:
                target.write_text(original)
        if done.returncode == 0:
            return "survived", seconds, output[-400:]
        if done.returncode < 0:                     # a signal: compiled code out of bounds (Numba checks none)
            return "crashed", seconds, output[-400:]
        if done.returncode not in (1,):              # 2-5: interrupted, internal or usage error, nothing collected
            return f"error {done.returncode}", seconds, output[-2000:]
        return ("compile" if any(e in output for e in COMPILE_ERRORS) else "killed"), seconds, output[-400:]


def _digest(*folders: Path) -> str:
    """A digest of the Python files under folders (the baselines hold for this content only)."""
    h = hashlib.sha256()
    for folder in folders:
        for path in sorted(folder.rglob("*.py")):
            h.update(str(path.relative_to(ROOT)).encode() + path.read_bytes())
    return h.hexdigest()[:16]


def wilson(k: int, n: int, z: float = 1.96):
    """The 95 % Wilson score interval of a proportion k / n."""
    if n == 0:
        return 0.0, 1.0
    p = k / n
    centre, half = p + z * z / (2 * n), z * math.sqrt(p * (1 - p) / n + z * z / (4 * n * n))
    return (centre - half) / (1 + z * z / n), (centre + half) / (1 + z * z / n)


def report(results: list[dict], drawn: int, total: int) -> str:
    """The report's Markdown: per module and overall; the survivors' diffs."""
    rows, modules = [], sorted({r["module"] for r in results})
    lines = [f"# Jitted numerics: the first {len(results)} of {drawn} mutants drawn at random ({total} in all)", "",
             "| module | tested | killed | of which compile errors | of which crashes | survived | timed out | score "
             "| 95 % interval |", "|---|---|---|---|---|---|---|---|---|"]
    for module in modules + ["all"]:
        rows = [r for r in results if module in ("all", r["module"])]
        killed = sum(r["outcome"] in ("killed", "compile", "crashed", "timeout") for r in rows)
        counts = {o: sum(r["outcome"] == o for r in rows)
                  for o in ("killed", "compile", "crashed", "survived", "timeout")}
        low, high = wilson(killed, len(rows))
        lines.append(f"| {module} | {len(rows)} | {counts['killed'] + counts['compile'] + counts['crashed']} | "
                     f"{counts['compile']} | {counts['crashed']} | {counts['survived']} | {counts['timeout']} | "
                     f"{killed / max(len(rows), 1):.0%} | {low:.0%}-{high:.0%} |")
    survivors = [r for r in results if r["outcome"] == "survived"]
    lines += ["", f"## Survivors ({len(survivors)})", ""]
    for r in survivors:
        lines += [f"### {r['name']} (line {r['line']}; tests: {' '.join(r['tests'])})", "", "```diff", r["diff"],
                  "```", ""]
    return "\n".join(lines) + "\n"


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--module", action="append", help="a file of andyc/numerics (repeatable; default all)")
    parser.add_argument("--sample", type=int, default=60, help="mutants drawn at random (0: all)")
    parser.add_argument("--seed", type=int, default=1)
    parser.add_argument("--jobs", type=int, default=1)
    parser.add_argument("--timeout", type=float, default=1800.0, help="seconds a mutant's tests may take at most")
    parser.add_argument("--list", action="store_true", help="only count the mutants per module")
    parser.add_argument("--out", type=Path, default=OUT)
    parser.add_argument("--report-only", action="store_true", help="write the report of the mutants tested so far")
    args = parser.parse_args(argv)

    found = all_mutants(args.module)
    if args.list:
        for module in sorted({m["module"] for m in found}):
            count = sum(m["module"] == module for m in found)
            print(f"{module:20s} {count:5d} mutants   tests: {' '.join(TESTS.get(module, DEFAULT_TESTS))}")
        print(f"{'all':20s} {len(found):5d}")
        return 0
    drawn = found if args.sample <= 0 else random.Random(args.seed).sample(found, min(args.sample, len(found)))
    args.out.mkdir(parents=True, exist_ok=True)
    log = args.out / "results.jsonl"
    done = {}
    if log.exists():
        for line in log.read_text().splitlines():
            record = json.loads(line)
            done[record["name"]] = record
    pending = [] if args.report_only else [materialize(m) for m in drawn if m["name"] not in done]
    workers = [Worker(args.out, i) for i in range(max(args.jobs, 1))] if pending else []
    free = list(workers)

    def on_a_worker(*a):
        worker = free.pop()
        try:
            return worker.test(*a)
        finally:
            free.append(worker)

    # the unmutated tree must pass each selection first (a failing baseline would count every mutant killed);
    # its time sets the selection's timeout, for a mutant that loops for ever in compiled code
    # (kept in baselines.json for this content of andyc/ and tests/, so that a rerun goes straight on)
    stamp = _digest(ROOT / "andyc", ROOT / "tests")
    saved = args.out / "baselines.json"
    baselines = json.loads(saved.read_text()) if saved.exists() else {}
    baselines = baselines if baselines.get("stamp") == stamp else {"stamp": stamp}
    selections = sorted({" ".join(TESTS.get(m["module"], DEFAULT_TESTS)) for m in pending} - set(baselines))

    def baseline(tests):
        outcome, seconds, tail = on_a_worker(tests.split(), args.timeout)
        print(f"baseline {tests}: {outcome} in {seconds:.0f} s", file=sys.stderr, flush=True)
        if outcome != "survived":
            print(tail, file=sys.stderr, flush=True)
            return
        baselines[tests] = seconds
        saved.write_text(json.dumps(baselines, indent=1))

    with ThreadPoolExecutor(max(len(workers), 1)) as pool:
        list(pool.map(baseline, selections))
    if any(" ".join(TESTS.get(m["module"], DEFAULT_TESTS)) not in baselines for m in pending):
        return 1
    timeouts = {tests: min(args.timeout, max(3 * s, 300.0)) for tests, s in baselines.items() if tests != "stamp"}

    def run(mutant):
        tests = TESTS.get(mutant["module"], DEFAULT_TESTS)
        outcome, seconds, tail = on_a_worker(tests, timeouts[" ".join(tests)], mutant["module"], mutant["source"])
        record = {k: mutant[k] for k in ("name", "module", "function", "line", "diff")}
        record.update(outcome=outcome, seconds=round(seconds, 1), tests=tests,
                      tail=tail if outcome.startswith("error") else "")
        with log.open("a") as f:
            f.write(json.dumps(record) + "\n")
        done[mutant["name"]] = record
        print(f"{len(done)}/{len(drawn)} {mutant['name']}: {outcome} ({seconds:.0f} s)", file=sys.stderr,
              flush=True)

    if pending:
        with ThreadPoolExecutor(len(workers)) as pool:
            list(pool.map(run, pending))
    # the score is over the drawn order's longest tested prefix, a random sample itself: a run stopped early
    # would otherwise leave out the slow mutants in flight, more often survivors than killed ones
    prefix = next((i for i, m in enumerate(drawn) if m["name"] not in done), len(drawn))
    results = [done[m["name"]] for m in drawn[:prefix] if not done[m["name"]]["outcome"].startswith("error")]
    text = report(results, len(drawn), len(found))
    (args.out / "report.md").write_text(text)
    print(text)
    return 0


if __name__ == "__main__":
    sys.exit(main())
