"""The compiled model and the arrays its algorithms work in, as MuJoCo's mjModel and mjData.

Model holds a model's sizes, its index tables and its own functions (the leaves), which
<name>_equations.py compiles as Numba C callbacks with the signatures of LEAVES. Every algorithm
of this package takes a Model and a Work; their types are the same for every model, so each
algorithm compiles once. Both are Numba structrefs: passed by reference, and typed from Python in
about a microsecond (a tuple of function pointers takes tens).

Work holds the scratch arrays; Python keeps its own references to them (Work.arrays), so reading
them needs no compiled accessor.

Every algorithm calls a leaf through `call(leaf, args)` (below), a plain indirect call. (Numba's
own call of a first-class function carries a fallback that re-enters Python; its presence alone
makes Numba count references to every array the calling function takes, which costs the
walker's step a fifth of its time.)

The leaves, each with t, x (state), u (inputs), p (parameters), d (discrete states) first where
marked STATE; k is a jump's index; S is the scratch of layout.py:

    dynamics(STATE, M, G)                     M (NV, NV) and G (NV,): M dv/dt = G (ANDY eq. 8); then into
                                              G[NV:] the power of each element that does work (andyc/symbolic/
                                              work.py; G has NV + NW entries)
    dynamics_constraints(STATE, M, G, S)      both this and constraints_into, sharing subexpressions
    constraints_into(STATE, S)                phi (NH,), c = A v + b (NC,), A (NC, NV) and kappa (NC,)
                                              with dc/dt = A dv/dt + kappa (ANDY eq. 11), into S
    signal_rates(STATE, xdot)                 d sigma/dt into xdot[NQ + NV:] (ANDY eq. 4)
    energy(STATE) -> E, power(STATE) -> P     total energy; power of the non-conservative elements
    frame_poses(STATE, out)                   each frame's pose in world, out (frames, 12): its origin, then
                                              its rotation (own axes -> world) row by row
    constraint_gains(p, S)                    Baumgarte gains K_s, K_d of each row (ANDY eq. 13-15), into S
    restitution(p, S)                         restitution of each jump's impact, into S
    guard(k, STATE, lam) -> g, enabled(k, STATE, lam) -> e   jump k happens where g crosses zero while e >= 0;
                                              lam (NC,): the multipliers of its source flow, which the
                                              caller computes first when JUMP_MULTIPLIERS[k] (see
                                              dynamics.guard_value)
    guard_rate(k, STATE, xdot) -> dg/dt
    reset(k, STATE)                           jump k's resets, into x and d
    flow_inputs(p, U)                         input values each flow sets, into U (NF, NU)
    closed_form(t, u, p, x)                   the exact solution the model declares, into x
    energy_law(k, STATE, grad) -> Phi_e       flow k's declared energy law and dPhi_e/dv into grad (NV); NaN
                                              where the flow keeps the built-in law (dynamics.project)
    forward_dynamics(STATE, M, G)             dv/dt into G[:NV] by the articulated-body algorithm, where the
                                              model has it (NB = NV), then the powers into G[NV:] as dynamics
    drive_power(STATE, xdot)                  the power driving the links that depend on t, from dv/dt in xdot,
                                              into xdot[NX + its work slot] (integrator.stage_powers)

and the input callbacks every integrator takes (inputs.py: the model's own expressions, model_inputs,
and what a run drives beyond them):

    status = inputs(t, x, d, p, flow, u, data)    INPUTS_SIGNATURE
"""

import ctypes

import numpy as np

from .compiler import NUMBA, cfunc, jit
from .layout import RETURNS, VECTORS, scratch_layout

SIZES = ("nq", "nv", "ns", "nx", "nu", "nh", "nc", "nd", "nf", "nj", "nw", "nt", "nb")   # nt: speeds under LTDL
                                                                                       # (or 0), nb: under ABA
