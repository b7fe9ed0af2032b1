"""Constraint residuals, Jacobian and velocity-product term (ANDY eq. 10-12; Braun & Goldfarb Part II §2).

With speeds v (coordinate rates first) the active constraints give

    phi(t, q)        holonomic residuals Gamma                          (nh rows)
    c(t, q, v)       velocity-level residuals: dGamma/dt = A v + b, then the
                     nonholonomic rows Phi_v as written               (nc rows)
    A = dc/dv        their velocity Jacobian, at the state
    kappa            dc/dt at dv/dt = 0, so that dc/dt = A dv/dt + kappa  (eq. 11:
                     the J' v term, with the explicit d/dt terms of rheonomic rows)

A nonholonomic row may be nonlinear in v (Braun & Goldfarb §2.2.3: Phi_v(t, q, v) = 0,
Appell-Hamel's z' - k sqrt(x'^2 + y'^2), Gauss's isokinetic |v|^2 - c). Nothing
below assumes linearity: differentiating the row along the motion gives
dPhi_v/dt = A dv/dt + kappa with A = dPhi_v/dv and kappa = dPhi_v/dt + dPhi_v/dq q'
(+ the frame quantities' terms), both evaluated at the current state, so the
multiplier solve (A M^-1 A^T lam = -kappa - A a) and the projection's one-pass
velocity correction (eq. 4: v <- v - M^-1 A^T (A M^-1 A^T)^+ Phi_v, A at the
state: one Newton step on Phi_v, no iteration) take such rows unchanged. For a
linear row J v + b these are J and J' v + db/dt, as before.

A row is a small user expression f in t, q, v and frame-quantity symbols
(`tip.x`, `tip.vx`, `tip.wx`; model.FrameQuantity). It is differentiated as
written, and each frame quantity enters through its own rate, taken from the
recursive kinematics (so nothing large is differentiated):

    rate(f) = df/dt + sum_i df/dq_i v_i + sum_P df/dP Pdot + sum_V df/dV kappa_V
    jac(f)  = df/dv + sum_V df/dV J_V

for positions P (whose rate Pdot is itself a velocity quantity) and velocity
quantities V = J_V v + b_V (with dV/dt = J_V dv/dt + kappa_V). With F the
`in` frame, d = r_A - r_F and d' = v_A - v_F:

    P = R_F^T d              Pdot = R_F^T (d' - w_F x d)
                             J = R_F^T (Jv_A - Jv_F + [d]x Jw_F)
                             kappa = R_F^T (ac_A - ac_F - al_F x d - 2 w_F x d' + w_F x (w_F x d))
    V = R_F^T v_A            J = R_F^T Jv_A     kappa = R_F^T (ac_A - w_F x v_A)
    W = R_F^T w_A            J = R_F^T Jw_A     kappa = R_F^T (al_A - w_F x w_A)

since d/dt R_F^T = -R_F^T [w_F]x. Holonomic rows: c = rate(Gamma),
A = jac(c), kappa = rate(c); nonholonomic rows: c = f, A = jac(f),
kappa = rate(f).
"""

from __future__ import annotations

from dataclasses import dataclass

import sympy as sp

from andyc.spec.expressions import TIME
from andyc.spec.model import Spec
from andyc.symbolic.emitter import Emitter
from andyc.symbolic.kinematics import FrameKinematics, cross, skew


@dataclass
class ConstraintTerms:
    rows: list              # constraint name of each velocity-level row
    multipliers: list       # multiplier name of each row
    phi: sp.Matrix          # nh x 1
    c: sp.Matrix            # nc x 1
    A: sp.Matrix            # nc x n
    kappa: sp.Matrix        # nc x 1
    stiffness: list         # K_s per row (0 for nonholonomic rows)
    damping: list           # K_d per row

    @property
    def nh(self) -> int:
        return self.phi.shape[0]

    @property
    def nc(self) -> int:
        return self.c.shape[0]


@dataclass
class _Rate:
    """A velocity-like quantity V = J v + b: its Jacobian row and kappa = dV/dt at dv/dt = 0."""
    J: list
    kappa: sp.Expr


