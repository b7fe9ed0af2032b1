"""SymbolicModel -> build/<name>/<name>_derivatives.py: exact first derivatives of the model's functions.

What a run with sensitivities (andyc.runtime.sensitivities) evaluates at every RK4 stage and at every
jump, each value with its gradient over W = (x, d, p, t) (the state, the discrete states, the parameters,
the time; andyc.symbolic.sensitivities.variables), from the symbolic forward mode of
andyc.symbolic.sensitivities:

    flow_terms(t, x, u, p, d)          M, dM (NV, NV, NW); G, dG; the constraint rows' A, dA (NC, NV, NW),
                                       kappa, dkappa, c, dc, and the holonomic rows' phi, dphi (NH, NW) (as the
                                       leaves `dynamics` and `constraints_into`)
    signal_terms(t, x, u, p, d)        the signals' rates s (NS,) and ds (NS, NW) (the leaf `signal_rates`)
    energy_terms(t, x, u, p, d)        the energy E and dE (NW,) (the leaf `energy`; the projection's eq. 5-6)
    guard_terms(k, t, x, u, p, d)      jump k's guard g and dg (NW,)
    reset_terms(k, t, x, u, p, d)      jump k's resets: the index in W of each target, its value, its gradient
    restitution_terms(k, t, x, u, p, d)   the restitution e of jump k's impact and de (NW,)

and, bound to those by the template templates/derivatives.py.j2, the algorithms every model shares
(andyc/numerics/tangents.py, from the build's copy of the numerics): `rates` (f and df/dW in a flow),
`step_tangent` (the RK4 step, the projection's corrections, and their tangent) and `tangent_steps` (the steps of
a stretch without jumps, in one call). Those and the terms above are compiled by Numba and cached beside the
file (the shared algorithms take the model's functions as arguments and compile inside these); the jump terms,
called once per jump, stay Python. BUILD_KEY ties the file to the build's equations.
"""

from __future__ import annotations

import andyc
from andyc.codegen.buildfiles import equations_path, numerics_package, written_constant
from andyc.codegen.generate import _environment
from andyc.codegen.leaves import STATE, _code
from andyc.codegen.printer import function_body
from andyc.outputs import check_output, update_text
from andyc.symbolic.model import SymbolicModel
from andyc.symbolic.sensitivities import ForwardGradients, variables


def derivatives_path(out_dir, name: str):
    return equations_path(out_dir, name).with_name(f"{name}_derivatives.py")


def _with_gradients(fg: ForwardGradients, items: list) -> list:
    """(target, expr) -> those and, for each, (gradient target[..., j], d expr / d w_j) of the nonzero entries; a
    target 'X[i, j]' gets 'dX[i, j, k]'."""
    out = []
    for target, expr in items:
        out.append((target, expr))
        name, _, index = target.partition("[")
        index = index.rstrip("]")
        for j, e in fg.gradient(expr).items():
            out.append((f"d{name}[{index + ', ' if index else ''}{j}]", e))
    return out