ROWS = ("s_a", "s_c", "s_w") + tuple(f"s_{name}" for name in VECTORS)  # the first row of each part of S
TABLES = ("quaternions",                            # index in x of each quaternion signal's w
          "flow_rows", "flow_nrows", "flow_nhrows",  # each flow's own rows (holonomic first), then -1
          "contact_rows", "contact_stick", "contact_tangents",   # per contact: its rows (active.select_rows adds
          "contact_mode", "contact_mu", "contact_dir",           # them while d[contact_mode] says it is closed)
          "impact_rows", "impact_nrows",             # rows taking each jump's impact
          "jump_source", "jump_target", "jump_direction", "jump_priority", "jump_order", "jump_multipliers",
          "jump_contact",                            # the contact whose impact jump k is, or -1
          "jump_mode_state", "jump_mode_mask",       # a contact's jump: its mode in d, the modes it leaves
          "row_work",                                # the work slot of each row's constraint power, or -1
          "row_friction",                            # ... of a gap row's sliding friction (its contact's), or -1
          "mass_parent", "mass_order",               # the tree of M: parent of each speed; children first
          "row_ptr", "row_cols", "flow_envelope")    # the rows' sparsity (sparse_rows.py; row_ptr empty: dense)
LEAF_NAMES = ("dynamics", "dynamics_constraints", "constraints_into", "signal_rates", "energy", "power",
              "frame_poses", "constraint_gains", "restitution", "guard", "guard_rate", "enabled", "reset",
              "flow_inputs", "closed_form", "energy_law", "drive_power", "forward_dynamics")
WORK = {    # the arrays of Work: name -> shape, from the sizes and the scratch layout
    "M": ("nv", "nv"), "G": ("ng",), "S": ("rows", "width"),
    "k": (4, "na"), "xt": ("na",), "x1": ("na",), "xb": ("na",), "xc": ("na",), "x_event": ("na",),
    "xdot": ("nx",), "g0": ("nj",), "u": ("nu",), "lam": ("nc",),
}
INDICES = {  # the integer arrays of Work: counts (steps, event trial steps, rows logged: integrator.advance), and the
    "counts": (3,), "active": (4, "nc"), "nactive": (3,), "envelope": (2, "nc"),   # active rows (active.py)
}

