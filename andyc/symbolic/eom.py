"""The equations of motion of one flow, written out for reading (`andyc eom`).

A flow's dynamics, in the names of the model file (ANDY paper eq. 5-8, 10-11):

    M(q) dv/dt = G(t, q, v, u)                    unconstrained (eq. 8)
    M = sum_k M_k,  M_k = Jv^T m Jv + Jw^T I Jw   per body (eq. 5)
    G = sum_k G_k + sum_j G_Fj                    inertial terms and gravity (eq. 6), the
                                                  other elements G_F = J^T K zeta (eq. 7)
    M dv/dt = G + A^T lambda,  A dv/dt + kappa = 0,  phi = 0
                                                  with the flow's active constraint rows (eq. 10-11)

and each element's own M_k and G_k. The SymbolicModel writes these over
intermediate symbols (model.assignments); here every intermediate is
substituted back, in order, and each entry is simplified within a budget:
`sp.simplify` for an entry of at most `simplify_ops` operations once written
out, `sp.factor_terms` up to `factor_ops`, nothing beyond (a 7-DOF arm's
entries run to 1e5 operations and more: no closed form reads well there). M is
symmetric: its upper triangle is simplified and mirrored.

Display names: coordinate `q1`, its speed `q1_dot` (LaTeX `\\dot{q}_{1}`), a
quasi-velocity, parameter, input, discrete state or signal by its own name.
An input the flow sets (`flows: [{inputs: ...}]`) is replaced by its value.
"""

from __future__ import annotations

import json
import time
from dataclasses import dataclass

import sympy as sp
from sympy.printing.conventions import split_super_sub
from sympy.printing.str import StrPrinter

from andyc.symbolic.model import SymbolicModel

SIMPLIFY_OPS = 400      # sp.simplify takes up to ~1 s per entry of this size (ball in a bowl, swing bar)
FACTOR_OPS = 20000      # factor_terms beyond this takes seconds per entry and saves little


class EomError(ValueError):
    """An element or flow the model does not have; the message lists the ones it has."""


@dataclass
class Equations:
    """A flow's equations of motion in display symbols; n speeds, r active constraint rows (h holonomic).

    M (n x n), G (n x 1), phi (h x 1), A (r x n), kappa (r x 1) are None when only one element was asked for.
    """
    model: str
    flow: str
    symbols: dict           # display Symbol -> (LaTeX, kind, note); kinds: coordinate, speed, signal,
                            # parameter, input, discrete, time
    speeds: list            # display Symbols of v
    M: sp.Matrix | None
    G: sp.Matrix | None
    rows: list              # "constraint (multiplier)" of each active row
    phi: sp.Matrix | None
    A: sp.Matrix | None
    kappa: sp.Matrix | None
    elements: dict          # element name -> (M_k or None, G_k or None)
    inputs: list            # input names, all (as the generated module's INPUTS)
    inputs_set: dict        # input name -> the value the flow gives it (substituted)
    entries: int = 0        # nonzero entries worked through (M's upper triangle)
    factored: int = 0       # ... of which past simplify_ops: only factor_terms
    as_written: int = 0     # ... past factor_ops: left as written out
    largest: int = 0        # operations of the largest entry, written out
    seconds: float = 0.0

    @property
    def latex_names(self) -> dict:
        return {s: tex for s, (tex, _, _) in self.symbols.items()}


def _legend(model: SymbolicModel, flow: int) -> tuple[dict, dict, dict]:
    """(model symbol -> display symbol, or the value the flow gives an input; display symbol -> (LaTeX, kind,
    note); input name -> the value the flow gives it)."""
    spec = model.spec
    rename, legend, inputs_set = {}, {}, {}

    def add(sym, name, kind, note="", tex=None):
        new = sp.Symbol(name, real=True)
        rename[sym] = new
        legend[new] = (tex or sp.latex(new), kind, note)

    for c in spec.coordinates:
        add(c.q, c.name, "coordinate")
    for c in spec.coordinates:
        base, sups, subs = split_super_sub(c.name)      # q1 -> \dot{q}_{1}, theta -> \dot{\theta}
        tex = sp.latex(sp.Symbol(base + "dot" + "".join("^" + s for s in sups) + "".join("_" + s for s in subs)))
        add(c.v, f"{c.name}_dot", "speed", f"d{c.name}/dt", tex)
    for s in spec.speeds:
        add(s.v, s.name, "speed", "quasi-velocity")
    for s in spec.signals:
        add(s.symbol, s.name, "signal", f"nonholonomic, frame '{s.frame}'")
    for name, (sym, value) in spec.parameters.items():
        add(sym, name, "parameter", f"default {value:g}")
    fixed = model.hybrid.flow_inputs[flow]
    for i, (name, (sym, value)) in enumerate(spec.inputs.items()):
        if i in fixed:
            rename[sym] = inputs_set[name] = sp.sympify(fixed[i]).xreplace(rename)
        else:
            add(sym, name, "input", f"default {value:g}")
    for x in spec.discrete:
        add(x.symbol, x.name, "discrete")
    legend[model.t] = ("t", "time", "")
    return rename, legend, inputs_set


