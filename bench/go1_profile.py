"""Where a Moreau-Jean step of Go1 standing goes (bench/go1.py --only profile): andyc/numerics/timestepping.py's step
copied here, cut after each stage, each cut timed in a compiled loop from the same state (the state, the modes
and the warm start put back before every step); a stage's cost is the difference between its cut and the one
before. The copy is checked first: run to its end, it must leave the state, the modes and the impulses exactly as
the build's own step does (else the profile says so and stops: the copy has fallen behind the step).

    python bench/go1.py --only profile
"""

from __future__ import annotations

import time

import numpy as np
from numba import njit

STAGES = ("copy the state back, mid point, signal rates", "inputs (the PD expressions)",
          "constraints_into at the mid point (28 contacts: 36 rows, A 36 x 18)", "dynamics leaf (M, G)",
          "factor M, v_free", "index set (28 contacts' predicted gaps)", "whiten the rows: C = A R^-1, w0",
          "W = C C^T", "contact solver (warm start, polish)", "v_{k+1}, the impulses' work",
          "positions, signals, quaternions, modes", "end of step: constraints_into, position corrections")


def make(model):
    """The staged step (cut(..., stop)) and its loop, compiled against the build's numerics."""
    N = model.numerics
    call = N.model.call
    T = N.timestepping
    _block, _modes, _corrections = T._block, T._modes, T._corrections
    _factor, _lower, _upper, _parts, _gram, _solve_parts = (T._factor, T._lower, T._upper, T._parts, T._gram,
                                                            T._solve_parts)
    solve = N.contact_solver.solve
    NORMAL, PLANAR, SPATIAL, BILATERAL = (N.contact_solver.NORMAL, N.contact_solver.PLANAR,
                                          N.contact_solver.SPATIAL, N.contact_solver.BILATERAL)
    KEEP, TOUCHING = T.KEEP, T.TOUCHING
    update_inputs, normalize = N.integrator.update_inputs, N.dynamics.normalize

    @njit
    def cut(model, w, s, theta, inputs, data, t, h, x, u, p, d, flow, stop):
        nq, nv, nx, nc = model.nq, model.nv, model.nx, model.contact_rows.shape[0]
        S, M, G = w.S, w.M, w.G
        v, a, xm, xdot = s.v, s.a, s.xm, s.xdot
        for j in range(nv):
            v[j] = x[nq + j]
        for j in range(x.shape[0]):
            xm[j] = x[j]
        for j in range(nq):
            xm[j] += theta * h * v[j]
        tm = t + theta * h
        if model.ns > 0:
            call(model.signal_rates, (t, x, u, p, d, xdot))
            for j in range(nq + nv, nx):
                xm[j] += theta * h * xdot[j]
        if stop == 0:
            return 0
        update_inputs(inputs, tm, xm, p, d, flow, u, data)
        if stop == 1:
            return 0
        call(model.constraints_into, (tm, xm, u, p, d, S))
        if stop == 2:
            return 0
        call(model.dynamics, (tm, xm, u, p, d, M, G))
        if stop == 3:
            return 0
        tree = s.tree[0] == 1
        _factor(model, M, tree)
        for j in range(nv):
            a[j] = G[j]
        _lower(model, M, a, tree)
        _upper(model, M, a, tree)
        for j in range(nv):
            a[j] = v[j] + h * a[j]
        for j in range(model.nw):
            x[nx + j] += h * G[nv + j]
        if stop == 4:
            return 0
        m, nb = 0, 0
        for r in range(model.flow_nrows[flow]):
            s.rows[m] = model.flow_rows[flow, r]
            m = _block(s, m, nb, BILATERAL, -1, 0.0, 1, 0.0, 0.0)
            nb += 1
        for i in range(nc):
            n = model.contact_rows[i]
            near = KEEP if d[model.contact_mode[i]] != 0.0 else TOUCHING
            u_free = S[model.s_cv, n]
            for j in range(nv):
                u_free += S[model.s_a + n, j] * (a[j] - v[j])
            if S[model.s_phi, n] + (1.0 - theta) * h * u_free > near:
                s.guess[i] = -1
                continue
            t1, kind = model.contact_stick[i], NORMAL
            if t1 >= 0:
                kind = SPATIAL if model.contact_tangents[i] == 2 else PLANAR
            s.rows[m] = n
            if t1 >= 0:
                s.rows[m + 1] = t1
                if kind == SPATIAL:
                    s.rows[m + 2] = t1 + 1
            guess = s.guess[i] if s.guess[i] >= 0 else 1
            if kind == SPATIAL and guess == 2 and s.guess_dir[i, 0] == 0.0 and s.guess_dir[i, 1] == 0.0:
                guess = 1
            m = _block(s, m, nb, kind, i, s.cmu[i], guess, s.guess_dir[i, 0], s.guess_dir[i, 1])
            nb += 1
        if stop == 5:
            return m
        vel = a                                           # _impulses, staged
        C = s.X[:m * nv].reshape((m, nv))
        w0, span = s.w0[:m], s.span
        for r in range(m):
            row = s.rows[r]
            Cr = C[r]
            av, af = 0.0, 0.0
            for j in range(nv):
                b = S[model.s_a + row, j]
                Cr[j] = b
                av += b * v[j]
                af += b * vel[j]
            w0[r] = af + S[model.s_cv, row] - av
            s.av[r] = av
            span[r, 0], span[r, 1] = _lower(model, M, Cr, tree)
        for k in range(nb):
            if s.owner[k] >= 0:
                w0[s.first[k]] += s.e[s.owner[k]] * min(S[model.s_cv, s.rows[s.first[k]]], 0.0)
        if stop == 6:
            return m
        parts = _parts(s, nb, nv)
        W = s.W[:m * m].reshape((m, m))
        if parts == 1:
            _gram(C, span, W, 0, m)
        if stop == 7:
            return m
        if parts == 1:
            sweeps, verified = solve(W, w0, s.kind[:nb], s.first[:nb], s.mu[:nb], s.state[:nb],
                                     s.direction[:2 * nb].reshape((nb, 2)), s.P[:m], s.work)
        else:
            sweeps, verified = _solve_parts(s, C, span, w0, parts)
        s.stats[1] += sweeps
        if not verified:
            s.stats[2] += 1
        if stop == 8:
            return m
        col = s.col
        for j in range(nv):
            col[j] = 0.0
        for r in range(m):
            P = s.P[r]
            if P != 0.0:
                Cr = C[r]
                for j in range(span[r, 0], span[r, 1]):
                    col[j] += Cr[j] * P
        _upper(model, M, col, tree)
        for j in range(nv):
            vel[j] += col[j]
        work = 0.0
        for r in range(m):
            row = s.rows[r]
            after = 0.0
            for j in range(nv):
                after += S[model.s_a + row, j] * vel[j]
            b = S[model.s_cv, row] - s.av[r]
            w0[r] = after + b
            work += s.P[r] * (0.5 * (s.av[r] + after) + b)
            s.total[row] += s.P[r]
            s.seen[row] = 1.0
        if model.nj > 0:
            x[nx + model.nw - 1] += work
        if stop == 9:
            return m
        for j in range(nq):
            x[j] += h * ((1.0 - theta) * v[j] + theta * a[j])
        if model.ns > 0:
            for j in range(nv):
                xm[nq + j] = (1.0 - theta) * v[j] + theta * a[j]
            call(model.signal_rates, (tm, xm, u, p, d, xdot))
            for j in range(nq + nv, nx):
                x[j] += h * xdot[j]
            normalize(model, x)
        for j in range(nv):
            x[nq + j] = a[j]
        _modes(model, s, nb, d)
        if stop == 10:
            return m
        _corrections(model, w, s, t + h, h, x, u, p, d, flow, tree)
        return m

    @njit
    def loop(n, model, w, s, theta, inputs, data, t, h, x, u, p, d, flow, stop, x0, d0, g0, gd0, own):
        m = 0
        for _ in range(n):
            for j in range(x.shape[0]):
                x[j] = x0[j]
            for j in range(d.shape[0]):
                d[j] = d0[j]
            for j in range(g0.shape[0]):
                s.guess[j] = g0[j]
                s.guess_dir[j, 0] = gd0[j, 0]
                s.guess_dir[j, 1] = gd0[j, 1]
            if own:
                T.step(model, w, s, theta, inputs, data, t, h, x, u, p, d, flow)
            else:
                m = cut(model, w, s, theta, inputs, data, t, h, x, u, p, d, flow, stop)
        return m
    return loop