if NUMBA:
    from numba import types
    from numba.core import cgutils
    from numba.core.extending import intrinsic
    from numba.experimental import structref

    # A leaf takes its arrays as plain C pointers (row-major, of the sizes in the module's constants): so its
    # signature is C's, and a leaf compiled by a C compiler (andyc.codegen.c_leaves) is one too.
    _f8, _i8, _P = types.float64, types.int64, types.CPointer(types.float64)
    _STATE = (_f8, _P, _P, _P, _P)
    _ARRAYS = types.float64[::1]
    LEAVES = {
        "dynamics": types.void(*_STATE, _P, _P),
        "dynamics_constraints": types.void(*_STATE, _P, _P, _P),
        "constraints_into": types.void(*_STATE, _P),
        "signal_rates": types.void(*_STATE, _P),
        "energy": _f8(*_STATE),
        "power": _f8(*_STATE),
        "frame_poses": types.void(*_STATE, _P),
        "constraint_gains": types.void(_P, _P),
        "restitution": types.void(_P, _P),
        "guard": _f8(_i8, *_STATE, _P),
        "guard_rate": _f8(_i8, *_STATE, _P),
        "enabled": _f8(_i8, *_STATE, _P),
        "reset": types.void(_i8, *_STATE),
        "flow_inputs": types.void(_P, _P),
        "closed_form": types.void(_f8, _P, _P, _P),
        "energy_law": _f8(_i8, *_STATE, _P),
        "drive_power": types.void(*_STATE, _P),
        "forward_dynamics": types.void(*_STATE, _P, _P),
    }
    INPUTS_SIGNATURE = _i8(_f8, _ARRAYS, _ARRAYS, _ARRAYS, _i8, _ARRAYS, _ARRAYS)

    def leaf(name):
        """Compile a model function as the leaf `name` (a C callback of its signature in LEAVES, cached
        beside it): its type is its signature, so the algorithms compile once for every model."""
        return cfunc(LEAVES[name])

    def input_callback(function):
        """Compile an input function `status = inputs(t, x, d, p, flow, u, data)` (INPUTS_SIGNATURE)."""
        return cfunc(INPUTS_SIGNATURE)(function)

    class CLeaf(types.WrapperAddressProtocol):
        """A leaf a C compiler made (the build's <name>_leaves_<key>_<cpu>.so): Numba types it by its signature in
        LEAVES, as a Numba leaf of that name, so the algorithms take either."""

        def __init__(self, library, name):
            self.library, self.name = library, name       # the library stays loaded while a leaf of it lives
            self.address = ctypes.cast(getattr(library, name), ctypes.c_void_p).value

        def __wrapper_address__(self):
            return self.address

        def signature(self):
            return LEAVES[self.name]

    @structref.register
    class ModelType(types.StructRef):
        def preprocess_fields(self, fields):
            return tuple((name, types.unliteral(t)) for name, t in fields)

    class Model(structref.StructRefProxy):
        """A compiled model, for the algorithms (see the module docstring). Build it with new_model."""

    @structref.register
    class WorkType(types.StructRef):
        def preprocess_fields(self, fields):
            return tuple((name, types.unliteral(t)) for name, t in fields)

    class WorkRef(structref.StructRefProxy):
        """The scratch of one model, for the algorithms. Build it with Work."""

    def _passes_as(given, wanted) -> bool:
        """Whether a value of type `given` can be passed where the leaf takes `wanted`: a C-contiguous array of its
        dtype where it takes a pointer (the leaf indexes it row-major), an array of the very type where it takes
        an array, or a number (cast)."""
        if isinstance(wanted, types.CPointer):
            return isinstance(given, types.Array) and given.dtype == wanted.dtype and given.layout == "C"
        if isinstance(wanted, types.Array):
            return (isinstance(given, types.Array) and given.dtype == wanted.dtype and given.ndim == wanted.ndim
                    and given.layout == "C")
        return isinstance(given, (types.Number, types.Boolean))

    def _argument(context, builder, value, given, wanted):
        if isinstance(wanted, types.CPointer):
            return context.make_array(given)(context, builder, value=value).data
        if isinstance(wanted, types.Array):
            return value
        return context.cast(builder, value, given, wanted)

    @intrinsic
    def call(typingctx, leaf, args):
        """leaf(*args), a leaf called through its C address (see the module docstring). Arrays must be
        C-contiguous of the leaf's dtype (else a typing error); numbers are cast to its argument types."""
        if not isinstance(leaf, types.FunctionType) or not isinstance(args, types.BaseTuple):
            return None
        prototype = leaf.ftype
        if len(args) != len(prototype.atypes) or not all(map(_passes_as, args.types, prototype.atypes)):
            return None

        def codegen(context, builder, signature, values):
            function, arguments = values
            address = cgutils.create_struct_proxy(leaf)(context, builder, value=function).c_addr
            pointer = builder.bitcast(address, context.get_value_type(prototype))
            passed = [builder.extract_value(arguments, i) for i in range(len(args))]
            passed = [_argument(context, builder, value, given, wanted)
                      for value, given, wanted in zip(passed, args.types, prototype.atypes)]
            return builder.call(pointer, passed)

        return prototype.rtype(leaf, args), codegen

    @intrinsic
    def borrowed(typingctx, array):
        """The same array without its reference count (a null meminfo), for an array that outlives every call
        it is passed to: Model's tables and Work's arrays (their `owner` keeps them) and the state of a run
        (its caller keeps it). Numba then skips the atomic increments and decrements on every call that
        takes it, which in a constrained step cost about a quarter of its time."""
        if not isinstance(array, types.Array):
            return None

        def codegen(context, builder, signature, values):
            view = context.make_array(array)(context, builder, value=values[0])
            view.meminfo = cgutils.get_null_value(view.meminfo.type)
            return view._getvalue()

        return array(array), codegen

    # Each holds its arrays borrowed (see borrowed) and, in `owner`, a tuple of the same arrays with their
    # counts, which keeps them alive as long as it lives.
    structref.define_proxy(Model, ModelType, SIZES + ROWS + TABLES + LEAF_NAMES + ("owner",))
    structref.define_proxy(WorkRef, WorkType, tuple(WORK) + tuple(INDICES) + ("owner",))
