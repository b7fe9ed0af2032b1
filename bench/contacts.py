"""The contacts section of bench/run.py (issue 21): steps per second of runs whose contacts open and close,
the cost of a contact's impact against a hand-written jump of the same motion, and one impact's solve alone."""

from __future__ import annotations

import time
from pathlib import Path

import andyc

ROOT = Path(__file__).resolve().parents[1]


def _best_run(model, t_end, dt, repeats=5, **options):
    """The fastest of `repeats` runs (wall time), after one that compiles."""
    andyc.simulate(model, 10 * dt, dt=dt, progress=False, **options)
    return min((andyc.simulate(model, t_end, dt=dt, every=1000, progress=False, **options) for _ in range(repeats)),
               key=lambda r: r.stats["wall_seconds"])


def _steps_per_second(run) -> float:
    s = run.stats
    return (s["steps"] + s["event_trial_steps"]) / s["wall_seconds"]


def contacts_benchmark(tmp: Path) -> None:
    """Issue 21: runs with contacts, and what contact handling costs against the same motion without it."""
    build = tmp / "contacts_build"
    ball = andyc.compile_model(ROOT / "models" / "bouncing_ball_contact.yaml", build)[0]
    plain = andyc.compile_model(ROOT / "models" / "bouncing_ball.yaml", build)[0]
    rod = andyc.compile_model(ROOT / "models" / "rod_drop.yaml", build)[0]
    hopper = andyc.compile_model(ROOT / "models" / "hopper_contact.yaml", build)[0]
    for label, model, t_end, dt, options in (
            ("ball, bouncing then resting, 10 s", ball, 10.0, 1e-3, {}),
            ("rod, e = 0.5, onto two supports, 3 s", rod, 3.0, 1e-3, {"parameters": {"e": 0.5}}),
            ("hopper, 2 s", hopper, 2.0, 1e-4, {})):
        run = _best_run(model, t_end, dt, **options)
        print(f"  {label}: {run.stats['jumps']} jumps, {_steps_per_second(run):.3g} steps/s "
              f"({run.stats['wall_seconds'] * 1e3:.1f} ms)")
    # Friction (planar Coulomb): a slipping contact's force is solved non-symmetrically (numerics.dynamics.slip_rows),
    # a sticking one by the symmetric solve of one more row; the same block slipping and sticking.
    rolling = andyc.compile_model(ROOT / "models" / "ball_rolling.yaml", build)[0]
    block = andyc.compile_model(ROOT / "models" / "block_incline.yaml", build)[0]
    run = _best_run(rolling, 1.0, 1e-3)
    print(f"  ball with friction, sliding then rolling, 1 s: {run.stats['jumps']} jumps, "
          f"{_steps_per_second(run):.3g} steps/s")
    slipping = _best_run(block, 5.0, 1e-3, parameters={"mu": 0.3})
    sticking = _best_run(block, 5.0, 1e-3, parameters={"mu": 0.7})
    print(f"  block on the incline, 5 s: slipping {_steps_per_second(slipping):.3g} steps/s, sticking "
          f"{_steps_per_second(sticking):.3g} steps/s")
    # The same 4 s of bouncing (the same impacts, before the accumulation point): the hand-written jump's
    # compiled impact against the contact's impact solved from Python (andyc.runtime.contacts); and that solve
    # alone, timed on the first impact's state.
    with_contact, without = _best_run(ball, 4.0, 1e-3), _best_run(plain, 4.0, 1e-3)
    print(f"  the first 4 s of the ball ({with_contact.stats['jumps']} impacts): contact "
          f"{with_contact.stats['wall_seconds'] * 1e3:.1f} ms, hand-written jump {without.stats['wall_seconds'] * 1e3:.1f} "
          "ms (the steps between impacts run the same compiled code)")
    from andyc.runtime.contacts import resolve_impact

    for label, model, options in (("ball", ball, {}), ("rod (two contacts)", rod, {"parameters": {"e": 0.5}})):
        run = _best_run(model, 1.0, 1e-3, repeats=1, **options)
        t, x, p = run.events["time"][0], run.events["state_before"][0], model.parameters(options.get("parameters"))
        u, d = model.input_defaults, model.initial_discrete(p)
        best = float("inf")
        for _ in range(5):
            tic = time.perf_counter()
            for _ in range(200):
                resolve_impact(model, t, x.copy(), u, p, d, 0, False)
            best = min(best, (time.perf_counter() - tic) / 200)
        print(f"  one contact impact solved (Python, {label}): {best * 1e6:.0f} us")
