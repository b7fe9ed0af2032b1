"""The constraint rows active at an instant: the flow's own, and those of the contacts closed in d.

A flow lists its own rows (FLOW_ROWS: the model's bilateral constraints active in it). A contact adds its rows
while it is closed, its mode being the discrete state d[CONTACT_MODE[i]] (andyc.spec.contacts: 0 open,
1 closed or sticking, 2 slipping forwards, or slipping with spatial friction, 3 slipping backwards), so that
the rows a run solves are chosen at run time, not enumerated as flows. select_rows(model, w, flow, d) writes
them into the Work, where every constrained solve reads them:

    w.active[0, r]   the r-th active row (an index into the NC rows), holonomic ones first
    w.active[1, r]   on a slipping contact's normal row, how its force carries the friction (slipping.slip_rows):
                     -sigma (t + 1) for planar friction (t its stick row, sigma = +1 slipping forwards),
                     t + 1 for spatial friction (t the first of its two stick rows); 0 on every other row
    w.active[2, r]   there: the jump whose coefficient is the contact's mu (its `stop`)
    w.active[3, r]   there, spatial friction: 1 + the index in d of its slip's direction; else 0
    w.nactive        [rows, holonomic rows, 1 when a contact slips]
    w.envelope       (2, NC) the flow's Gram envelope, for the sparse solve (sparse_rows.py), which applies only
                     to models without contacts (andyc.codegen.generate)

Every algorithm that takes a flow and d calls select_rows first; those it calls read the Work.
"""

from .compiler import jit

STICK, SLIP_POS, SLIP_NEG = 1, 2, 3     # a contact's modes beside open (0), as andyc.spec.contacts


@jit(inline="always")
def _put(a, m, row, code, mu, direction):
    a[0, m] = row
    a[1, m] = code
    a[2, m] = mu
    a[3, m] = direction


@jit
def select_rows(model, w, flow, d):
    """The rows active in `flow` with the contacts' modes in d, into w (module docstring); returns their number."""
    a, n = w.active, w.nactive
    own, own_h = model.flow_nrows[flow], model.flow_nhrows[flow]
    m = 0
    for r in range(own_h):
        _put(a, m, model.flow_rows[flow, r], 0, 0, 0)
        m += 1
    slips = 0
    for i in range(model.contact_rows.shape[0]):       # the closed contacts' gaps (holonomic)
        mode = int(d[model.contact_mode[i]])
        if mode == 0:
            continue
        t = model.contact_stick[i]
        if mode == STICK or t < 0:
            _put(a, m, model.contact_rows[i], 0, 0, 0)
        elif model.contact_tangents[i] == 2:
            _put(a, m, model.contact_rows[i], t + 1, model.contact_mu[i], model.contact_dir[i] + 1)
            slips = 1
        else:
            _put(a, m, model.contact_rows[i], -(t + 1) if mode == SLIP_POS else t + 1, model.contact_mu[i], 0)
            slips = 1
        m += 1
    n[1] = m
    for r in range(own_h, own):
        _put(a, m, model.flow_rows[flow, r], 0, 0, 0)
        m += 1
    for i in range(model.contact_rows.shape[0]):       # the sticking contacts' stick rows
        t = model.contact_stick[i]
        if t < 0 or int(d[model.contact_mode[i]]) != STICK:
            continue
        _put(a, m, t, 0, 0, 0)
        m += 1
        if model.contact_tangents[i] == 2:
            _put(a, m, t + 1, 0, 0, 0)
            m += 1
    n[0] = m
    n[2] = slips
    if model.row_ptr.shape[0] > 0:                      # (the sparse solve: a model without contacts)
        for r in range(model.nc):
            w.envelope[0, r] = model.flow_envelope[flow, 0, r]
            w.envelope[1, r] = model.flow_envelope[flow, 1, r]
    return m