def profile(model, dt: float = 1e-3, parameters=None, at=(1.0, 1.5, 2.0), n: int = 3000, rounds: int = 7):
    """[(t, rows of the step's problem, sweeps, corrections, times (rounds, stages + 1) us)] at each state of a
    standing run (the last column: the build's own step)."""
    from go1 import Moreau
    h = Moreau(model, dt, parameters)
    loop = make(model)
    out = []
    last = len(STAGES) - 1
    for t_at in at:
        h.steps(int(round(t_at / dt)) - h.i)
        snap = h.snapshot()
        x0, d0, g0, gd0, i = snap
        fn, data = h.source.function_data
        t = i * dt

        def args(stop, own=False):
            return (model.ref, h.w.ref, h.s, 0.5, fn, data, t, dt, h.x, h.w.u, h.p, h.d, h.flow, stop, x0, d0, g0,
                    gd0, own)
        loop(1, *args(last, True))
        own = (h.x.copy(), h.d.copy(), h.s.P.copy())
        before = h.s.stats.copy()
        m = loop(1, *args(last))
        sweeps, corrections = int(h.s.stats[1] - before[1]), int(h.s.stats[3] - before[3])
        if not (np.array_equal(own[0], h.x) and np.array_equal(own[1], h.d) and np.array_equal(own[2], h.s.P)):
            raise SystemExit("bench/go1_profile.py: the staged copy no longer does what timestepping.step does; "
                             "bring it up to date")
        loop(5, *args(0))
        times = np.zeros((rounds, len(STAGES) + 1))
        for r in range(rounds):
            for stop in range(len(STAGES) + 1):
                tic = time.perf_counter()
                loop(n, *args(min(stop, last), stop == len(STAGES)))
                times[r, stop] = (time.perf_counter() - tic) / n * 1e6
        h.restore(snap)
        out.append((t_at, m, sweeps, corrections, times))
    return out


def report(model, dt: float = 1e-3) -> None:
    print(f"\nprofile: one Moreau-Jean step of Go1 standing (dt {dt:g}), each stage's cut timed from the same state "
          "(best of 7 rounds of 3000 steps; a stage = its cut less the one before; noisy machines make small "
          "stages negative)")
    for t_at, m, sweeps, corrections, times in profile(model, dt):
        best = times.min(axis=0)
        print(f"  state at t = {t_at:g} s: {m} rows in the step's problem, {sweeps} Gauss-Seidel sweeps, "
              f"{corrections} position corrections; the copy's whole step {best[-2]:.2f} us, the build's own step "
              f"{best[-1]:.2f} us")
        prev = 0.0
        for k, name in enumerate(STAGES):
            print(f"    {name:72s} {best[k] - prev:6.2f} us")
            prev = best[k]
