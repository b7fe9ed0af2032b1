"""Eigenvalues along one value (`andyc linearize --sweep NAME=A:B:N`), and where stability changes.

At each value of a parameter, input, coordinate or speed, the flow is linearized (andyc.analysis.linearization:
at rest, about a steady motion, or anywhere for a flow without rows) and its eigenvalues are taken without the
structural zeros a steady motion carries. Those zeros (a cyclic heading, a first integral such as the rolling
speed) sit in a cluster that round-off splits by eps^(1/k) for a Jordan block of size k; near a change of
stability the crossing eigenvalues join the cluster, and counting eigenvalues of A itself would place the
change only to about 1e-7. So:

1. a state that nothing depends on (its column of A is zero) is removed: its eigenvalue is 0 and the others
   are those of A without its row and column; repeated until no column is zero;
2. A is restricted to its range, of dimension n - m, with m the least nullity over the sweep's values (the
   zeros present everywhere): R = Q^T A Q, Q the first n - m left singular vectors. The range is invariant,
   so R's eigenvalues are A's less m zeros.

Stability (the number of eigenvalues of R with a positive real part, past 1e-9 of |A|) is counted at each
value; where it changes between neighbours, the change is located to 1e-13 of the range by Brent's method
on a smooth test function (as continuation codes do; Kuznetsov, "Elements of Applied Bifurcation Theory",
3rd ed., 2004, §10.2): det R, where a real eigenvalue crosses zero, or else the real part of the complex pair
nearest the imaginary axis, where a pair crosses it (Hopf).
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from andyc.analysis.linearization import linearize_at
from andyc.outputs import write_atomic
from andyc.symbolic.linearize import LinearizeError
from andyc.symbolic.model import SymbolicModel

ZERO_COLUMN = 1e-12     # a column of A this small, relative to |A|, is zero (a state nothing depends on)
RANK = 1e-10            # singular values of A below this, relative to |A|, count as zero
UNSTABLE = 1e-9         # a real part above this, relative to max(1, |A|), is unstable


@dataclass
class Change:
    """Stability changes at `value` of the swept name: `before` unstable eigenvalues below it, `after` above;
    `kind`: 'real' (a real eigenvalue crosses zero) or 'hopf' (a complex pair crosses the imaginary axis)."""
    value: float
    before: int
    after: int
    kind: str


@dataclass
class Sweep:
    name: str
    values: np.ndarray          # (N,)
    eigenvalues: np.ndarray     # (N, n - m): R's eigenvalues at each value, sorted by real, then imaginary part
    unstable: np.ndarray        # (N,) ints
    structural: int             # m + the removed states: the zero eigenvalues left out at every value
    changes: list


def essential(A: np.ndarray, nullity: int | None = None) -> tuple[np.ndarray, int]:
    """(R, m) for A: steps 1 and 2 of the module docstring, with m the nullity after step 1 (given, or A's own
    numerical nullity); R has len(A) - (states removed) - m rows."""
    scale = max(np.abs(A).max(initial=0.0), 1e-300)
    keep = list(range(len(A)))
    while keep:
        sub = A[np.ix_(keep, keep)]
        zero = [k for j, k in enumerate(keep) if np.abs(sub[:, j]).max() <= ZERO_COLUMN * scale]
        if not zero:
            break
        keep = [k for k in keep if k not in zero]
    sub = A[np.ix_(keep, keep)]
    if not keep:
        return sub, 0
    U, s, _ = np.linalg.svd(sub)
    m = int(np.sum(s <= RANK * scale)) if nullity is None else nullity
    Q = U[:, :len(keep) - m]
    return Q.T @ sub @ Q, m


def unstable(R: np.ndarray, scale: float) -> int:
    ev = np.linalg.eigvals(R)
    return int(np.sum(ev.real > UNSTABLE * max(1.0, scale)))


def sweep(model: SymbolicModel, name: str, values, at: dict | None = None, parameters: dict | None = None,
          inputs: dict | None = None, flow: str | None = None, t: float = 0.0) -> Sweep:
    """The linearizations of `flow` along `name` at each of `values` (the point: as linearize_at, with `name`
    set), their eigenvalues without the structural zeros, and where stability changes (module docstring).
    LinearizeError for a name that is no parameter, input, coordinate or speed, and as linearize_at."""
    from scipy.optimize import brentq

    spec = model.spec
    states = [c.name for c in spec.coordinates] + list(spec.speed_names)
    kind = next((k for k, names in (("parameters", spec.parameters), ("inputs", spec.inputs), ("at", states))
                 if name in names), None)
    if kind is None:
        raise LinearizeError(f"{spec.name}: nothing named '{name}' to sweep (--sweep); parameters: "
                             f"{', '.join(spec.parameters) or 'none'}; inputs: {', '.join(spec.inputs) or 'none'}; "
                             f"states: {', '.join(states)}")
    given = {"at": dict(at or {}), "parameters": dict(parameters or {}), "inputs": dict(inputs or {})}
    cyclic = None               # a steady motion's cyclic coordinates: found at the first value, kept after

    def A_at(v) -> np.ndarray:
        nonlocal cyclic
        given[kind][name] = float(v)
        lin = linearize_at(model, given["at"], given["parameters"], given["inputs"], flow, t, cyclic=cyclic)
        cyclic = list(lin.cyclic) or None
        return lin.A

    values = np.asarray(values, dtype=float)
    matrices = [A_at(v) for v in values]
    nullity = min(essential(A)[1] for A in matrices)        # the zeros present at every value
    reduced = [essential(A, nullity)[0] for A in matrices]
    eigenvalues = np.array([_sorted(np.linalg.eigvals(R)) for R in reduced])
    counts = np.array([unstable(R, np.abs(A).max()) for R, A in zip(reduced, matrices)])

    def det(v):
        return float(np.linalg.det(essential(A_at(v), nullity)[0]))

    def hopf(v):
        ev = np.linalg.eigvals(essential(A_at(v), nullity)[0])
        pairs = ev[np.abs(ev.imag) > 0]
        return float(pairs.real[np.argmin(np.abs(pairs.real))]) if len(pairs) else np.nan

    changes, span = [], abs(values[-1] - values[0])
    for i in np.flatnonzero(np.diff(counts)):
        lo, hi = values[i], values[i + 1]
        for test, what in ((det, "real"), (hopf, "hopf")):
            a, b = test(lo), test(hi)
            if np.isfinite(a) and np.isfinite(b) and a * b < 0:
                changes.append(Change(brentq(test, lo, hi, xtol=1e-13 * span, rtol=4 * np.finfo(float).eps),
                                      int(counts[i]), int(counts[i + 1]), what))
                break
        else:
            changes.append(Change(0.5 * (lo + hi), int(counts[i]), int(counts[i + 1]), "unlocated"))
    return Sweep(name, values, eigenvalues, counts, len(matrices[0]) - len(reduced[0]), changes)


def _sorted(ev: np.ndarray) -> np.ndarray:
    return ev[np.lexsort((ev.imag, ev.real))]


def report(sw: Sweep, model_name: str) -> str:
    """The sweep for reading: each value with the largest real part and the number unstable, then the
    changes of stability."""
    lines = [f"{model_name}: eigenvalues along {sw.name} ({len(sw.values)} values; {sw.structural} structural "
             "zero eigenvalues left out at each: cyclic states and first integrals)",
             f"{sw.name:>14}  {'largest real part':>18}  {'its imaginary part':>18}  unstable"]
    for v, ev, k in zip(sw.values, sw.eigenvalues, sw.unstable):
        top = ev[np.argmax(ev.real)] if len(ev) else 0j
        lines.append(f"{v:14.8g}  {top.real:18.10g}  {abs(top.imag):18.10g}  {k:8d}")
    what = {"real": "a real eigenvalue crosses zero", "hopf": "a complex pair crosses the imaginary axis (Hopf)",
            "unlocated": "not located: no test function changes sign; refine the sweep"}
    for c in sw.changes:
        lines.append(f"stability changes at {sw.name} = {c.value:.15g}: {what[c.kind]}; {c.before} unstable "
                     f"eigenvalue(s) below, {c.after} above")
    if not sw.changes:
        lines.append("stability does not change over the sweep")
    return "\n".join(lines)


def save(sw: Sweep, out_dir, model_name: str) -> Path:
    """DIR/<name>_sweep_<swept>.csv: the swept value, the unstable count, then each eigenvalue's real and
    imaginary parts (written whole: andyc.outputs.write_atomic)."""
    path = Path(out_dir) / f"{model_name}_sweep_{sw.name}.csv"
    n = sw.eigenvalues.shape[1]
    header = ",".join([sw.name, "unstable"] + [f"re{i + 1},im{i + 1}" for i in range(n)])
    columns = [sw.values, sw.unstable] + [part for i in range(n) for part in (sw.eigenvalues[:, i].real,
                                                                              sw.eigenvalues[:, i].imag)]
    with write_atomic(path) as tmp:
        np.savetxt(tmp, np.column_stack(columns), delimiter=",", header=header, comments="", fmt="%.17g")
    return path
