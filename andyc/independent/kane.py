"""Kane's method on a random serial chain (andyc.independent.chains): the same system as andyc derives
from the chain's YAML, derived with sympy.physics.mechanics alone (no andyc.symbolic or andyc.codegen).

With generalized speeds u = dq/dt, Kane's equations read

    sum_i  [ m_i a_Ci . dv_Ci/du_r + (I_i alpha_i + w_i x I_i w_i) . dw_i/du_r ]
        = sum_i m_i g e_g . dv_Ci/du_r,           r = 1..n,

i.e.  M(q) du/dt = forcing(q, u), where forcing holds gravity and every velocity-product term: andyc's
convention M dv/dt = G with v = dq/dt.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field
from functools import cached_property

import numpy as np
import sympy as sp
from sympy.physics import mechanics as me

from andyc.independent.chains import Chain, unit_axis

__all__ = ["KaneModel", "kane_model"]


def _const(x):
    """A chain constant as SymPy: floats stay Floats, 'pi/2'-style strings are exact."""
    return sp.sympify(x, locals={"pi": sp.pi}) if isinstance(x, str) else sp.Float(float(x))


def _frame_vector(frame: me.ReferenceFrame, values) -> me.Vector:
    x, y, z = (_const(v) for v in values)
    return x * frame.x + y * frame.y + z * frame.z


def _float_matrix(a) -> sp.Matrix:
    return sp.Matrix(3, 3, [sp.Float(float(x)) for x in np.asarray(a).ravel()])


def _fixed_frame(parent: me.ReferenceFrame, R: np.ndarray, name: str) -> me.ReferenceFrame:
    """A frame C fixed in `parent` with parent.dcm(C) = R (parent components = R @ C components)."""
    child = me.ReferenceFrame(name)
    child.orient_explicit(parent, _float_matrix(R))   # orient_explicit takes parent.dcm(child)
    child.set_ang_vel(parent, 0)
    return child


def _revolute_frame(parent, R: np.ndarray, k: np.ndarray, q, u, name: str) -> me.ReferenceFrame:
    """The frame L with parent.dcm(L) = R Rot(k, q) and angular velocity u k (k in L axes).

    Rodrigues, Rot(k, q) = I + sin(q) K + (1 - cos(q)) K^2 with K = [k]x, so
    R Rot(k, q) = R (I + K^2) + sin(q) R K - cos(q) R K^2: one DCM per link, with
    numeric coefficients. As Rot(k, q) k = k, the relative angular velocity is
    q' k in the axes after R, i.e. u k in L's own axes.
    """
    K = np.array([[0.0, -k[2], k[1]], [k[2], 0.0, -k[0]], [-k[1], k[0], 0.0]])
    dcm = (_float_matrix(R @ (np.eye(3) + K @ K)) + sp.sin(q) * _float_matrix(R @ K)
           - sp.cos(q) * _float_matrix(R @ K @ K))
    frame = me.ReferenceFrame(name)
    frame.orient_explicit(parent, dcm)
    frame.set_ang_vel(parent, u * _frame_vector(frame, k))
    return frame


@dataclass
class KaneModel:
    """Kane's equations M(q) du/dt = forcing(q, u) of a chain, with u = dq/dt.

    q, u: the dynamicsymbols; params: parameter symbols (g, m1..mn) with defaults
    param_values; mass_matrix, forcing: SymPy matrices in plain symbols q_sym, v_sym,
    params; derive_seconds: wall time of KanesMethod(...) + kanes_equations(...);
    setup_seconds: the kinematics before it (frames, points, velocities).
    M(q, v) and forcing(q, v) evaluate numerically (numpy arrays, default
    parameters unless p is given, p in the order of `params`).
    """
    chain: Chain
    kane: me.KanesMethod
    q: list
    u: list
    q_sym: tuple
    v_sym: tuple
    params: tuple
    param_values: np.ndarray
    mass_matrix: sp.Matrix
    forcing_vector: sp.Matrix
    derive_seconds: float
    setup_seconds: float
    _fn: object = field(default=None, repr=False)

    @cached_property
    def cse(self) -> tuple:
        """sympy.cse over every entry of mass_matrix, then every entry of forcing."""
        return sp.cse(list(self.mass_matrix) + list(self.forcing_vector))

    @cached_property
    def ops_after_cse(self) -> int:
        """sum(count_ops) over the cse replacements and the reduced expressions."""
        replacements, reduced = self.cse
        return int(sum(sp.count_ops(e) for _, e in replacements) + sum(sp.count_ops(e) for e in reduced))

    @cached_property
    def ops_before_cse(self) -> int:
        return int(sum(sp.count_ops(e) for e in list(self.mass_matrix) + list(self.forcing_vector)))

    def _evaluate(self, q, v, p=None) -> tuple[np.ndarray, np.ndarray]:
        if self._fn is None:
            replacements, reduced = self.cse
            self._fn = sp.lambdify([self.q_sym, self.v_sym, self.params], reduced, modules="numpy",
                                   cse=lambda exprs: (replacements, exprs))
        p = self.param_values if p is None else p
        n = len(self.q)
        values = np.array(self._fn(np.asarray(q, float), np.asarray(v, float), np.asarray(p, float)),
                          dtype=float)
        return values[:n * n].reshape(n, n), values[n * n:]

    def M(self, q, v=None, p=None) -> np.ndarray:
        """Mass matrix at q (v is ignored: M depends on q only)."""
        return self._evaluate(q, np.zeros(len(self.q)) if v is None else v, p)[0]

    def forcing(self, q, v, p=None) -> np.ndarray:
        """Generalized forces: gravity and velocity-product terms, M du/dt = forcing."""
        return self._evaluate(q, v, p)[1]


def kane_model(chain: Chain) -> KaneModel:
    """Derive `chain` with sympy.physics.mechanics.KanesMethod.

    Kinematics, one ReferenceFrame per link: parent.dcm(L_i) is R Rot(k, q_i)
    for an axis-form revolute joint (angular velocity u_i k), R for a prismatic
    one (then point P_i = P + q_i k, velocity u_i k in L_i), and Rz(theta) Rx(alpha)
    for a DH row (angular velocity theta' z_parent; origin P + d z_parent + a x_L).
    Points come from Point.locatenew; velocities from v2pt_theory (points fixed
    in a frame) or v1pt_theory (a prismatic joint's moving point). A tool frame
    is folded into its body numerically (COM t_T + R_T c, inertia R_T I R_T^T).
    Bodies are RigidBody with inertia about the COM in the body frame; gravity is
    the force m_i g e_g at each COM. Generalized speeds u_i = q_i' (kd_eqs
    q_i' - u_i = 0). Masses and g stay symbols (as in andyc, where they are
    runtime parameters); every other constant is a Float (or exact, like pi/2).

    derive_seconds times KanesMethod(...) + kanes_equations(...) only.
    """
    t0 = time.perf_counter()
    n = chain.n
    q = [me.dynamicsymbols(f"q{i + 1}") for i in range(n)]
    u = [me.dynamicsymbols(f"u{i + 1}") for i in range(n)]
    g = sp.Symbol("g", real=True)
    masses = [sp.Symbol(link.mass_parameter, real=True) for link in chain.links]

    N = me.ReferenceFrame("N")
    O = me.Point("O")
    O.set_vel(N, 0)
    gravity = g * _frame_vector(N, chain.gravity)

    frame, point = N, O
    bodies, loads = [], []
    for link, qi, ui, mi in zip(chain.links, q, u, masses):
        k = link.index
        if link.translation is not None:                     # Trans(t), t in parent axes
            moved = point.locatenew(f"P{k}t", _frame_vector(frame, link.translation))
            moved.v2pt_theory(point, N, frame)
            point = moved
        R = np.eye(3) if link.rotation is None else link.rotation.matrix()
        if link.dh is None:
            axis = unit_axis(link.axis)
            if link.joint == "revolute":                     # Rot(R) Rot(k, q): one frame
                frame = _revolute_frame(frame, R, axis, qi, ui, f"L{k}")
            else:                                            # Rot(R) Trans(q k)
                if link.rotation is not None:
                    frame = _fixed_frame(frame, R, f"L{k}")
                moved = point.locatenew(f"P{k}", qi * _frame_vector(frame, axis))
                moved.set_vel(frame, ui * _frame_vector(frame, axis))
                moved.v1pt_theory(point, N, frame)
                point = moved
        else:                                                # Rz(theta) Tz(d) Tx(a) Rx(alpha)
            d, theta, a, alpha = (_const(x) for x in link.dh)
            if link.joint == "revolute":
                theta = theta + qi
            else:
                d = d + qi
            ct, st, ca, sa = sp.cos(theta), sp.sin(theta), sp.cos(alpha), sp.sin(alpha)
            dcm = sp.Matrix([[ct, -st * ca, st * sa], [st, ct * ca, -ct * sa], [0, sa, ca]])
            joint = me.ReferenceFrame(f"L{k}")
            joint.orient_explicit(frame, dcm)
            z_parent = sa * joint.y + ca * joint.z              # the parent's z axis, in L axes
            joint.set_ang_vel(frame, (ui if link.joint == "revolute" else 0) * z_parent)
            moved = point.locatenew(f"P{k}", d * z_parent + a * joint.x)   # Rz(theta) keeps z; Rx keeps x
            if link.joint == "revolute":
                moved.v2pt_theory(point, N, joint)
            else:
                moved.set_vel(joint, ui * z_parent)
                moved.v1pt_theory(point, N, joint)
            frame, point = joint, moved
        # A tool frame (T, R_T) is folded into the body: COM t + R_T c and inertia
        # R_T I R_T^T, both in the joint frame's axes.
        com, inertia = np.array(link.com, float), np.array(link.inertia, float)
        if link.tool is not None:
            t_tool, r_tool = link.tool
            R_T = np.eye(3) if r_tool is None else r_tool.matrix()
            com = np.array(t_tool, float) + R_T @ com
            inertia = R_T @ inertia @ R_T.T
        C = point.locatenew(f"C{k}", _frame_vector(frame, com))
        C.v2pt_theory(point, N, frame)
        J = [[sp.Float(float(x)) for x in row] for row in inertia]
        # me.inertia takes the dyadic's matrix entries: I = [[xx, xy, zx], [xy, yy, yz], [zx, yz, zz]].
        I = me.inertia(frame, J[0][0], J[1][1], J[2][2], ixy=J[0][1], iyz=J[1][2], izx=J[0][2])
        bodies.append(me.RigidBody(f"B{k}", C, frame, mi, (I, C)))
        loads.append((C, mi * gravity))
    setup = time.perf_counter() - t0

    t0 = time.perf_counter()
    kane = me.KanesMethod(N, q_ind=q, u_ind=u, kd_eqs=[qi.diff(me.dynamicsymbols._t) - ui for qi, ui in zip(q, u)])
    kane.kanes_equations(bodies, loads)
    derive = time.perf_counter() - t0

    q_sym = tuple(sp.Symbol(f"q_{i + 1}", real=True) for i in range(n))
    v_sym = tuple(sp.Symbol(f"v_{i + 1}", real=True) for i in range(n))
    tt = me.dynamicsymbols._t
    plain = {**{qi.diff(tt): vi for qi, vi in zip(q, v_sym)}, **dict(zip(q, q_sym)), **dict(zip(u, v_sym))}
    M = kane.mass_matrix.xreplace(plain)
    F = kane.forcing.xreplace(plain)
    leftover = (M.free_symbols | F.free_symbols) - set(q_sym) - set(v_sym) - {g, *masses}
    if leftover:   # a dynamicsymbol or q' left behind would show up here as t
        raise RuntimeError(f"Kane equations still depend on {sorted(map(str, leftover))}")
    return KaneModel(chain=chain, kane=kane, q=q, u=u, q_sym=q_sym, v_sym=v_sym,
                     params=(g, *masses), param_values=np.array(list(chain.parameters.values()), dtype=float),
                     mass_matrix=M, forcing_vector=F, derive_seconds=derive, setup_seconds=setup)