else:
    LEAVES, INPUTS_SIGNATURE = {name: None for name in LEAF_NAMES}, None

    def leaf(name):
        return lambda function: function

    def input_callback(function):
        return function

    class CLeaf:
        """A leaf a C compiler made, called through ctypes (numbers as C's, arrays as row-major pointers)."""

        def __init__(self, library, name):
            self.function = getattr(library, name)
            self.function.restype = ctypes.c_double if name in RETURNS else None

        def __call__(self, *args):
            return self.function(*(a.ctypes.data_as(ctypes.POINTER(ctypes.c_double)) if isinstance(a, np.ndarray)
                                   else ctypes.c_int64(a) if isinstance(a, (int, np.integer)) else ctypes.c_double(a)
                                   for a in args))

    def call(leaf, args):
        """As compiled: a leaf indexes its arrays flat (row-major), as through C pointers."""
        return leaf(*(a.reshape(-1) if isinstance(a, np.ndarray) else a for a in args))

    def borrowed(array):
        return array

    class Model:
        def __init__(self, *values):
            for name, value in zip(SIZES + ROWS + TABLES + LEAF_NAMES + ("owner",), values):
                setattr(self, name, value)

    class WorkRef:
        def __init__(self, *values):
            for name, value in zip(tuple(WORK) + tuple(INDICES) + ("owner",), values):
                setattr(self, name, value)


@jit
def _model(sizes, rows, quaternions, flow_rows, flow_nrows, flow_nhrows, contact_rows, contact_stick,
           contact_tangents, contact_mode, contact_mu, contact_dir, impact_rows,
           impact_nrows, jump_source, jump_target, jump_direction, jump_priority, jump_order, jump_multipliers,
           jump_contact, jump_mode_state, jump_mode_mask, row_work, row_friction, mass_parent, mass_order, row_ptr,
           row_cols, flow_envelope, leaves):
    (dynamics, dynamics_constraints, constraints_into, signal_rates, energy, power, frame_poses,
     constraint_gains, restitution, guard, guard_rate, enabled, reset, flow_inputs, closed_form, energy_law,
     drive_power, forward_dynamics) = leaves
    return Model(sizes[0], sizes[1], sizes[2], sizes[3], sizes[4], sizes[5], sizes[6], sizes[7], sizes[8], sizes[9],
                 sizes[10], sizes[11], sizes[12],
                 rows[0], rows[1], rows[2], rows[3], rows[4], rows[5], rows[6], rows[7], rows[8], rows[9], rows[10],
                 rows[11], rows[12],
                 borrowed(quaternions), borrowed(flow_rows), borrowed(flow_nrows), borrowed(flow_nhrows),
                 borrowed(contact_rows), borrowed(contact_stick), borrowed(contact_tangents), borrowed(contact_mode),
                 borrowed(contact_mu), borrowed(contact_dir),
                 borrowed(impact_rows), borrowed(impact_nrows), borrowed(jump_source), borrowed(jump_target),
                 borrowed(jump_direction), borrowed(jump_priority), borrowed(jump_order), borrowed(jump_multipliers),
                 borrowed(jump_contact), borrowed(jump_mode_state), borrowed(jump_mode_mask),
                 borrowed(row_work), borrowed(row_friction), borrowed(mass_parent), borrowed(mass_order),
                 borrowed(row_ptr), borrowed(row_cols), borrowed(flow_envelope),
                 dynamics, dynamics_constraints, constraints_into, signal_rates, energy, power, frame_poses,
                 constraint_gains, restitution, guard, guard_rate, enabled, reset, flow_inputs, closed_form,
                 energy_law, drive_power, forward_dynamics,
                 (quaternions, flow_rows, flow_nrows, flow_nhrows, contact_rows, contact_stick, contact_tangents,
                  contact_mode, contact_mu, contact_dir, impact_rows, impact_nrows,
                  jump_source, jump_target, jump_direction, jump_priority, jump_order, jump_multipliers, jump_contact,
                  jump_mode_state, jump_mode_mask, row_work, row_friction, mass_parent, mass_order, row_ptr, row_cols,
                  flow_envelope))