def render(model: SymbolicModel, key: str) -> str:
    """The text of <name>_derivatives.py (see the module docstring)."""
    n, cons, h = model.dof, model.constraints, model.hybrid
    nw = len(variables(model))
    flow_items = ([(f"M[{i}, {j}]", model.M[i, j]) for i in range(n) for j in range(n)]
                  + [(f"G[{i}]", model.G[i]) for i in range(n)]
                  + [(f"A[{r}, {j}]", cons.A[r, j]) for r in range(cons.nc) for j in range(n)]
                  + [(f"kappa[{r}]", e) for r, e in enumerate(cons.kappa)]
                  + [(f"c[{r}]", e) for r, e in enumerate(cons.c)]
                  + [(f"phi[{r}]", e) for r, e in enumerate(cons.phi)])
    nq, ns = len(model.q), len(model.signals)
    index = {**{c.name: i for i, c in enumerate(model.spec.coordinates)},
             **{name: nq + i for i, name in enumerate(model.spec.speed_names)},
             **{x.name: nq + n + ns + i for i, x in enumerate(model.spec.discrete)}}
    jump_exprs = [e for j in h.jumps for e in (j.guard, j.restitution, *(e for _, e in j.resets))]
    signal_items = [(f"s[{i}]", e) for i, e in enumerate(model.signal_rates)]
    fg = ForwardGradients(model, [e for _, e in flow_items + signal_items] + jump_exprs + [model.energy],
                          variables(model))
    pool = dict(model.assignments)
    pool.update(fg.assignments)

    def body(items, returns, indent=4):
        return _code(model, function_body(_with_gradients(fg, items), pool), returns, indent)

    lines = ["@njit(cache=True, error_model=\"numpy\")",
             "def flow_terms(t, x, u, p, d):",
             f"    M, dM = np.zeros(({n}, {n})), np.zeros(({n}, {n}, NW))",
             f"    G, dG = np.zeros({n}), np.zeros(({n}, NW))",
             f"    A, dA = np.zeros(({cons.nc}, {n})), np.zeros(({cons.nc}, {n}, NW))",
             f"    kappa, dkappa = np.zeros({cons.nc}), np.zeros(({cons.nc}, NW))",
             f"    c, dc = np.zeros({cons.nc}), np.zeros(({cons.nc}, NW))",
             f"    phi, dphi = np.zeros({cons.nh}), np.zeros(({cons.nh}, NW))",
             *body(flow_items, None), "    return M, dM, G, dG, A, dA, kappa, dkappa, c, dc, phi, dphi", "", "",
             "@njit(cache=True, error_model=\"numpy\")",
             "def signal_terms(t, x, u, p, d):",
             f"    s, ds = np.zeros({ns}), np.zeros(({ns}, NW))",
             *body(signal_items, "s, ds"), "", "",
             "@njit(cache=True, error_model=\"numpy\")",
             "def energy_terms(t, x, u, p, d):",
             "    E, dE = 0.0, np.zeros(NW)",
             *body([("E", model.energy)], "E, dE"), "", ""]
    for name, make in (("guard_terms", lambda j: [("g", j.guard)]),
                       ("restitution_terms", lambda j: [("e", j.restitution)])):
        out = name[:1] if name == "guard_terms" else "e"
        lines += [f"def {name}(k, {STATE}):", f"    {out}, d{out} = 0.0, np.zeros(NW)"]
        for k, j in enumerate(h.jumps):
            lines += [f"    if k == {k}:", *body(make(j), f"{out}, d{out}", 8)]
        lines += [f"    return {out}, d{out}", "", ""]
    lines += [f"def reset_terms(k, {STATE}):"]
    for k, j in enumerate(h.jumps):
        m = len(j.resets)
        if not m:
            continue
        lines += [f"    if k == {k}:", f"        r, dr = np.zeros({m}), np.zeros(({m}, NW))",
                  *body([(f"r[{i}]", e) for i, (_, e) in enumerate(j.resets)], None, 8),
                  f"        return {[index[s] for s, _ in j.resets]!r}, r, dr"]
    lines += ["    return [], np.zeros(0), np.zeros((0, NW))"]
    return _environment().get_template("derivatives.py.j2").render(
        version=andyc.__version__, name=model.spec.name, build_key=key, nw=nw, functions="\n".join(lines),
        numerics=numerics_package())


def write_derivatives(model: SymbolicModel, out_dir, key: str) -> bool:
    """Write out_dir/<name>/<name>_derivatives.py for the build `key`, unless it holds that text; True when
    written."""
    path = derivatives_path(out_dir, model.spec.name)
    check_output(path, model.spec.files, "generated module")
    if written_constant(path, "BUILD_KEY") == key:
        return False
    return update_text(path, render(model, key))