class FrameQuantities:
    """Frame quantities as emitted symbols, each defined once from the frame kinematics,
    and the rate and speed Jacobian of expressions that use them (see the module docstring)."""

    def __init__(self, spec: Spec, kin: dict[str, FrameKinematics], emit: Emitter):
        self.kin, self.emit = kin, emit
        self.q = [c.q for c in spec.coordinates]
        self.v = spec.speed_symbols
        self.n = len(self.v)
        self.rates: dict[sp.Symbol, _Rate] = {}     # velocity-like symbol -> rate
        self.position_rate: dict[sp.Symbol, sp.Symbol] = {}   # position symbol -> its Pdot symbol
        self.vectors: dict = {}

    def rate(self, f) -> sp.Expr:
        """df/dt at dv/dt = 0."""
        # Only by the coordinates f holds (the others give zero terms): a row's few, not the model's.
        held = f.free_symbols
        out = sp.diff(f, TIME) + sum((sp.diff(f, qi) * vi for qi, vi in zip(self.q, self.v) if qi in held),
                                     sp.Integer(0))
        for sym in f.free_symbols:
            if sym in self.position_rate:
                out += sp.diff(f, sym) * self.position_rate[sym]
            elif sym in self.rates:
                out += sp.diff(f, sym) * self.rates[sym].kappa
        return out

    def jac(self, f) -> list:
        """df/dv: with rate(f), df/dt = rate(f) + jac(f) dv/dt."""
        held = f.free_symbols
        row = [sp.diff(f, vi) if vi in held else sp.S.Zero for vi in self.v]
        for sym in held & set(self.rates):
            df = sp.diff(f, sym)
            row = [r + df * J if J != 0 else r for r, J in zip(row, self.rates[sym].J)]
        return row

    def define(self, sym: sp.Symbol, fq) -> None:
        if sym in self.rates or sym in self.position_rate:
            return
        value, J, kappa = self._vectors(fq.frame, fq.in_frame, fq.kind)
        a = fq.axis
        rate = _Rate(list(J[a, :]), kappa[a])
        if fq.kind == "position":
            self.emit.define(sym, value[a][0])
            dot = self.emit.define(sp.Symbol(f"{sym}_dot", real=True), value[a][1])
            self.position_rate[sym] = dot
            self.rates[dot] = rate
        else:
            self.emit.define(sym, value[a])
            self.rates[sym] = rate

    def _vectors(self, frame: str, in_frame: str, kind: str):
        """(value, J, kappa) of a frame quantity; for positions value[i] = (P_i, Pdot_i)."""
        key = (frame, in_frame, kind)
        if key not in self.vectors:
            A, F = self.kin[frame], self.kin[in_frame]
            RT = F.R.T
            label = f"k{len(self.vectors)}"
            if kind == "position":
                d = A.r - F.r
                dd = A.v - F.v
                value = list(zip(RT * d, RT * (dd - cross(F.w, d))))
                J = RT * (A.Jv - F.Jv + skew(d) * F.Jw)
                kappa = RT * (A.ac - F.ac - cross(F.al, d) - 2 * cross(F.w, dd) + cross(F.w, cross(F.w, d)))
            elif kind == "velocity":
                value, J, kappa = RT * A.v, RT * A.Jv, RT * (A.ac - cross(F.w, A.v))
            else:
                value, J, kappa = RT * A.w, RT * A.Jw, RT * (A.al - cross(F.w, A.w))
            self.vectors[key] = (value, self.emit.matrix(f"{label}J", J) if self.n else J,
                                 self.emit.matrix(f"{label}k", kappa))
        return self.vectors[key]


def constraint_terms(spec: Spec, quantities: FrameQuantities) -> ConstraintTerms:
    """phi, c, A and kappa of every constraint of `spec` (holonomic rows first)."""
    n = quantities.n
    rate, jac = quantities.rate, quantities.jac
    for con in spec.constraints:
        for sym, fq in con.quantities.items():
            quantities.define(sym, fq)

    phi, c, A, kappa, names, lams, ks, kd = [], [], [], [], [], [], [], []
    for con in spec.constraints:
        for row, lam in zip(con.rows, con.multipliers):
            if con.holonomic:
                phi.append(row)
                row = rate(row)
            c.append(row)
            A.append(jac(row))
            kappa.append(rate(row))
            names.append(con.name)
            lams.append(lam)
            ks.append(con.stiffness if con.holonomic else sp.Integer(0))
            kd.append(con.damping)
    return ConstraintTerms(names, lams, sp.Matrix(phi), sp.Matrix(c),
                           sp.Matrix(len(c), n, lambda i, j: A[i][j]) if c else sp.zeros(0, n),
                           sp.Matrix(kappa), ks, kd)