def c_leaves(path: str, names) -> dict:
    """The leaves `names` of the shared library at path (a build's <name>_leaves_<key>_<cpu>.so, which
    andyc/codegen/c_leaves.py writes), by name, as the algorithms take them."""
    library = ctypes.CDLL(path)
    return {name: CLeaf(library, name) for name in names}


def sizes_of(equations) -> dict:
    """The sizes of a generated <name>_equations.py module (NQ, NV, ...), with the scratch layout's "rows" and
    "width", by lower-case name."""
    sizes = {name: int(getattr(equations, name.upper(), 0)) for name in SIZES}
    ne = sizes["nj"] + len(getattr(equations, "FRICTIONS", ()))         # the coefficients the restitution leaf gives
    layout = scratch_layout(sizes["nv"], sizes["nc"], ne)
    return {**sizes, "na": sizes["nx"] + sizes["nw"], "ng": sizes["nv"] + sizes["nw"], "rows": layout["rows"],
            "width": layout["width"], "ne": ne}


def new_model(equations, stubs, constrained=None) -> Model:
    """The Model of a generated <name>_equations.py module: its sizes (NQ, NV, ...), tables (FLOW_ROWS, ...)
    and leaves; `stubs` (a module of leaves that do nothing) stands in for the leaves a model has none of
    (no constraints, no jumps, ...). `constrained`: "dense" or "sparse" overrides the module's CONSTRAINED_SOLVE
    (sparse_rows.py; "sparse" needs its tables: ValueError without)."""
    sizes = sizes_of(equations)
    layout = scratch_layout(sizes["nv"], sizes["nc"], sizes["ne"])
    rows = np.array([layout[name] for name in ("A", "C", "W") + VECTORS], dtype=np.int64)
    tables = [np.ascontiguousarray(getattr(equations, name.upper()), dtype=np.int64) for name in TABLES]
    chosen = constrained or getattr(equations, "CONSTRAINED_SOLVE", "dense")
    if chosen == "sparse" and not len(tables[TABLES.index("row_ptr")]):
        raise ValueError("the sparse constrained solve does not apply to this model (no ROW_PTR)")
    if chosen != "sparse":
        tables[TABLES.index("row_ptr")] = tables[TABLES.index("row_ptr")][:0]
    leaves = tuple(getattr(equations, name, None) or getattr(stubs, name) for name in LEAF_NAMES)
    return _model(np.array([sizes[name] for name in SIZES], dtype=np.int64), rows, *tables, leaves)


@jit
def _work(M, G, S, k, xt, x1, xb, xc, x_event, xdot, g0, u, lam, counts, active, nactive, envelope):
    return WorkRef(borrowed(M), borrowed(G), borrowed(S), borrowed(k), borrowed(xt), borrowed(x1), borrowed(xb),
                   borrowed(xc), borrowed(x_event), borrowed(xdot), borrowed(g0), borrowed(u), borrowed(lam),
                   borrowed(counts), borrowed(active), borrowed(nactive), borrowed(envelope),
                   (M, G, S, k, xt, x1, xb, xc, x_event, xdot, g0, u, lam, counts, active, nactive, envelope))


class Work:
    """The scratch arrays of one model (WORK, then the integer INDICES), zeroed, and `ref`, the same arrays as
    the algorithms take them."""

    def __init__(self, sizes: dict):
        for table, dtype in ((WORK, np.float64), (INDICES, np.int64)):
            for name, shape in table.items():
                setattr(self, name, np.zeros(tuple(sizes[s] if isinstance(s, str) else s for s in shape), dtype))
        self.ref = _work(*(getattr(self, name) for name in (*WORK, *INDICES)))