class _Written:
    """The model's intermediate symbols written out in display symbols, with their sizes (count_ops)."""

    def __init__(self, model: SymbolicModel, rename: dict, exprs: list):
        needed = model.intermediates_of(exprs)
        self.values, self.sizes = dict(rename), {}
        for sym, expr in model.assignments:
            if sym in needed:
                self.values[sym] = expr.xreplace(self.values)
                self.sizes[sym] = self.size(expr)

    def size(self, expr) -> int:
        """count_ops of expr with its intermediates written out, from their sizes (no expansion)."""
        return sp.count_ops(expr) + sum(self.sizes.get(a, 0) for a in sp.preorder_traversal(expr) if a.is_Symbol)

    def __call__(self, expr):
        return expr.xreplace(self.values)


def _readable(expr, size: int, simplify_ops: int, factor_ops: int):
    if expr.is_Atom or size > factor_ops:
        return expr
    cheap = sp.factor_terms(expr)
    if size > simplify_ops:
        return cheap
    best = sp.simplify(expr)
    return best if sp.count_ops(best) <= sp.count_ops(cheap) else cheap


def _parts(model: SymbolicModel, rows: list, element: str | None) -> dict:
    """key -> (matrix in the model's symbols, symmetric): M, G and the rows' phi, A, kappa (unless `element`),
    and ("M" or "G", element name) per element."""
    cons = model.constraints
    parts = {}
    if element is None:
        parts["M"], parts["G"] = (model.M, True), (model.G, False)
        holonomic = [r for r in rows if r < cons.nh]
        parts["phi"] = (sp.Matrix(len(holonomic), 1, [cons.phi[r] for r in holonomic]), False)
        parts["A"] = (cons.A.extract(rows, list(range(model.dof))), False)
        parts["kappa"] = (sp.Matrix(len(rows), 1, [cons.kappa[r] for r in rows]), False)
    for e in model.elements:
        if element in (None, e.name):
            for key, mat, sym in ((("M", e.name), e.M, True), (("G", e.name), e.G, False)):
                if mat is not None:
                    parts[key] = (mat, sym)
    return parts


def equations(model: SymbolicModel, flow: str | None = None, element: str | None = None,
              simplify_ops: int = SIMPLIFY_OPS, factor_ops: int = FACTOR_OPS, progress=None) -> Equations:
    """The equations of `flow` (default: the initial one) for reading; only `element`'s M_k, G_k when given.

    progress(done, total, seconds) is called after each entry."""
    start = time.perf_counter()
    spec, hybrid, cons = model.spec, model.hybrid, model.constraints
    if flow is not None and flow not in hybrid.flows:
        raise EomError(f"{spec.name}: no flow named '{flow}'; flows: {', '.join(hybrid.flows)}")
    k = hybrid.initial if flow is None else hybrid.flows.index(flow)
    names = [e.name for e in model.elements]
    if element is not None and element not in names:
        raise EomError(f"{spec.name}: no element named '{element}'; elements: {', '.join(names)}")
    rename, legend, inputs_set = _legend(model, k)
    rows = hybrid.flow_rows[k]
    parts = _parts(model, rows, element)
    written = _Written(model, rename, [x for mat, _ in parts.values() for x in mat])
    cells = [(key, i, j) for key, (mat, sym) in parts.items() for i in range(mat.rows) for j in range(mat.cols)
             if mat[i, j] != 0 and (not sym or j >= i)]
    out = {key: sp.zeros(*mat.shape) for key, (mat, _) in parts.items()}
    largest = factored = as_written = 0
    seen = {}
    for done, (key, i, j) in enumerate(cells, 1):
        raw = parts[key][0][i, j]
        size = written.size(raw)
        largest = max(largest, size)
        factored += simplify_ops < size <= factor_ops
        as_written += size > factor_ops
        expr = written(raw)
        if expr not in seen:        # an element's entry is often the whole's (one body on a joint)
            seen[expr] = _readable(expr, size, simplify_ops, factor_ops)
        out[key][i, j] = seen[expr]
        if parts[key][1]:
            out[key][j, i] = out[key][i, j]
        if progress:
            progress(done, len(cells), time.perf_counter() - start)
    return Equations(
        model=spec.name, flow=hybrid.flows[k], symbols=legend, speeds=[rename[v] for v in model.v],
        M=out.get("M"), G=out.get("G"), rows=[f"{cons.rows[r]} ({cons.multipliers[r]})" for r in rows],
        phi=out.get("phi"), A=out.get("A"), kappa=out.get("kappa"),
        elements={e.name: (out.get(("M", e.name)), out.get(("G", e.name))) for e in model.elements
                  if element in (None, e.name)},
        inputs=list(spec.inputs), inputs_set=inputs_set,
        entries=len(cells), factored=factored, as_written=as_written, largest=largest,
        seconds=time.perf_counter() - start)


