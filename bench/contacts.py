"""The contacts section of bench/run.py (issue 21): steps per second of runs whose contacts open and close,
the cost of contact handling per step against the same model without its contacts (item 8: the resting ball,
the rocking block; the knee walker with contacts against the hand-guarded one; alternated rounds in one run, min
and max), the cost of a contact's impact against a hand-written jump of the same motion, and one impact's solve
alone."""

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


def _without_contacts(path: Path, tmp: Path) -> Path:
    """The model file at `path` with its `contacts:` section (and what follows: expectations) left out, as
    <name>_free.yaml in tmp: the same bodies and frames, moving freely."""
    text = path.read_text().split("\ncontacts:\n")[0] + "\n"
    name = path.stem + "_free"
    out = tmp / f"{name}.yaml"
    out.write_text(text.replace(f"name: {path.stem}\n", f"name: {name}\n"))
    return out


def _us_per_step(model, t_end, dt, options) -> tuple:
    """(microseconds per RK4 step, trial steps of event location included; the run) of one run."""
    run = andyc.simulate(model, t_end, dt=dt, every=1000, progress=False, **options)
    s = run.stats
    return s["wall_seconds"] / (s["steps"] + s["event_trial_steps"]) * 1e6, run


CONTACT_COST = (
    # label, model, its options; the same model without contacts runs the same t_end and dt with no options
    ("resting ball (on the ground from the start, contact closed: one row, its liftoff guard on the normal "
     "force)", "bouncing_ball_contact", 10.0, 1e-3, {"parameters": {"h0": 0.0}}),
    ("rocking block (two corners with friction: 16 modes; rocks, then rests on both)", "rocking_block", 5.0,
     1e-3, {"method": "projection"}),
)


def contact_cost(tmp: Path, build: Path, rounds: int = 7) -> None:
    """Item 8 of issue 21: steps per second with contacts, and the cost of contact handling per step: the same
    model with its contacts section left out (its bodies moving freely, same steps), timed alternately in each
    round (with, without), min and max over the rounds."""
    print(f"  cost of contact handling per step (RK4 steps incl. event-location trials; {rounds} rounds, "
          "alternated with the same model without its contacts; min .. max):")
    for label, name, t_end, dt, options in CONTACT_COST:
        path = ROOT / "models" / f"{name}.yaml"
        model = andyc.compile_model(path, build)[0]
        free = andyc.compile_model(_without_contacts(path, tmp), build)[0]
        free_options = {k: v for k, v in options.items() if k != "parameters"}
        _us_per_step(model, 10 * dt, dt, options), _us_per_step(free, 10 * dt, dt, free_options)     # compile
        with_us, without_us, extra = [], [], []
        for _ in range(rounds):
            a, run = _us_per_step(model, t_end, dt, options)
            b, _ = _us_per_step(free, t_end, dt, free_options)
            with_us.append(a)
            without_us.append(b)
            extra.append(a - b)
        print(f"    {label}, {t_end:g} s at dt = {dt:g} ({options.get('method', 'rk4')}): "
              f"{run.stats['jumps']} jumps; with contacts {1e6 / max(with_us):.3g} .. {1e6 / min(with_us):.3g} "
              f"steps/s ({min(with_us):.2f} .. {max(with_us):.2f} us/step), without {min(without_us):.2f} .. "
              f"{max(without_us):.2f} us/step; contact handling {min(extra):.2f} .. {max(extra):.2f} us/step "
              f"(x{min(a / b for a, b in zip(with_us, without_us)):.2f} .. "
              f"x{max(a / b for a, b in zip(with_us, without_us)):.2f})")
    walker_cost(build, rounds)


def walker_cost(build: Path, rounds: int) -> None:
    """The knee walker with its feet and knee stops as contacts (64 modes, no hand-written jump) against the
    hand-guarded walker (six flows, six jumps), alternated rounds: the same bodies and the same 3 s at dt = 1e-3
    (projection), but not the same motion (the contact walker's gait, other masses on a 0.0504 rad slope, about 5
    steps, against 5 steps of the reference's gait), so the difference per step is contact handling together with
    what the gaits' events cost."""
    contact = andyc.compile_model(ROOT / "models" / "passive_walker_contact.yaml", build)[0]
    hand = andyc.compile_model(ROOT / "models" / "passive_walker.yaml", build)[0]
    options = {"method": "projection"}
    _us_per_step(contact, 0.01, 1e-3, options), _us_per_step(hand, 0.01, 1e-3, options)       # compile
    with_us, without_us = [], []
    for _ in range(rounds):
        a, run = _us_per_step(contact, 3.0, 1e-3, options)
        b, plain = _us_per_step(hand, 3.0, 1e-3, options)
        with_us.append(a)
        without_us.append(b)
    extra = [a - b for a, b in zip(with_us, without_us)]
    print(f"    walker with contacts (feet with friction, knee stops: 64 modes), 3 s at dt = 0.001 (projection): "
          f"{run.stats['jumps']} jumps; {1e6 / max(with_us):.3g} .. {1e6 / min(with_us):.3g} steps/s "
          f"({min(with_us):.2f} .. {max(with_us):.2f} us/step); the hand-guarded walker ({plain.stats['jumps']} "
          f"jumps) {min(without_us):.2f} .. {max(without_us):.2f} us/step; contact handling {min(extra):.2f} .. "
          f"{max(extra):.2f} us/step (x{min(a / b for a, b in zip(with_us, without_us)):.2f} .. "
          f"x{max(a / b for a, b in zip(with_us, without_us)):.2f}; not the same motion: the contact walker walks "
          "another gait, with other masses)")


def contacts_benchmark(tmp: Path) -> None:
    """Issue 21: runs with contacts, and what contact handling costs against the same motion without it."""
    build = tmp / "contacts_build"
    contact_cost(tmp, build)
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
    # Friction (planar Coulomb): a slipping contact's force is solved non-symmetrically (numerics.slipping.slip_rows),
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
                resolve_impact(model, t, x.copy(), u, p, d.copy(), 0, False)
            best = min(best, (time.perf_counter() - tic) / 200)
        print(f"  one contact impact solved (Python, {label}): {best * 1e6:.0f} us")
    moreau_benchmark(ball, build)


def moreau_benchmark(ball, build: Path) -> None:
    """The moreau method (Moreau-Jean time-stepping, its compiled loop): steps per second on
    the resting ball and the rocking block, against rk4 / projection's event-driven runs of the same models."""
    block = andyc.compile_model(ROOT / "models" / "rocking_block.yaml", build)[0]
    for label, model, t_end, options, event_driven in (
            ("resting ball, 10 s", ball, 10.0, {"parameters": {"h0": 0.0}}, "rk4"),
            ("rocking block, 5 s (rocks, then rests on both corners)", block, 5.0, {}, "projection")):
        moreau = _best_run(model, t_end, 1e-3, repeats=3, method="moreau", **options)
        events = _best_run(model, t_end, 1e-3, repeats=3, method=event_driven, **options)
        s = moreau.stats
        print(f"  moreau, {label}: {s['steps'] / s['wall_seconds']:.3g} steps/s ({s['contact_sweeps']} Gauss-Seidel "
              f"sweeps, {s['unverified_steps']} steps unverified); {event_driven}: {_steps_per_second(events):.3g} "
              "steps/s")
