"""Elements -> equations of motion M dv/dt = G (ANDY paper eq. 5-8).

Body at frame k (COM at the origin), mass m, inertia I (own axes), with the
angular quantities in the body's own axes (wb, Jwb, alb; see kinematics):

    M_k = Jv^T m Jv + Jwb^T I Jwb                                     (eq. 5)
    G_k = Jv^T m (g - ac) - Jwb^T (I alb + wb x I wb)                 (eq. 6)

Every other element has virtual power A = chi^T K zeta (Table 1) and adds
G = J_chi^T K zeta (eq. 7):

    force F written in frame e at frame f      G += Jv_f^T R_e F
    torque T written in frame e on frame f     G += Jw_f^T R_e T
    linear damper on chi                       G -= b J_chi^T chi
    quadratic damper on chi                    G -= b |chi| J_chi^T chi
    spring of length x(q) or |r_a - r_b|       G -= k (x - x0) dx/dq
    potential V(q, t)                          G -= dV/dq

Each element states its terms as pairs (J, f): G += J^T f, and (J, W):
M += J^T W J. The sums (eq. 8) first add the f and W of elements that share
a Jacobian (a body and the damper at its COM; the bars of one rigid body),
then multiply once. The energy is the kinetic energy plus gravity, spring and
potential energy; `power` is the power of each element that does work (forces,
torques, dampers; springs and potentials by their explicit dependence on t: see
work.py, which adds the constraints').
"""

from __future__ import annotations

from dataclasses import dataclass, field

import sympy as sp

from andyc.errors import SpecError
from andyc.spec.constraints import driven_frames
from andyc.spec.model import Spec
from andyc.symbolic.emitter import Emitter
from andyc.symbolic.kinematics import FrameKinematics, cross
from andyc.symbolic.work import time_power


@dataclass
class ElementTerms:
    """What one element contributes: M += sum J^T W J, G += sum J^T f + G_direct."""
    name: str
    inertia: list = field(default_factory=list)     # [(J 3 x n, W 3 x 3 or scalar)]
    loads: list = field(default_factory=list)       # [(J 3 x n, f 3 x 1)]
    G_direct: sp.Matrix | None = None               # n x 1, for elements on speeds or coordinates
    energy: sp.Expr = sp.Integer(0)
    power: sp.Expr = sp.Integer(0)
    drive: tuple = ()       # (a, b): its share a . dv/dt + b of the power that drives the links depending on t (work.py)

    @property
    def M(self) -> sp.Matrix | None:
        """This element's own mass-matrix term (the assembly groups them instead)."""
        terms = [J.T * W * J for J, W in self.inertia]
        return sum(terms[1:], terms[0]) if terms else None

    @property
    def G(self) -> sp.Matrix | None:
        """This element's own generalized force."""
        terms = [J.T * f for J, f in self.loads] + ([self.G_direct] if self.G_direct is not None else [])
        return sum(terms[1:], terms[0]) if terms else None


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
    driven = set(driven_frames(spec.frames))

    def moved(K) -> tuple:
        """The velocity and own-axes angular velocity a frame has at zero speeds: its motion along t."""
        return K.v - K.Jv * v, K.wb - K.Jwb * v

    for b in spec.bodies:
        K = kin[b.frame]
        terms = ElementTerms(b.name, inertia=[(K.Jv, b.mass * sp.eye(3))], loads=[(K.Jv, b.mass * (spec.gravity - K.ac))],
                             energy=(b.mass * K.v.dot(K.v) + K.wb.dot(b.inertia * K.wb)) / 2
                             - b.mass * spec.gravity.dot(K.r))
        if b.inertia != sp.zeros(3, 3):
            Iw = b.inertia * K.wb
            terms.inertia.append((K.Jwb, b.inertia))
            terms.loads.append((K.Jwb, -(b.inertia * K.alb + cross(K.wb, Iw))))
        if b.frame in driven:       # m (a - g) . V_t + (I alb + wb x I wb) . W_t, a = Jv dv/dt + ac
            Vt, Wt = moved(K)
            terms.drive = (b.mass * K.Jv.T * Vt + K.Jwb.T * b.inertia * Wt,
                           b.mass * (K.ac - spec.gravity).dot(Vt)
                           + (b.inertia * K.alb + cross(K.wb, b.inertia * K.wb)).dot(Wt))
        out.append(terms)
    for f in spec.loads:
        K = kin[f.frame]
        if f.kind == "torque" and f.in_frame == f.frame:    # already in the body's axes
            J, rate, vec = K.Jwb, K.wb, f.vector
        else:
            vec = kin[f.in_frame].R * f.vector
            J, rate = (K.Jv, K.v) if f.kind == "force" else (K.Jw, K.w)
        out.append(_driven(ElementTerms(f.name, loads=[(J, vec)], power=rate.dot(vec)), f.frame in driven, v))
    for a in spec.actuators:            # a generalized force on one speed, clamped to its limit
        j = damped.index(a.speed)
        J = sp.zeros(1, n)
        J[0, j] = 1
        force = a.force if a.limit is None else sp.Min(sp.Max(a.force, -a.limit), a.limit)
        out.append(ElementTerms(a.name, loads=[(J, sp.Matrix([force]))], power=force * v[j]))
    for d in spec.dampers:
        if d.law == "coulomb":          # (dry friction: the moreau method's bounded rows, not a smooth force)
            continue
        if d.speed is not None:
            j = damped.index(d.speed)
            J = sp.zeros(1, n)
            J[0, j] = 1
            chi = sp.Matrix([v[j]])
        else:
            K = kin[d.frame]
            J, chi = (K.Jwb, K.wb) if d.angular else (K.Jv, K.v)
        gain = d.coefficient * (_norm(chi) if d.law == "quadratic" else 1)
        out.append(_driven(ElementTerms(d.name, loads=[(J, -gain * chi)], power=-gain * chi.dot(chi)),
                           d.frame in driven, v))
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
        energy = s.stiffness * stretch ** 2 / 2
        terms = ElementTerms(s.name, G_direct=-s.stiffness * stretch * dx, energy=energy, power=time_power(energy))
        if s.between is not None and set(s.between) & driven:   # k (x - x0) dx/dt at zero speeds
            (Va, _), (Vb, _) = moved(kin[s.between[0]]), moved(kin[s.between[1]])
            terms.drive = (sp.zeros(n, 1), s.stiffness * stretch * delta.dot(Va - Vb) / x)
        out.append(terms)
    for p in spec.potentials:
        out.append(ElementTerms(p.name, G_direct=-gradient(p.energy), energy=p.energy, power=time_power(p.energy)))
    return out