# Rendering -----------------------------------------------------------------

def _quantities(eq: Equations) -> list:
    """[(name, LaTeX name, matrix, what)] of what eq holds, whole-system quantities first."""
    out = [(n, tex, m, "") for n, tex, m in (("M", "M", eq.M), ("G", "G", eq.G), ("phi", r"\phi", eq.phi),
                                             ("A", "A", eq.A), ("kappa", r"\kappa", eq.kappa)) if m is not None]
    for name, pair in eq.elements.items():
        label = r"_{\text{" + name.replace("_", r"\_") + "}}"
        out += [(f"{x}_{name}", x + label, m, f"element '{name}': its own {what}")
                for x, m, what in zip("MG", pair, ("mass matrix", "generalized force")) if m is not None]
    return out


def _kinds(eq: Equations) -> dict:
    """kind -> [display symbol]."""
    out = {}
    for sym, (_, kind, _) in eq.symbols.items():
        out.setdefault(kind, []).append(sym)
    return out


def decimals(mat):
    """`mat` with each rational whose denominator is a power of ten (a number the model file wrote as a
    decimal, 1.0e-7, which andyc keeps exact as 1/10000000) as that decimal: for reading. The derivation's
    own fractions (1/2, 1/12) stay; the sympy format, which must read back exactly, keeps them all."""
    def decimal(r):
        q = r.q
        while q % 10 == 0:
            q //= 10
        return q == 1 and r.q > 1

    found = {r: sp.Float(repr(float(r))) for r in mat.atoms(sp.Rational) if decimal(r)}
    return mat.xreplace(found) if found else mat


def to_latex(eq: Equations, standalone: bool = False) -> str:
    """An `equation` block per quantity (a fragment, or with `standalone` a document); comment lines say
    what the symbols are."""
    tex = eq.latex_names
    legend = "; ".join(f"{kind}: " + ", ".join(str(s) if tex[s] == str(s) else f"{s} = {tex[s]}" for s in syms)
                       for kind, syms in _kinds(eq).items())
    lines = [f"% andyc eom: model '{eq.model}', flow '{eq.flow}'",
             r"% M \dot{v} = G (ANDY eq. 5-8); with constraint rows M \dot{v} = G + A^T \lambda, "
             r"A \dot{v} + \kappa = 0, \phi = 0 (eq. 10-11)",
             f"% symbols: {legend}"]
    if eq.inputs_set:
        lines.append(f"% inputs set by flow '{eq.flow}': " + ", ".join(f"{k} = {v}" for k, v in eq.inputs_set.items()))
    if len(eq.speeds) > 10:     # amsmath's matrix takes 10 columns unless told
        lines.append(rf"\setcounter{{MaxMatrixCols}}{{{len(eq.speeds)}}}")
    if eq.M is not None:
        lines += [r"\begin{equation}", r"M \dot{v} = G, \quad v = " + sp.latex(sp.Matrix(eq.speeds), symbol_names=tex),
                  r"\end{equation}", "% active constraint rows: " + (", ".join(eq.rows) or "none")]
    for _, label, mat, what in _quantities(eq):
        if mat.rows:
            lines += [f"% {what}"] if what else []
            lines += [r"\begin{equation}", f"{label} = {sp.latex(decimals(mat), symbol_names=tex)}",
                      r"\end{equation}"]
    body = "\n".join(lines) + "\n"
    if standalone:
        return ("\\documentclass{article}\n\\usepackage{amsmath}\n\\usepackage[margin=1.5cm]{geometry}\n"
                f"\\begin{{document}}\n{body}\\end{{document}}\n")
    return body


