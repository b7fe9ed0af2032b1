"""Elements -> equations of motion M(q) dv/dt = G(q, v, t) (ANDY paper eq. 5-8).

Body k at frame k (COM at the origin), mass m, inertia I (frame axes),
I_w = R_k I R_k^T:

    M_k = Jv^T m Jv + Jw^T I_w Jw                                    (eq. 5)
    G_k = -Jv^T m ac - Jw^T (I_w al + w x I_w w)    (inertial, eq. 6)
          + Jv^T m g                                 (gravity, Table 1)

Every other element has virtual power A = chi^T K zeta (Table 1) and adds
G = J_chi^T K zeta (eq. 7):

    force F written in frame e at frame f      G += Jv_f^T R_e F
    torque T written in frame e on frame f     G += Jw_f^T R_e T
    linear damper on chi                       G -= b J_chi^T chi
    quadratic damper on chi                    G -= b |chi| J_chi^T chi
    spring of length x(q) or |r_a - r_b|       G -= k (x - x0) dx/dq
    potential V(q, t)                          G -= dV/dq

The total M and G are the sums over elements (eq. 8). The energy is the
kinetic energy plus gravity, spring and potential energy; `power` is the
power of the non-conservative elements (forces, torques, dampers), so that
dE/dt = power for models whose potentials do not depend on t.
"""

from __future__ import annotations

from dataclasses import dataclass

import sympy as sp

from andyc.errors import SpecError
from andyc.spec.model import Spec
from andyc.symbolic.emitter import Emitter
from andyc.symbolic.kinematics import FrameKinematics, cross


@dataclass
class ElementTerms:
    """What one element contributes: to M, to G, to energy, to power."""
    name: str
    M: sp.Matrix | None = None
    G: sp.Matrix | None = None
    energy: sp.Expr = sp.Integer(0)
    power: sp.Expr = sp.Integer(0)


def _norm(vec: sp.Matrix) -> sp.Expr:
    return sp.sqrt(sum(x ** 2 for x in vec))


def element_terms(spec: Spec, kin: dict[str, FrameKinematics], emit: Emitter) -> list[ElementTerms]:
    q = [c.q for c in spec.coordinates]
    v = sp.Matrix(spec.speed_symbols)
    n = len(v)
    damped = [c.name for c in spec.coordinates] + [s.name for s in spec.speeds]

    def gradient(expr) -> sp.Matrix:
        """d expr / dq, one entry per speed (zero for quasi-velocities)."""
        return sp.Matrix([sp.diff(expr, qi) for qi in q] + [0] * (n - len(q)))
    out = []
    for b in spec.bodies:
        K = kin[b.frame]
        k = K.index
        Iw = emit.matrix(f"b{k}I", K.R * b.inertia * K.R.T) if b.inertia != sp.zeros(3, 3) else sp.zeros(3, 3)
        IwJw = emit.matrix(f"b{k}W", Iw * K.Jw) if Iw != sp.zeros(3, 3) else sp.zeros(3, n)
        M = b.mass * (K.Jv.T * K.Jv) + K.Jw.T * IwJw
        h = Iw * K.al + cross(K.w, Iw * K.w)
        G = K.Jv.T * (b.mass * (spec.gravity - K.ac)) - K.Jw.T * h
        T = (b.mass * K.v.dot(K.v) + K.w.dot(Iw * K.w)) / 2
        V = -b.mass * spec.gravity.dot(K.r)
        out.append(ElementTerms(b.name, M=M, G=G, energy=T + V))
    for f in spec.loads:
        K = kin[f.frame]
        vec = kin[f.in_frame].R * f.vector
        J, rate = (K.Jv, K.v) if f.kind == "force" else (K.Jw, K.w)
        out.append(ElementTerms(f.name, G=J.T * vec, power=rate.dot(vec)))
    for d in spec.dampers:
        if d.speed is not None:
            j = damped.index(d.speed)
            J = sp.zeros(1, n)
            J[0, j] = 1
            chi = sp.Matrix([v[j]])
        else:
            K = kin[d.frame]
            J, chi = (K.Jw, K.w) if d.angular else (K.Jv, K.v)
        gain = d.coefficient * (_norm(chi) if d.law == "quadratic" else 1)
        out.append(ElementTerms(d.name, G=-gain * (J.T * chi), power=-gain * chi.dot(chi)))
    for s in spec.springs:
        if s.length is not None:
            x = s.length
            dx = gradient(x)
        else:
            a, b = kin[s.between[0]], kin[s.between[1]]
            delta = a.r - b.r
            x = emit.scalar(f"s_{s.name}_len", _norm(delta))
            dx = (a.Jv - b.Jv).T * delta / x
        stretch = x - s.rest_length
        out.append(ElementTerms(s.name, G=-s.stiffness * stretch * dx, energy=s.stiffness * stretch ** 2 / 2))
    for p in spec.potentials:
        out.append(ElementTerms(p.name, G=-gradient(p.energy), energy=p.energy))
    return out


def assemble(spec: Spec, terms: list[ElementTerms]):
    """Sum the element terms (eq. 8); check that every speed moves mass."""
    n = len(spec.speed_symbols)
    M = sp.zeros(n, n)
    G = sp.zeros(n, 1)
    energy = sp.Integer(0)
    power = sp.Integer(0)
    for e in terms:
        if e.M is not None:
            M += e.M
        if e.G is not None:
            G += e.G
        energy += e.energy
        power += e.power
    owners = [("coordinate", c) for c in spec.coordinates] + [("speed", s) for s in spec.speeds]
    idle = [owners[j] for j in range(n) if all(M[j, i] == 0 for i in range(n))]
    if idle:
        raise SpecError([spec.source.diag(x.where, f"{kind} '{x.name}' moves no mass or inertia, so the "
                                          "mass matrix is singular",
                                          "use it in a link that carries a body, or remove it")
                         for kind, x in idle])
    return M, G, energy, power