def _driven(terms: ElementTerms, driven: bool, v: sp.Matrix) -> ElementTerms:
    """A force, torque or damper on a frame moved along t: the power its force f has along that motion, counted in
    its own power P = f . (J v + V_t) and not in the equations' f . J v, goes to the drive with the sign that
    balances the energy: f . J v - P (= -f . V_t)."""
    if driven:
        (J, f), = terms.loads
        terms.drive = (sp.zeros(len(v), 1), f.dot(J * v) - terms.power)
    return terms


def _entries(J: sp.Matrix) -> tuple:
    """J's shape and nonzero entries, a key equal for equal matrices: a Jacobian's few nonzero columns, not its
    3 x n entries (a model's bodies times its speeds would make the assembly quadratic in its size)."""
    return J.shape, tuple(sorted(J.todok().items()))


def assemble(spec: Spec, terms: list[ElementTerms]):
    """Sum the element terms (eq. 8); check that every speed moves mass."""
    n = len(spec.speed_symbols)
    M = sp.zeros(n, n)
    G = sp.zeros(n, 1)
    energy = sp.Integer(0)
    power = sp.Integer(0)
    inertia: dict = {}      # Jacobian entries -> (J, summed W)
    loads: dict = {}        # Jacobian entries -> (J, summed f)
    for e in terms:
        for J, W in e.inertia:
            key = _entries(J)
            inertia[key] = (J, inertia[key][1] + W if key in inertia else W)
        for J, f in e.loads:
            key = _entries(J)
            loads[key] = (J, loads[key][1] + f if key in loads else f)
        if e.G_direct is not None:
            G += e.G_direct
        energy += e.energy
        power += e.power
    for J, W in inertia.values():
        M += J.T * W * J
    for J, f in loads.values():
        G += J.T * f
    owners = [("coordinate", c) for c in spec.coordinates] + [("speed", s) for s in spec.speeds]
    idle = [owners[j] for j in range(n) if all(M[j, i] == 0 for i in range(n))]
    if idle:
        raise SpecError([spec.source.diag(x.where, f"{kind} '{x.name}' moves no mass or inertia, so the "
                                          "mass matrix is singular",
                                          "use it in a link that carries a body, or remove it")
                         for kind, x in idle])
    return M, G, energy, power