class _PythonPrinter(StrPrinter):
    """str() that Python reads back exactly after `from sympy import *`: Rational(p, q), every digit of a
    Float, each symbol by its variable's name."""

    def __init__(self, variables: dict):
        super().__init__()
        self.variables = variables

    def _print_Symbol(self, expr):
        return self.variables.get(expr, expr.name)

    def _print_Rational(self, expr):
        return f"Rational({expr.p}, {expr.q})"

    def _print_Float(self, expr):
        return sp.srepr(expr)


def to_sympy(eq: Equations) -> str:
    """A Python file: `from sympy import *`, the symbols, then rows, M, G, phi, A, kappa and `elements`.
    A symbol whose name sympy or the file already uses gets a trailing underscore as its variable."""
    taken = set(dir(sp)) | {"M", "G", "phi", "A", "kappa", "rows", "elements"}
    variables = {}
    for sym in eq.symbols:
        name = sym.name
        while name in taken:
            name += "_"
        taken.add(name)
        variables[sym] = name
    pr = _PythonPrinter(variables).doprint
    lines = [f'"""Equations of motion of model \'{eq.model}\' in flow \'{eq.flow}\' (andyc eom; ANDY eq. 5-8).',
             "",
             f"M dv/dt = G with v = [{', '.join(map(str, eq.speeds))}]; with constraint rows (`rows`) also",
             "M dv/dt = G + A^T lambda, A dv/dt + kappa = 0, phi = 0 (eq. 10-11).",
             "elements: {name: (M_k, G_k)}, None where the element adds nothing.",
             *([f"Inputs set by the flow: {', '.join(f'{k} = {v}' for k, v in eq.inputs_set.items())}."]
               if eq.inputs_set else []),
             '"""', "from sympy import *  # noqa: F401,F403", ""]
    for s, (_, kind, note) in eq.symbols.items():
        lines.append(f"{variables[s]} = Symbol({s.name!r}, real=True)  # {kind}" + (f", {note}" if note else ""))
    lines.append("")
    if eq.M is not None:
        lines.append(f"rows = {eq.rows!r}")
    lines += [f"{name} = {pr(mat)}" for name, _, mat, what in _quantities(eq) if not what]
    lines.append("elements = {}")
    for name, (M, G) in eq.elements.items():
        lines.append(f"elements[{name!r}] = (\n{None if M is None else pr(M)},\n{None if G is None else pr(G)})")
    return "\n".join(lines) + "\n"


def to_json(eq: Equations) -> str:
    """Model, flow, names, and each quantity as {shape, str: entries as sympy str, latex} (null when absent)."""
    tex = eq.latex_names

    def quantity(mat):
        if mat is None:
            return None
        return {"shape": list(mat.shape), "str": [[str(mat[i, j]) for j in range(mat.cols)] for i in range(mat.rows)],
                "latex": sp.latex(decimals(mat), symbol_names=tex)}

    kinds = {kind: [s.name for s in syms] for kind, syms in _kinds(eq).items()}
    return json.dumps({
        "model": eq.model, "flow": eq.flow,
        "states": kinds.get("coordinate", []) + kinds.get("speed", []) + kinds.get("signal", []),
        "coordinates": kinds.get("coordinate", []), "speeds": kinds.get("speed", []),
        "signals": kinds.get("signal", []), "parameters": kinds.get("parameter", []),
        "inputs": eq.inputs, "discrete": kinds.get("discrete", []),
        "symbols": {s.name: {"latex": t, "kind": kind, "note": note} for s, (t, kind, note) in eq.symbols.items()},
        "inputs_set": {k: str(v) for k, v in eq.inputs_set.items()},
        "constraint_rows": eq.rows if eq.M is not None else None,
        **{k: quantity(m) for k, m in (("M", eq.M), ("G", eq.G), ("phi", eq.phi), ("A", eq.A), ("kappa", eq.kappa))},
        "elements": {name: {"M": quantity(M), "G": quantity(G)} for name, (M, G) in eq.elements.items()},
    }, indent=1) + "\n"


FORMATS = ("latex", "sympy", "json")


def equations_text(eq: Equations, fmt: str, standalone: bool = False) -> str:
    """eq as text in one of FORMATS (`standalone`: a whole LaTeX document)."""
    return to_latex(eq, standalone) if fmt == "latex" else {"sympy": to_sympy, "json": to_json}[fmt](eq)
