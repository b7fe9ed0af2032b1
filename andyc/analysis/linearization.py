"""Linearization about an operating point given by name (`andyc linearize`): the point, the report, the files.

The derivatives are andyc.symbolic.linearize's (exact, forward mode); here the point is put together from
names -- the model's initial state with some coordinates and speeds given, its parameters and inputs with
some overridden, a flow, a time; optionally moved to the nearest rest point first -- and the result is
written out: a report for reading and, on request, DIR/<name>_linearization.npz with DIR/<name>_A.csv and
DIR/<name>_B.csv.

A constrained flow's speeds that the point does not give are completed from its rows (c = A v + b is linear
in v: the least change of those speeds that makes c = 0), so that `--at phi_dot=10` is a rolling disk's
steady motion with its contact point's speeds following. (andyc.analysis.eigensweep sweeps one value and
locates where stability changes.)
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from andyc.errors import plural
from andyc.outputs import write_atomic
from andyc.runtime.timestepping import refuse_friction
from andyc.symbolic.linearize import (Linearization, LinearizeError, default_point, find_equilibrium,
                                      linearize, values_at)
from andyc.symbolic.model import SymbolicModel


def linearize_at(model: SymbolicModel, at: dict | None = None, parameters: dict | None = None,
                 inputs: dict | None = None, flow: str | None = None, t: float = 0.0,
                 equilibrium: bool = False, cyclic=None) -> Linearization:
    """A and B of `flow` (a name; default the initial flow) at time t about the model's initial state with the
    coordinates and speeds in `at` {name: value} set, at its parameters and inputs with `parameters` and
    `inputs` {name: value} overriding their defaults (the flow's own inputs win). equilibrium: first move the
    coordinates to the rest point nearest them (speeds 0, dv/dt = 0; andyc.symbolic.linearize.find_equilibrium).
    The speeds of a constrained flow not in `at` are completed from its rows (see the module docstring).
    cyclic: the coordinates a steady motion leaves out (default: those the flow's equations do not use).

    LinearizeError for an unknown flow, input, parameter, coordinate or speed, and for a point the
    linearization does not handle; the message names what exists."""
    spec = model.spec
    refuse_friction([d.name for d in spec.joint_frictions], "andyc linearize", fix="", error=LinearizeError)
    flows = model.hybrid.flows
    if flow is not None and flow not in flows:
        raise LinearizeError(f"{spec.name}: no flow named '{flow}'; flows: {', '.join(flows)}")
    k = flows.index(flow) if flow is not None else None
    unknown = sorted(set(inputs or {}) - set(spec.inputs))
    if unknown:
        raise LinearizeError(f"{spec.name}: no input named {', '.join(unknown)} (--input); inputs: "
                             f"{', '.join(spec.inputs) or 'none'}")
    x, u, p, d = default_point(model, parameters, inputs, k)
    names = [c.name for c in spec.coordinates] + list(spec.speed_names)
    for name, value in (at or {}).items():
        if name not in names:
            raise LinearizeError(f"{spec.name}: no coordinate or speed named '{name}' (--at); "
                                 f"states: {', '.join(names)}")
        x[names.index(name)] = value
    if equilibrium:
        n = len(spec.coordinates)
        x[:n] = find_equilibrium(model, x[:n], u, p, d, t, k)
        x[n:] = 0.0
    x = _complete_speeds(model, x, u, p, d, t, k, set(at or {}))
    return linearize(model, x, u, p, d, t, k, cyclic)


def _complete_speeds(model: SymbolicModel, x, u, p, d, t, flow, given: set) -> np.ndarray:
    """x with the speeds not in `given` changed least (least squares) so that the flow's rows hold: c = A v + b
    = 0, exactly, as c is linear in v. Unchanged where the rows hold or the flow has none."""
    flow = model.hybrid.initial if flow is None else flow
    rows, C = model.hybrid.flow_rows[flow], model.constraints
    n = len(model.v)
    speeds = list(model.spec.speed_names)
    free = [j for j, name in enumerate(speeds) if name not in given]
    if not rows or not free:
        return x
    values = values_at(model, [C.c[r] for r in rows] + [C.A[r, j] for r in rows for j in free], x, u, p, d, t)
    c, A = values[:len(rows)], values[len(rows):].reshape(len(rows), len(free))
    if np.max(np.abs(c)) <= 1e-12 * max(1.0, np.max(np.abs(x))):
        return x
    x = x.copy()
    x[n + np.array(free)] -= np.linalg.lstsq(A, c, rcond=None)[0]
    return x


def unstable_count(eigenvalues) -> int:
    """How many eigenvalues have a positive real part, past the round-off of the largest (1e-9 of it)."""
    ev = np.asarray(eigenvalues)
    return int(np.sum(ev.real > 1e-9 * max(1.0, np.abs(ev).max(initial=0.0))))


def report(lin: Linearization, name: str) -> str:
    """The linearization of model `name` for reading: the point, the null-space bases of a constrained flow,
    A and B with their states and inputs, the eigenvalues and how many have a positive real part."""
    with np.printoptions(precision=6, suppress=False, linewidth=120):
        point = ", ".join(f"{n} = {v:.10g}" for n, v in zip(lin.point_names or lin.state_names, lin.x))
        inputs = ", ".join(f"{n} = {v:.10g}" for n, v in zip(lin.input_names, lin.u)) or "none"
        lines = [f"{name}: linearized in flow '{lin.flow}' at t = {lin.t:g} about {point}; inputs {inputs}"]
        if lin.cyclic:
            lines.append(f"a steady motion: the cyclic coordinates {', '.join(lin.cyclic)} are left out; dq = N_q z "
                         "(zero rows for them), dv = N_v w + P z (P keeps the speeds on the constraints as q moves)")
        if lin.form == "null-space":
            lines.append(f"flow '{lin.flow}' is constrained: null-space form, dq = N_q z, dv = N_v w (orthonormal "
                         f"bases of the null space of its constraint rows at the point)\nN_q =\n{lin.basis_q}\n"
                         f"N_v =\n{lin.basis_v}")
        lines.append(f"states: {', '.join(lin.state_names)}\nA =\n{lin.A}")
        if lin.input_names:
            lines.append(f"inputs: {', '.join(lin.input_names)}\nB =\n{lin.B}")
    ev = lin.eigenvalues
    lines.append("eigenvalues: " + ", ".join(f"{e.real:.10g}{e.imag:+.10g}j" if e.imag else f"{e.real:.10g}"
                                             for e in ev))
    unstable = unstable_count(ev)
    lines.append(f"{plural(unstable, 'eigenvalue')} with positive real part" + (" (unstable)" if unstable else ""))
    return "\n".join(lines)


def output_paths(out_dir, name: str) -> list[Path]:
    """The files `save` writes for model `name`: the .npz, then A's and B's CSV."""
    return [Path(out_dir) / f"{name}{suffix}" for suffix in ("_linearization.npz", "_A.csv", "_B.csv")]


def save(lin: Linearization, out_dir, name: str) -> list[Path]:
    """Write output_paths(out_dir, name), each whole (andyc.outputs.write_atomic): the .npz holds A, B, x, u,
    t, state_names, input_names, eigenvalues, flow, form (and N_q, N_v in the null-space form); the CSVs A and
    B with their states' and inputs' names as the header."""
    npz, a_csv, b_csv = paths = output_paths(out_dir, name)
    bases = {"N_q": lin.basis_q, "N_v": lin.basis_v} if lin.form == "null-space" else {}
    with write_atomic(npz) as tmp, open(tmp, "wb") as fh:
        np.savez(fh, A=lin.A, B=lin.B, x=lin.x, u=lin.u, t=lin.t,
                 state_names=np.array(lin.state_names), input_names=np.array(lin.input_names, dtype=str),
                 eigenvalues=lin.eigenvalues, flow=lin.flow, form=lin.form, **bases)
    for matrix, names, path in ((lin.A, lin.state_names, a_csv), (lin.B, lin.input_names, b_csv)):
        with write_atomic(path) as tmp:
            np.savetxt(tmp, matrix, delimiter=",", header=",".join(names), comments="")
    return paths
