"""A corpus of hostile and careless input aimed at the features of the last rounds (issue 40): contacts,
simulate: and expect:, `andyc test`, `sweep`, `cycle`, `view`, `graph`, meshes, signals and inputs.

Each case writes its files into a fresh folder and runs one andyc command in process (click's CliRunner). What
must hold for every case (the rules of tests/test_hostile_corpus.py, and two more):

- the exit code is 1 (an invalid model or input, a run that stopped) or 2 (a usage error); no exception but
  SystemExit escapes; no traceback, no internal error, no terminal escape in the output;
- one located line per problem: for a model, every line but the count is `FILE:LINE: PATH: what; fix` in the
  model's file (and at the document path the case names, when it names one); for an option or another input,
  one `Error: ...` line (click's `Invalid value for '--x': ...` where an option's value is wrong), or the
  command's one `andyc: ...` line;
- nothing is written outside what the case names as the command's outputs (the folder's files before and
  after), and the inputs it names are unchanged.

Most cases are `andyc check` of a model text or an option refused before any work; those that need a compiled
model use the shipped models' builds, compiled once for all (build/tests).
"""

from __future__ import annotations

import os
import re
from dataclasses import dataclass, field
from pathlib import Path

import pytest

from tests.support import MODELS, yaml_text
from tests.support.cli import invoke
from tests.support.diagnostics import LINE_FORMAT

FIFO = object()                 # a file value: a named pipe


@dataclass
class Case:
    id: str
    args: list                  # {d}: the case's folder, {b}: the shipped models' build folder, {m}: models/
    files: dict = field(default_factory=dict)
    codes: tuple = (1, 2)
    kind: str = "option"        # "model": FILE:LINE lines of files["m.yaml"]; "option": one Error: line; "line":
    #                             one line of the command's own (andyc: ... or Error: ...)
    path: str | None = None     # the document path a model case's problem is at
    says: str = ""
    writes: tuple = ()          # files (relative to the folder) the command may make
    needs: str | None = None    # a shipped model this case needs compiled


# -- the models to break ---------------------------------------------------------------------------------------

BALL = """\
name: cball
description: A point mass bouncing on the ground.
parameters: {m: 1.0, g: 9.81, h0: 1.0, e: 0.8}
coordinates:
  y: {initial: h0}
gravity: [0, -g, 0]
frames:
  - {name: ball, parent: world, prismatic: y, axis: y}
bodies:
  - {name: mass, frame: ball, mass: m}
contacts:
  - {name: ground, gap: ball.y, restitution: e, multiplier: normal_force}
"""

BLOCK = """\
name: fblock
description: A block on an incline with Coulomb friction.
parameters: {m: 1.0, g: 9.81, th: 0.5, mu: 0.3}
coordinates:
  x: {initial: 0}
  y: {initial: 0}
gravity: [0, -g, 0]
frames:
  - {name: slide, parent: world, prismatic: x, axis: x}
  - {name: block, parent: slide, prismatic: y, axis: y}
bodies:
  - {name: mass, frame: block, mass: m}
contacts:
  - name: slope
    gap: cos(th)*block.y - sin(th)*block.x
    slip: cos(th)*block.vx + sin(th)*block.vy
    friction: mu
    multiplier: normal_force
"""

PENDULUM = """\
name: pend
description: A pendulum with an input torque.
parameters: {m: 1.0, l: 1.0, g: 9.81}
inputs: {T: 0}
coordinates:
  q: {initial: 0.5}
gravity: [0, -g, 0]
frames:
  - {name: arm, parent: world, revolute: q, shape: {box: {size: [0.02, l, 0.02]}}}
  - {name: tip, parent: arm, translation: [0, -l, 0]}
bodies:
  - {name: bob, frame: tip, mass: m}
torques:
  - {name: drive, frame: arm, vector: [0, 0, T]}
simulate: {t_end: 1, dt: 1.0e-3}
expect:
  - t_end: 1
    energy_balance: 1.0e-6
"""


def edited(base: str, old: str, new: str) -> str:
    assert base.count(old) == 1, f"{old!r} must occur once"
    return base.replace(old, new)


def model(id, base, old, new, path=None, says="", files=None):
    return Case(id, ["check", "{d}/m.yaml"], {"m.yaml": edited(base, old, new), **(files or {})}, (1,), "model",
                path, says)


def contact(id, old, new, path=None, says="", base=BALL):
    return model(f"contact-{id}", base, old, new, path, says)


# -- 1. contacts -------------------------------------------------------------------------------------------------

GAP = "gap: ball.y, "
CONTACT_CASES = [
    contact("restitution-negative", "restitution: e,", "restitution: -0.5,", "contacts[0].restitution"),
    contact("restitution-above-1", "restitution: e,", "restitution: 1.5,", "contacts[0].restitution"),
    contact("restitution-nan", "restitution: e,", "restitution: .nan,", "contacts[0].restitution"),
    contact("restitution-inf", "restitution: e,", "restitution: .inf,", "contacts[0].restitution"),
    contact("restitution-text", "restitution: e,", "restitution: bouncy,", "contacts[0].restitution"),
    contact("restitution-list", "restitution: e,", "restitution: [1, 2],", "contacts[0].restitution"),
    contact("restitution-uses-state", "restitution: e,", "restitution: y,", "contacts[0].restitution"),
    contact("restitution-uses-time", "restitution: e,", "restitution: e*t,", "contacts[0].restitution"),
    contact("restitution-payload", "restitution: e,", "restitution: 'e # __import__(\"os\")',",
            "contacts[0].restitution", "'#'"),
    contact("restitution-param-above-1", "e: 0.8}", "e: 1.8}", None),
    contact("gap-constant", GAP, "gap: h0, ", "contacts[0].gap"),
    contact("gap-number", GAP, "gap: 1, ", "contacts[0].gap"),
    contact("gap-empty", GAP, "gap: '', ", "contacts[0].gap"),
    contact("gap-unknown-name", GAP, "gap: bal.y, ", "contacts[0].gap"),
    contact("gap-unknown-frame-quantity", GAP, "gap: ball.w, ", "contacts[0].gap"),
    contact("gap-uses-speed", GAP, "gap: y_dot, ", "contacts[0].gap"),
    contact("gap-overflow", GAP, "gap: 'ball.y*1e308*10', ", "contacts[0].gap", "overflows"),
    contact("gap-comparison", GAP, "gap: 'ball.y > 0', ", "contacts[0].gap"),
    contact("gap-division-by-zero", GAP, "gap: 'ball.y/0', ", "contacts[0].gap"),
    contact("gap-list", GAP, "gap: [ball.y, y], ", "contacts[0].gap"),
    contact("gap-missing", GAP, "", "contacts[0]"),
    contact("name-missing", "{name: ground, ", "{", "contacts[0]"),
    contact("name-keyword", "{name: ground, ", "{name: class, ", "contacts[0].name"),
    contact("name-taken-by-frame", "{name: ground, ", "{name: ball, ", None),
    contact("unknown-key", "multiplier: normal_force}", "multiplier: normal_force, stiffness: 1}",
            "contacts[0].stiffness"),
    contact("multiplier-bad-name", "multiplier: normal_force}", "multiplier: 'normal force'}",
            "contacts[0].multiplier"),
    contact("multiplier-taken", "multiplier: normal_force}", "multiplier: y_dot}", None),
    contact("multiplier-list", "multiplier: normal_force}", "multiplier: [a, b]}", "contacts[0].multiplier"),
    contact("duplicate-contact", "  - {name: ground, gap: ball.y, restitution: e, multiplier: normal_force}\n",
            "  - {name: ground, gap: ball.y, restitution: e, multiplier: normal_force}\n"
            "  - {name: ground, gap: ball.y - 1, restitution: e, multiplier: f2}\n", None),
    contact("more-than-1024-contacts", "  - {name: ground, gap: ball.y, restitution: e, multiplier: normal_force}\n",
            "".join(f"  - {{name: c{k}, gap: ball.y + {k}}}\n" for k in range(1025)), "contacts"),
    contact("contacts-not-a-list", "contacts:\n  - {name: ground, gap: ball.y, restitution: e, multiplier: "
            "normal_force}\n", "contacts: {name: ground}\n", "contacts"),
    contact("contacts-empty-entry", "  - {name: ground, gap: ball.y, restitution: e, multiplier: normal_force}\n",
            "  - {}\n", "contacts[0]"),
    contact("flow-lists-a-contact-row", "contacts:\n", "hybrid: {flows: [{name: f, constraints: [ground]}]}\n"
            "contacts:\n", "hybrid.flows[0].constraints[0]", "contact"),
    contact("slip-without-friction", "multiplier: normal_force}", "multiplier: normal_force, slip: y_dot}", None),
    contact("friction-without-slip", "multiplier: normal_force}", "multiplier: normal_force, friction: 0.3}", None),
    contact("friction-negative", "friction: mu", "friction: -0.3", "contacts[0].friction", base=BLOCK),
    contact("friction-nan", "friction: mu", "friction: .nan", "contacts[0].friction", base=BLOCK),
    contact("friction-inf", "friction: mu", "friction: .inf", "contacts[0].friction", base=BLOCK),
    contact("friction-text", "friction: mu", "friction: sticky", "contacts[0].friction", base=BLOCK),
    contact("friction-uses-state", "friction: mu", "friction: x", "contacts[0].friction", base=BLOCK),
    contact("friction-uses-time", "friction: mu", "friction: mu*t", "contacts[0].friction", base=BLOCK),
    contact("friction-param-negative", "mu: 0.3}", "mu: -0.3}", None, base=BLOCK),
    contact("slip-no-speed", "slip: cos(th)*block.vx + sin(th)*block.vy", "slip: block.x", "contacts[0].slip",
            base=BLOCK),
    contact("slip-squared", "slip: cos(th)*block.vx + sin(th)*block.vy", "slip: block.vx**2", "contacts[0].slip",
            base=BLOCK),
    contact("slip-product-of-speeds", "slip: cos(th)*block.vx + sin(th)*block.vy", "slip: x_dot*y_dot",
            "contacts[0].slip", base=BLOCK),
    contact("slip-in-function", "slip: cos(th)*block.vx + sin(th)*block.vy", "slip: sin(x_dot)", "contacts[0].slip",
            base=BLOCK),
    contact("slip-three", "slip: cos(th)*block.vx + sin(th)*block.vy", "slip: [x_dot, y_dot, x_dot]",
            "contacts[0].slip", base=BLOCK),
    contact("slip-empty-list", "slip: cos(th)*block.vx + sin(th)*block.vy", "slip: []", "contacts[0].slip",
            base=BLOCK),
    contact("slip-two-identical", "slip: cos(th)*block.vx + sin(th)*block.vy", "slip: [x_dot, x_dot]", None,
            base=BLOCK),                # (issue 40, the lead's: three warnings about andyc's own discrete states)
    contact("slip-payload", "slip: cos(th)*block.vx + sin(th)*block.vy", "slip: 'x_dot # x'", "contacts[0].slip",
            "'#'", base=BLOCK),
    contact("friction-multiplier-taken", "multiplier: normal_force\n",
            "multiplier: normal_force\n    friction_multiplier: normal_force\n", None, base=BLOCK),
    contact("friction-multiplier-count", "multiplier: normal_force\n",
            "multiplier: normal_force\n    friction_multiplier: [a, b]\n", None, base=BLOCK),
    contact("gap-starts-closed-inside", "y: {initial: h0}", "y: {initial: -1}", None),
]

# -- 2. simulate: and expect: ------------------------------------------------------------------------------------

SIM = "simulate: {t_end: 1, dt: 1.0e-3}"
EXPECT = "  - t_end: 1\n    energy_balance: 1.0e-6\n"


def simulate(id, new, path, says=""):
    return model(f"simulate-{id}", PENDULUM, SIM, f"simulate: {new}", path, says)


def expect(id, new, path, says=""):
    return model(f"expect-{id}", PENDULUM, EXPECT, new, path, says)


SIMULATE_CASES = [
    simulate("t-end-inf", "{t_end: .inf}", "simulate.t_end", "not a finite number"),
    simulate("t-end-nan", "{t_end: .nan}", "simulate.t_end", "not a finite number"),
    simulate("t-end-negative", "{t_end: -1}", "simulate.t_end"),
    simulate("t-end-zero", "{t_end: 0}", "simulate.t_end"),
    simulate("t-end-1e309", "{t_end: 1e309}", "simulate.t_end", "not a finite number"),
    simulate("t-end-text", "{t_end: long}", "simulate.t_end"),
    simulate("t-end-huge", "{t_end: 1.0e+300}", "simulate.t_end", "past the limit of 1e+11"),
    simulate("dt-nan", "{dt: .nan}", "simulate.dt", "not a finite number"),
    simulate("dt-zero", "{dt: 0}", "simulate.dt"),
    simulate("dt-tiny", "{dt: 1.0e-300}", "simulate.dt", "past the limit of 1e+11"),
    simulate("dt-longer-than-run", "{t_end: 1, dt: 2}", "simulate.dt", "longer than t_end"),
    simulate("rtol-nan", "{rtol: .nan}", "simulate.rtol", "not a finite number"),
    simulate("rtol-one", "{rtol: 1}", "simulate.rtol"),
    simulate("atol-inf", "{atol: .inf}", "simulate.atol", "not a finite number"),
    simulate("atol-zero", "{atol: 0}", "simulate.atol"),
    simulate("method-unknown", "{method: euler}", "simulate.method"),
    simulate("method-number", "{method: 4}", "simulate.method"),
    simulate("init-unknown", "{init: maybe}", "simulate.init"),
    simulate("init-tol-nan", "{init_tol: .nan}", "simulate.init_tol", "not a finite number"),
    simulate("energy-tol-inf", "{energy_tol: .inf}", "simulate.energy_tol", "not a finite number"),
    simulate("event-tol-zero", "{event_tol: 0}", "simulate.event_tol"),
    simulate("event-tol-above-1", "{event_tol: 2}", "simulate.event_tol"),
    simulate("zeno-tol-nan", "{zeno_tol: .nan}", "simulate.zeno_tol", "not a finite number"),
    simulate("every-zero", "{every: 0}", "simulate.every"),
    simulate("every-float", "{every: 2.5}", "simulate.every"),
    simulate("every-huge", "{every: 100000000000000000000000}", "simulate.every", "past the limit"),
    simulate("max-instant-jumps-zero", "{max_instant_jumps: 0}", "simulate.max_instant_jumps"),
    simulate("max-instant-jumps-huge", "{max_instant_jumps: 100000000000000000000}", "simulate.max_instant_jumps",
             "past the limit"),
    simulate("frames-unknown", "{frames: [hand]}", "simulate.frames[0]"),
    simulate("frames-text", "{frames: some}", "simulate.frames"),
    simulate("stop-after-unknown-jump", "{stop_after: {bounce: 1}}", "simulate.stop_after.bounce"),
    simulate("stop-after-zero", "{stop_after: {bounce: 0}}", "simulate.stop_after.bounce"),
    simulate("unknown-option", "{t_edn: 1}", "simulate.t_edn"),
    simulate("energy-correction-text", "{energy_correction: maybe}", "simulate.energy_correction"),
    simulate("not-a-mapping", "[1, 2]", "simulate"),
    simulate("output-option", "{out: /etc/passwd}", "simulate.out"),
]

EXPECT_CASES = [
    expect("t-end-missing", "  - {energy_drift: 1}\n", "expect[0]"),
    expect("t-end-inf", "  - {t_end: .inf}\n", "expect[0].t_end", "not a finite number"),
    expect("t-end-1e309", "  - {t_end: 1e309}\n", "expect[0].t_end", "not a finite number"),
    expect("t-end-huge", "  - {t_end: 1.0e+300}\n", "expect[0].t_end", "past the limit of 1e+11"),
    expect("t-end-negative", "  - {t_end: -1}\n", "expect[0].t_end"),
    expect("dt-nan", "  - {t_end: 1, dt: .nan}\n", "expect[0].dt", "not a finite number"),
    expect("rtol-nan", "  - {t_end: 1, rtol: .nan}\n", "expect[0].rtol", "not a finite number"),
    expect("energy-drift-nan", "  - {t_end: 1, energy_drift: .nan}\n", "expect[0].energy_drift",
           "not a finite number"),
    expect("energy-drift-negative", "  - {t_end: 1, energy_drift: -1}\n", "expect[0].energy_drift"),
    expect("energy-balance-inf", "  - {t_end: 1, energy_balance: .inf}\n", "expect[0].energy_balance",
           "not a finite number"),
    expect("residual-without-constraints", "  - {t_end: 1, residual: 1.0e-9}\n", "expect[0].residual",
           "no constraints"),
    expect("residual-nan", "  - {t_end: 1, residual: .nan}\n", "expect[0].residual", "not a finite number"),
    expect("jumps-unknown", "  - {t_end: 1, jumps: {bounce: 1}}\n", "expect[0].jumps.bounce"),
    expect("jumps-negative", "  - {t_end: 1, jumps: {bounce: -1}}\n", "expect[0].jumps.bounce"),
    expect("jump-times-tol-nan", "  - {t_end: 1, jump_times: {times: {}, tol: .nan}}\n", "expect[0].jump_times.tol",
           "not a finite number"),
    expect("jump-times-nan", "  - {t_end: 1, jump_times: {times: {bounce: [.nan]}, tol: 1}}\n",
           "expect[0].jump_times.times.bounce[0]", "not a finite number"),
    expect("jump-times-unknown-jump", "  - {t_end: 1, jump_times: {times: {bounce: [0.1]}, tol: 1}}\n",
           "expect[0].jump_times.times.bounce"),
    expect("states-t-past-end", "  - {t_end: 1, states: [{t: 2, values: {q: 0}, tol: 1}]}\n",
           "expect[0].states[0].t", "past the run's end"),
    expect("states-t-nan", "  - {t_end: 1, states: [{t: .nan, values: {q: 0}, tol: 1}]}\n",
           "expect[0].states[0].t", "not a finite number"),
    expect("states-value-inf", "  - {t_end: 1, states: [{t: 1, values: {q: .inf}, tol: 1}]}\n",
           "expect[0].states[0].values.q", "not a finite number"),
    expect("states-unknown-state", "  - {t_end: 1, states: [{t: 1, values: {qq: 0}, tol: 1}]}\n",
           "expect[0].states[0].values.qq"),
    expect("states-tol-negative", "  - {t_end: 1, states: [{t: 1, values: {q: 0}, tol: -1}]}\n",
           "expect[0].states[0].tol"),
    expect("states-no-closed-form", "  - {t_end: 1, states: [{t: 1, closed_form: true, tol: 1}]}\n",
           "expect[0].states[0].closed_form", "no closed_form"),
    expect("states-reference-missing", "  - {t_end: 1, states: [{t: 1, reference: nope.h5, tol: 1}]}\n",
           "expect[0].states[0].reference", "does not exist"),
    expect("final-min-nan", "  - {t_end: 1, final: [{value: q, min: .nan}]}\n", "expect[0].final[0].min",
           "not a finite number"),
    expect("final-max-1e309", "  - {t_end: 1, final: [{value: q, max: 1e309}]}\n", "expect[0].final[0].max",
           "not a finite number"),
    expect("final-min-above-max", "  - {t_end: 1, final: [{value: q, min: 2, max: 1}]}\n", "expect[0].final[0]",
           "above max"),
    expect("final-payload", "  - {t_end: 1, final: [{value: 'q # __import__(\"os\")', max: 1}]}\n",
           "expect[0].final[0].value", "'#'"),
    expect("final-unknown-name", "  - {t_end: 1, final: [{value: qq, max: 1}]}\n", "expect[0].final[0].value"),
    expect("final-uses-input", "  - {t_end: 1, final: [{value: T, max: 1}]}\n", "expect[0].final[0].value"),
    expect("parameters-unknown", "  - {t_end: 1, parameters: {mass: 1}}\n", "expect[0].parameters.mass"),
    expect("parameters-inf", "  - {t_end: 1, parameters: {m: .inf}}\n", "expect[0].parameters.m",
           "not a finite number"),
    expect("inputs-unknown", "  - {t_end: 1, inputs: {F: 1}}\n", "expect[0].inputs.F"),
    expect("inputs-payload", "  - {t_end: 1, inputs: {T: '1 # x'}}\n", "expect[0].inputs.T", "'#'"),
    expect("inputs-tower", "  - {t_end: 1, inputs: {T: '2**2**2**2**2**2'}}\n", "expect[0].inputs.T",
           "past the limit"),
    expect("unknown-check", "  - {t_end: 1, energy_drfit: 1}\n", "expect[0].energy_drfit"),
    expect("not-a-list", "  {t_end: 1}\n", "expect"),
]

# -- 3. andyc test, sweep, cycle, view, graph: options and their inputs -------------------------------------------

P = "{m}/double_pendulum.yaml"
SWEEP = ["sweep", P, "--build-dir", "{b}", "-o", "{d}/s.zarr", "--t-end", "0.05"]


def sweep(id, *args, says="", kind="line", needs=None):
    return Case(f"sweep-{id}", [*SWEEP, *args], {}, (2,), kind, None, says, needs=needs)


TEST_CASES = [
    Case("test-no-path", ["test"], {}, (2,)),
    Case("test-missing-path", ["test", "{d}/nope.yaml"], {}, (2,), says="does not exist"),
    Case("test-junit-is-model", ["test", "{d}/m.yaml", "--junit", "{d}/m.yaml"], {"m.yaml": PENDULUM}, (2,),
         says="overwrite"),
    Case("test-junit-folder", ["test", "{d}/m.yaml", "--junit", "{d}/out"], {"m.yaml": PENDULUM, "out/keep": ""},
         (2,)),
    Case("test-junit-under-file", ["test", "{d}/m.yaml", "--junit", "{d}/f/j.xml"], {"m.yaml": PENDULUM, "f": "x"},
         (2,), says="not a folder"),
    Case("test-build-dir-is-model", ["test", "{d}/m.yaml", "--build-dir", "{d}/m.yaml"], {"m.yaml": PENDULUM},
         (2,)),
    Case("test-format-unknown", ["test", "{d}/m.yaml", "--format", "xml"], {"m.yaml": PENDULUM}, (2,)),
    Case("test-bad-model", ["test", "{d}/m.yaml", "--build-dir", "{d}/build"],
         {"m.yaml": edited(PENDULUM, "m: 1.0,", "m: -1.0,")}, (1,), "model", "parameters.m"
         if False else None),
    Case("test-nan-expectation", ["test", "{d}/m.yaml", "--build-dir", "{d}/build"],
         {"m.yaml": edited(PENDULUM, "energy_balance: 1.0e-6", "energy_balance: .nan")}, (1,), "model",
         "expect[0].energy_balance"),
    Case("test-empty-folder", ["test", "{d}/models", "--build-dir", "{d}/build"], {"models/keep": ""}, (5,), "line",
         says="nothing tested"),
    Case("test-folder-of-text", ["test", "{d}/models", "--build-dir", "{d}/build"], {"models/notes.txt": "x"}, (5,),
         "line", says="no model file"),
    Case("test-broken-link", ["test", "{d}/models", "--build-dir", "{d}/build"], {"models/m.yaml": "->nowhere.yaml"},
         (1,), "line", says="cannot read the file"),
    Case("test-fifo-model", ["test", "{d}/m.yaml", "--build-dir", "{d}/build"], {"m.yaml": FIFO}, (1,), "line",
         says="special file"),
]

SWEEP_CASES = [
    sweep("no-points", says="choose the points one way"),
    sweep("two-ways", "--grid", "m1=0:1:2", "--samples", "3", says="choose the points one way"),
    sweep("grid-huge", "--grid", "m1=1:2:1000000000", says="past the limit of 1e+07"),
    sweep("grid-product-huge", "--grid", "m1=1:2:100000", "--grid", "m2=1:2:1000", says="past the limit"),
    sweep("grid-count-digits", "--grid", "m1=1:2:" + "9" * 5000, says="past the limit"),
    sweep("grid-count-negative", "--grid", "m1=1:2:-3", says="empty range"),
    sweep("grid-count-float", "--grid", "m1=1:2:2.5", says="not a whole number"),
    sweep("grid-nan", "--grid", "m1=nan:2:3", says="not a finite number"),
    sweep("grid-inf", "--grid", "m1=1:inf:3", says="not a finite number"),
    sweep("grid-malformed", "--grid", "m1", says="not NAME=FROM:TO:COUNT"),
    sweep("grid-payload-name", "--grid", "__import__('os')=1:2:3", says="not NAME=FROM:TO:COUNT"),
    sweep("grid-unknown-name", "--grid", "mass=1:2:2", says="unknown name 'mass'", needs="double_pendulum"),
    sweep("grid-twice", "--grid", "m1=1:2:2", "--grid", "m1=1:2:2", says="swept twice", needs="double_pendulum"),
    sweep("grid-reserved", "--grid", "m1=1:2:2", "--metric", "outcome=max(q1)", says="store's own variable",
          needs="double_pendulum"),
    sweep("samples-zero", "--samples", "0", "--dist", "m1=normal(1,0.1)", kind="option"),
    sweep("samples-huge", "--samples", "100000000", "--dist", "m1=normal(1,0.1)", says="past the limit"),
    sweep("samples-no-dist", "--samples", "3", says="needs at least one --dist"),
    sweep("dist-without-samples", "--grid", "m1=1:2:2", "--dist", "m1=normal(1,0.1)", says="goes with --samples"),
    sweep("dist-unknown", "--samples", "3", "--dist", "m1=gamma(1,2)", says="a bad distribution"),
    sweep("dist-sigma-negative", "--samples", "3", "--dist", "m1=normal(1,-1)", says="must be above 0"),
    sweep("dist-uniform-reversed", "--samples", "3", "--dist", "m1=uniform(2,1)", says="needs A < B"),
    sweep("dist-nan", "--samples", "3", "--dist", "m1=normal(nan,1)", says="not a finite number"),
    sweep("seed-negative", "--samples", "3", "--dist", "m1=normal(1,0.1)", "--seed", "-1", kind="option"),
    sweep("seed-huge", "--samples", "3", "--dist", "m1=normal(1,0.1)", "--seed", "1" + "0" * 30, kind="option"),
    Case("sweep-points-dev-zero", [*SWEEP, "--points", "/dev/zero"], {}, (2,), "line", says="special file"),
    Case("sweep-points-fifo", [*SWEEP, "--points", "{d}/p.csv"], {"p.csv": FIFO}, (2,), "line", says="special file"),
    Case("sweep-points-missing", [*SWEEP, "--points", "{d}/nope.csv"], {}, (2,), "line", says="no such file"),
    Case("sweep-points-empty", [*SWEEP, "--points", "{d}/p.csv"], {"p.csv": ""}, (2,), "line", says="p.csv:1: empty"),
    Case("sweep-points-header-only", [*SWEEP, "--points", "{d}/p.csv"], {"p.csv": "m1\n"}, (2,), "line",
         says="a header and no points"),
    Case("sweep-points-bad-header", [*SWEEP, "--points", "{d}/p.csv"], {"p.csv": "m 1\n1\n"}, (2,), "line",
         says="is not a name"),
    Case("sweep-points-nan", [*SWEEP, "--points", "{d}/p.csv"], {"p.csv": "m1\n1\nnan\n"}, (2,), "line",
         says="p.csv:3: m1 is 'nan', not a finite number"),
    Case("sweep-points-ragged", [*SWEEP, "--points", "{d}/p.csv"], {"p.csv": "m1,m2\n1\n"}, (2,), "line",
         says="p.csv:2: 1 values for 2 names"),
    Case("sweep-points-binary", [*SWEEP, "--points", "{d}/p.csv"], {"p.csv": b"\xff\xfe\x00garbage"}, (2,), "line",
         says="cannot read it as a CSV text file"),
    Case("sweep-points-nul", [*SWEEP, "--points", "{d}/p.csv"], {"p.csv": "m1\n1\x00\n"}, (2,), "line"),
    Case("sweep-points-unknown-name", [*SWEEP, "--points", "{d}/p.csv"], {"p.csv": "mass\n1\n"}, (2,), "line",
         says="unknown name 'mass'", needs="double_pendulum"),
    sweep("metric-unparsable", "--grid", "m1=1:2:2", "--metric", "e=max(energy", says="cannot parse"),
    sweep("metric-payload", "--grid", "m1=1:2:2", "--metric", "e=__import__('os').system('x')"),
    sweep("metric-no-name", "--grid", "m1=1:2:2", "--metric", "max(q1)"),
    sweep("metric-unknown-name", "--grid", "m1=1:2:2", "--metric", "e=max(qq)", says="unknown name 'qq'",
          needs="double_pendulum"),
    sweep("metric-nested-run-function", "--grid", "m1=1:2:2", "--metric", "e=max(min(q1))", needs="double_pendulum"),
    sweep("metric-tower", "--grid", "m1=1:2:2", "--metric", "e=2**2**2**2**2**2", says="past the limit"),
    sweep("set-unknown", "--grid", "m1=1:2:2", "--set", "nope=1", says="has no parameter or input 'nope'",
          needs="double_pendulum"),
    sweep("set-nan", "--grid", "m1=1:2:2", "--set", "m2=nan", kind="option"),
    sweep("stop-after-unknown", "--grid", "m1=1:2:2", "--stop-after", "bounce=1", says="has no jump 'bounce'",
          needs="double_pendulum"),
    sweep("trajectory-one", "--grid", "m1=1:2:2", "--trajectory", "1", says="--trajectory 1"),
    sweep("trajectory-huge", "--grid", "m1=1:2:2", "--trajectory", "1000000000", kind="option"),
    sweep("workers-zero", "--grid", "m1=1:2:2", "--workers", "0", kind="option"),
    sweep("workers-and-scheduler", "--grid", "m1=1:2:2", "--workers", "2", "--scheduler", "tcp://127.0.0.1:9",
          says="give one of them"),
    sweep("batch-zero", "--grid", "m1=1:2:2", "--batch", "0", kind="option"),
    sweep("timeout-nan", "--grid", "m1=1:2:2", "--timeout", "nan", kind="option"),
    sweep("timeout-zero", "--grid", "m1=1:2:2", "--timeout", "0", kind="option"),
    sweep("t-end-inf", "--grid", "m1=1:2:2", "--t-end", "inf", kind="option"),
    sweep("dt-negative", "--grid", "m1=1:2:2", "--dt", "-1", kind="option"),
    sweep("rtol-one", "--grid", "m1=1:2:2", "--rtol", "1", kind="option"),
    sweep("method-unknown", "--grid", "m1=1:2:2", "--method", "euler", kind="option"),
    sweep("max-events-zero", "--grid", "m1=1:2:2", "--max-events", "0", kind="option"),
    Case("sweep-out-is-points", [*SWEEP, "--points", "{d}/p.csv", "-o", "{d}/p.csv"], {"p.csv": "m1\n1\n"}, (2,),
         "line", says="overwrite", needs="double_pendulum"),
    Case("sweep-out-is-a-file", [*SWEEP, "--grid", "m1=1:2:2", "-o", "{d}/s.zarr"], {"s.zarr": "not a store"}, (2,),
         "line", needs="double_pendulum"),
    Case("sweep-out-is-other-folder", [*SWEEP, "--grid", "m1=1:2:2", "-o", "{d}/s.zarr"], {"s.zarr/x": "x"}, (2,),
         "line", says="not a sweep's result store", needs="double_pendulum"),
    Case("sweep-scheduler-refused", [*SWEEP, "--grid", "m1=1:2:2", "--scheduler", "tcp://127.0.0.1:9"], {}, (1,),
         "line", says="Connection refused", needs="double_pendulum"),
    Case("sweep-scheduler-scheme", [*SWEEP, "--grid", "m1=1:2:2", "--scheduler", "http://127.0.0.1:1"], {}, (1,),
         "line", says="unknown address scheme", needs="double_pendulum"),
    Case("sweep-model-missing", ["sweep", "{d}/nope.yaml", "--grid", "m1=1:2:2", "-o", "{d}/s.zarr"], {}, (1, 2),
         "line"),
    Case("sweep-model-invalid", ["sweep", "{d}/m.yaml", "--grid", "m=1:2:2", "-o", "{d}/s.zarr", "--build-dir",
                                 "{d}/build"], {"m.yaml": edited(PENDULUM, "m: 1.0,", "m: .nan,")}, (1,), "model"),
    Case("plot-store-not-a-store", ["plot", "{d}/s.zarr", "-o", "{d}/p.png"], {"s.zarr/x": "x"}, (2,),
         says="not a result store"),
    Case("plot-store-with-signals", ["plot", "{d}/s.zarr", "--signals", "q1"], {"s.zarr/x": "x"}, (2,),
         says="not a sweep's store"),
]

CYCLE = ["cycle", "{m}/compass_gait.yaml", "--section", "strike", "--build-dir", "{b}", "-o", "{d}/c.json"]


def cycle(id, *args, says="", kind="option", codes=(2,), needs=None):
    return Case(f"cycle-{id}", [*CYCLE, *args], {}, codes, kind, None, says, needs=needs)


CYCLE_CASES = [
    Case("cycle-no-section", ["cycle", "{m}/compass_gait.yaml", "-o", "{d}/c.json"], {}, (2,)),
    cycle("period-zero", "--period", "0"),
    cycle("period-negative", "--period", "-1"),
    cycle("dt-nan", "--dt", "nan"),
    cycle("dt-zero", "--dt", "0"),
    cycle("tol-inf", "--tol", "inf"),
    cycle("tol-zero", "--tol", "0"),
    cycle("max-iterations-zero", "--max-iterations", "0"),
    cycle("t-max-nan", "--t-max", "nan"),
    cycle("event-tol-negative", "--event-tol", "-1"),
    cycle("at-nan", "--at", "th1=nan"),
    cycle("at-malformed", "--at", "th1", kind="line"),
    cycle("continue-malformed", "--continue", "slope", kind="line"),
    cycle("continue-empty", "--continue", "slope=0.1:0.1", kind="line"),
    cycle("continue-nan", "--continue", "slope=nan:0.1", kind="line"),
    cycle("step-zero", "--continue", "slope=0:0.1", "--step", "0"),
    cycle("max-points-zero", "--continue", "slope=0:0.1", "--max-points", "0"),
    cycle("basin-and-continue", "--continue", "slope=0:0.1", "--basin", "th1=0:1:2", kind="line",
          says="give one of them"),
    cycle("steps-zero", "--basin", "th1=0:1:2", "--steps", "0"),
    cycle("workers-zero", "--basin", "th1=0:1:2", "--workers", "0"),
    Case("cycle-out-is-model", ["cycle", "{d}/m.yaml", "--section", "x", "-o", "{d}/m.yaml"], {"m.yaml": BALL}, (2,),
         "line", says="overwrite"),
    Case("cycle-model-invalid", ["cycle", "{d}/m.yaml", "--section", "x", "--build-dir", "{d}/build", "-o",
                                 "{d}/c.json"], {"m.yaml": edited(BALL, "mass: m}", "mass: -m}")}, (1,), "model"),
    cycle("section-unknown", "--section", "bounce", kind="line", codes=(1, 2), needs="compass_gait"),
]

RUN = "{run}"
VIEW_CASES = [
    Case("view-missing", ["view", "{d}/nope.h5"], {}, (2,)),
    Case("view-not-h5", ["view", "{d}/r.csv"], {"r.csv": "t\n0\n"}, (2,)),
    Case("view-garbage", ["view", "{d}/r.h5", "-o", "{d}/r.html"], {"r.h5": b"\x89HDF\r\n\x1a\ngarbage"}, (2,)),
    Case("view-empty-h5", ["view", "{d}/r.h5", "-o", "{d}/r.html"], {"r.h5": "EMPTY_H5"}, (2,)),
    Case("view-out-not-html", ["view", RUN, "-o", "{d}/r.png"], {}, (2,), says=".html"),
    Case("view-out-is-run", ["view", RUN, "-o", RUN], {}, (2,)),
    Case("view-out-folder", ["view", RUN, "-o", "{d}/dir.html"], {"dir.html/keep": ""}, (2,)),
    Case("view-out-under-file", ["view", RUN, "-o", "{d}/f/r.html"], {"f": "x"}, (2,)),
    Case("view-fps-zero", ["view", RUN, "--fps", "0", "-o", "{d}/r.html"], {}, (2,)),
    Case("view-fps-nan", ["view", RUN, "--fps", "nan", "-o", "{d}/r.html"], {}, (2,)),
    Case("view-max-samples-zero", ["view", RUN, "--max-samples", "0", "-o", "{d}/r.html"], {}, (2,)),
    Case("view-follow-unknown", ["view", RUN, "--follow", "hand", "-o", "{d}/r.html"], {}, (2,),
         says="logged no frame 'hand'"),
    Case("view-trails-unknown", ["view", RUN, "--trails", "tip,hand", "-o", "{d}/r.html"], {}, (2,),
         says="logged no frame 'hand'"),
    Case("view-no-frames", ["view", "{d}/nf.h5", "-o", "{d}/r.html"], {"nf.h5": "NO_FRAMES"}, (2,),
         says="logged no frames"),
    Case("view-fifo", ["view", "{d}/r.h5", "-o", "{d}/r.html"], {"r.h5": FIFO}, (2,)),
    Case("plot-window-nan", ["plot", RUN, "--window", "nan:1", "-o", "{d}/p.png"], {}, (2,)),
    Case("plot-window-reversed", ["plot", RUN, "--window", "2:1", "-o", "{d}/p.png"], {}, (2,)),
    Case("plot-window-malformed", ["plot", RUN, "--window", "1", "-o", "{d}/p.png"], {}, (2,)),
    Case("plot-window-empty", ["plot", RUN, "--window", "5:6", "-o", "{d}/p.png"], {}, (2,)),
    Case("plot-signals-unknown", ["plot", RUN, "--signals", "nope", "-o", "{d}/p.png"], {}, (2,)),
    Case("plot-signals-empty", ["plot", RUN, "--signals", ",", "-o", "{d}/p.png"], {}, (2,)),
    Case("plot-signals-with-animate", ["plot", RUN, "--signals", "y", "--animate", "-o", "{d}/p.gif"], {}, (2,)),
    Case("plot-signals-escape", ["plot", RUN, "--signals", "\x1b[2J", "-o", "{d}/p.png"], {}, (2,)),
    Case("plot-out-xyz", ["plot", RUN, "-o", "{d}/p.xyz"], {}, (2,), says="unknown image type"),
    Case("plot-out-pgf", ["plot", RUN, "-o", "{d}/p.pgf"], {}, (2,), says="unknown image type"),
    Case("plot-animate-out-png", ["plot", RUN, "--animate", "-o", "{d}/p.png"], {}, (2,)),
    Case("plot-frames-max-zero", ["plot", RUN, "--animate", "--frames-max", "0", "-o", "{d}/p.gif"], {}, (2,)),
    Case("plot-fps-without-animate", ["plot", RUN, "--fps", "10", "-o", "{d}/p.png"], {}, (2,)),
    Case("plot-metric-on-run", ["plot", RUN, "--metric", "x", "-o", "{d}/p.png"], {}, (2,)),
]

GRAPH_CASES = [
    Case("graph-missing", ["graph", "{d}/nope.yaml", "-o", "{d}/g.svg"], {}, (1, 2), "line"),
    Case("graph-invalid-model", ["graph", "{d}/m.yaml", "-o", "{d}/g.svg"],
         {"m.yaml": edited(BALL, "parent: world", "parent: wrld")}, (1,), "model", "frames[0].parent"),
    Case("graph-out-xyz", ["graph", "{d}/m.yaml", "-o", "{d}/g.xyz"], {"m.yaml": BALL}, (2,)),
    Case("graph-out-is-model", ["graph", "{d}/m.yaml", "-o", "{d}/m.yaml"], {"m.yaml": BALL}, (2,)),
    Case("graph-out-folder", ["graph", "{d}/m.yaml", "-o", "{d}/g.svg"], {"m.yaml": BALL, "g.svg/keep": ""}, (2,)),
    Case("graph-out-under-file", ["graph", "{d}/m.yaml", "-o", "{d}/f/g.svg"], {"m.yaml": BALL, "f": "x"}, (2,)),
    Case("graph-model-fifo", ["graph", "{d}/m.yaml", "-o", "{d}/g.svg"], {"m.yaml": FIFO}, (1,), "line",
         says="special file"),
    Case("graph-model-binary", ["graph", "{d}/m.yaml", "-o", "{d}/g.svg"], {"m.yaml": b"\xff\xfe\x00"}, (1,), "line"),
]

# -- 4. meshes ---------------------------------------------------------------------------------------------------

SHAPE = "shape: {box: {size: [0.02, l, 0.02]}}"
STL = "solid x\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\nvertex 0 1 0\nendloop\nendfacet\n" \
      "endsolid x\n"


def mesh(id, new, path="frames[0].shape.mesh.file", says="", files=None):
    return model(f"mesh-{id}", PENDULUM, SHAPE, f"shape: {{mesh: {new}}}", path, says, files)


MESH_CASES = [
    mesh("missing-file", "{file: nope.stl}"),
    mesh("outside-folder", "{file: ../secret.stl}"),
    mesh("absolute-outside", "{file: /etc/passwd}"),
    mesh("wrong-suffix", "{file: m.txt}", files={"m.txt": STL}),
    mesh("no-suffix", "{file: m}", files={"m": STL}),
    mesh("folder", "{file: d.stl}", files={"d.stl/keep": ""}),
    mesh("fifo", "{file: p.stl}", files={"p.stl": FIFO}),
    mesh("link-out", "{file: evil.stl}", files={"evil.stl": "->/etc/passwd"}),
    mesh("link-chain", "{file: b.obj}", files={"b.obj": "->a.dae", "a.dae": "->/etc/passwd"}),
    mesh("link-to-folder", "{file: l.stl}", files={"l.stl": "->sub", "sub/keep": ""}),
    mesh("scale-zero", "{file: m.stl, scale: 0}", "frames[0].shape.mesh.scale", files={"m.stl": STL}),
    mesh("scale-negative", "{file: m.stl, scale: -1}", "frames[0].shape.mesh.scale", files={"m.stl": STL}),
    mesh("scale-nan", "{file: m.stl, scale: .nan}", "frames[0].shape.mesh.scale", files={"m.stl": STL}),
    mesh("scale-two", "{file: m.stl, scale: [1, 2]}", "frames[0].shape.mesh.scale", files={"m.stl": STL}),
    mesh("scale-text", "{file: m.stl, scale: big}", "frames[0].shape.mesh.scale", files={"m.stl": STL}),
    mesh("file-empty-name", "{file: ''}"),
    mesh("file-number", "{file: 5}", "frames[0].shape"),
    mesh("file-nul", "{file: \"m\\0.stl\"}"),
    mesh("unknown-key", "{file: m.stl, colour: red}", "frames[0].shape.mesh", files={"m.stl": STL}),
    model("shape-colour-nan", PENDULUM, SHAPE, "shape: {box: {size: [0.02, l, 0.02]}, colour: [.nan, 0, 0]}",
          "frames[0].shape.colour"),
    model("shape-colour-unknown", PENDULUM, SHAPE, "shape: {box: {size: [0.02, l, 0.02]}, colour: blurple}",
          "frames[0].shape.colour"),
    model("shape-size-negative", PENDULUM, SHAPE, "shape: {box: {size: [-1, l, 0.02]}}", None),
    model("shape-size-uses-state", PENDULUM, SHAPE, "shape: {box: {size: [q, l, 0.02]}}", None),
    model("shape-radius-inf", PENDULUM, SHAPE, "shape: {sphere: {radius: .inf}}", "frames[0].shape.sphere.radius"),
    model("shape-two-kinds", PENDULUM, SHAPE, "shape: {sphere: {radius: 1}, box: {size: [1, 1, 1]}}", None),
    model("shape-axis-zero", PENDULUM, SHAPE, "shape: {cylinder: {radius: 0.1, length: 1, axis: [0, 0, 0]}}",
          "frames[0].shape.cylinder.axis"),
]

# -- 5. signals and inputs ---------------------------------------------------------------------------------------

SIGNAL_MODEL = """\
name: sig
parameters: {m: 1.0}
coordinates:
  x: {initial: 0}
speeds: {wx: {initial: 0}, wy: {initial: 0}, wz: {initial: 1}}
frames:
  - {name: slide, parent: world, prismatic: x, axis: x}
  - {name: body, parent: slide, ball: {speeds: [wx, wy, wz], quaternion: [1, 0, 0, 0]}}
bodies:
  - {name: mass, frame: body, mass: m, inertia: [1, 1, 1]}
"""

INPUT_CASES = [
    model("inputs-nan", PENDULUM, "inputs: {T: 0}", "inputs: {T: .nan}", "inputs.T"),
    model("inputs-inf", PENDULUM, "inputs: {T: 0}", "inputs: {T: -.inf}", "inputs.T"),
    model("inputs-payload", PENDULUM, "inputs: {T: 0}", "inputs: {T: '0 # x'}", "inputs.T", "'#'"),
    model("inputs-uses-unknown", PENDULUM, "inputs: {T: 0}", "inputs: {T: 'qq*2'}", "inputs.T"),
    model("inputs-list", PENDULUM, "inputs: {T: 0}", "inputs: {T: [1, 2]}", "inputs.T"),
    model("inputs-named-like-state", PENDULUM, "inputs: {T: 0}", "inputs: {q: 0}", None),
    model("inputs-tower", PENDULUM, "inputs: {T: 0}", "inputs: {T: '2**2**2**2**2**2'}", "inputs.T",
          "past the limit"),
    model("signal-quaternion-not-unit", SIGNAL_MODEL, "quaternion: [1, 0, 0, 0]", "quaternion: [1, 1, 0, 0]", None),
    model("signal-quaternion-nan", SIGNAL_MODEL, "quaternion: [1, 0, 0, 0]", "quaternion: [.nan, 0, 0, 0]", None),
    model("signal-quaternion-short", SIGNAL_MODEL, "quaternion: [1, 0, 0, 0]", "quaternion: [1, 0, 0]", None),
    model("signal-quaternion-huge", SIGNAL_MODEL, "quaternion: [1, 0, 0, 0]", "quaternion: [1e308, 1e308, 0, 0]", None,
          "norm 1.41421356237e+308"),
    model("signal-name-clash", SIGNAL_MODEL, "parameters: {m: 1.0}", "parameters: {m: 1.0, body_qw: 1}", None),
    Case("sim-input-table-fifo", ["sim", "{m}/cart_pole.yaml", "--build-dir", "{b}", "--t-end", "0.01", "--input",
                                  "F={d}/push.csv", "-o", "{d}/r.h5"], {"push.csv": FIFO}, (2,), "line",
         says="is a special file, not a CSV table", needs="cart_pole"),
    Case("sim-input-table-folder", ["sim", "{m}/cart_pole.yaml", "--build-dir", "{b}", "--t-end", "0.01", "--input",
                                    "F={d}/push.csv", "-o", "{d}/r.h5"], {"push.csv/keep": ""}, (2,), "line",
         says="is a folder, not a CSV table", needs="cart_pole"),
    Case("sim-controller-fifo", ["sim", "{m}/cart_pole.yaml", "--build-dir", "{b}", "--t-end", "0.01",
                                 "--controller", "{d}/c.py", "-o", "{d}/r.h5"], {"c.py": FIFO}, (2,), "line",
         says="not a Python file", needs="cart_pole"),
    Case("sim-input-table-dev-zero", ["sim", "{m}/cart_pole.yaml", "--build-dir", "{b}", "--t-end", "0.01",
                                      "--input", "F=/dev/zero.csv", "-o", "{d}/r.h5"], {}, (2,), "line",
         needs="cart_pole"),
    Case("sim-input-escape", ["sim", "{m}/cart_pole.yaml", "--build-dir", "{b}", "--t-end", "0.01", "--input",
                              "F=\x1b[2J", "-o", "{d}/r.h5"], {}, (2,), "line", needs="cart_pole"),
    Case("sim-input-signal-name", ["sim", "{m}/cart_pole.yaml", "--build-dir", "{b}", "--t-end", "0.01", "--input",
                                   "x=1", "-o", "{d}/r.h5"], {}, (2,), "line", needs="cart_pole"),
    Case("sim-theta-nan", ["sim", "{m}/cart_pole.yaml", "--build-dir", "{b}", "--t-end", "0.01", "--method",
                           "moreau", "--theta", "nan", "-o", "{d}/r.h5"], {}, (2,), needs="cart_pole"),
    Case("sim-theta-without-moreau", ["sim", "{m}/cart_pole.yaml", "--build-dir", "{b}", "--t-end", "0.01",
                                      "--theta", "0.7", "-o", "{d}/r.h5"], {}, (2,), "line", needs="cart_pole"),
]

CASES = (CONTACT_CASES + SIMULATE_CASES + EXPECT_CASES + TEST_CASES + SWEEP_CASES + CYCLE_CASES + VIEW_CASES
         + GRAPH_CASES + MESH_CASES + INPUT_CASES)


def _case(c) -> Case:
    return c.values[0] if hasattr(c, "values") else c      # (a pytest.param of a Case)


def test_the_corpus_is_large_and_its_ids_unique():
    ids = [_case(c).id for c in CASES]
    assert len(ids) == len(set(ids))
    assert len(CASES) >= 150


# -- running a case ----------------------------------------------------------------------------------------------

def _write(tmp_path: Path, name: str, content) -> None:
    path = tmp_path / name
    path.parent.mkdir(parents=True, exist_ok=True)
    if name.endswith("/keep"):
        return
    if content is FIFO:
        os.mkfifo(path)
    elif isinstance(content, str) and content.startswith("->"):
        path.symlink_to(content[2:])
    elif content == "EMPTY_H5":
        import h5py
        h5py.File(path, "w").close()
    elif content == "NO_FRAMES":
        _run_file(path, frames=False)
    else:
        path.write_bytes(content if isinstance(content, bytes) else content.encode("utf-8", "surrogatepass"))


def _run_file(path: Path, frames: bool = True) -> Path:
    """A small run file of a made-up model (one logged frame, `tip`, unless not `frames`)."""
    import numpy as np

    from andyc.runtime.run import Run
    n = 11
    Run(model="m", spec_sha256="0", method="rk4", dt=0.1, nq=1, nv=1, rtol=0.0, atol=0.0, t_end=1.0, parameters={},
        inputs={}, state_names=["y", "y_dot"], time=np.linspace(0, 1, n), state=np.ones((n, 2)), energy=np.zeros(n),
        frames={"tip": np.zeros((n, 3))} if frames else {}, frame_parents={"tip": "world"} if frames else {}
        ).save(path)
    return path


def _tree(folder: Path) -> dict:
    """Every path under folder (links not followed) -> its bytes (None for folders, pipes and links)."""
    out = {}
    for p in sorted(folder.rglob("*")):
        regular = p.is_file() and not p.is_symlink()
        out[str(p.relative_to(folder))] = p.read_bytes() if regular and p.stat().st_size < 10_000_000 else None
    return out


@pytest.mark.parametrize("case", CASES, ids=lambda c: c.id)
def test_a_feature_of_the_last_rounds_gets_one_located_line_per_problem(case, tmp_path, shipped_build, compiled,
                                                                        monkeypatch):
    if case.needs:
        compiled(case.needs)                    # the shared build, made once for all
    for name, content in case.files.items():
        _write(tmp_path, name, content)
    run = tmp_path / "run.h5"
    uses_run = any("{run}" in a for a in case.args)
    if uses_run:
        _run_file(run)
    monkeypatch.chdir(tmp_path)
    before = _tree(tmp_path)
    args = [a.replace("{d}", str(tmp_path)).replace("{b}", str(shipped_build)).replace("{m}", str(MODELS))
            .replace("{run}", str(run)) for a in case.args]
    result = invoke(*args)
    text = result.output
    assert result.exception is None or isinstance(result.exception, SystemExit), repr(result.exception)
    assert result.exit_code in case.codes, text
    for bad in ("Traceback", "internal error", "\x1b", "\x07"):
        assert bad not in text, text
    assert case.says in text, text
    lines = [line for line in text.splitlines() if line.strip()]
    if case.kind == "model":                    # FILE:LINE: PATH: what; fix, each in the model file
        problems = [line for line in result.stderr.splitlines() if "(warning)" not in line]
        if problems and re.fullmatch(r"\d+ problems? found", problems[-1]):   # (check's count; test prints none)
            problems.pop()
        assert problems, result.stderr
        for line in problems:
            found = LINE_FORMAT.match(line)
            assert found and found["file"] == str(tmp_path / "m.yaml") and int(found["line"]) >= 1, line
        if case.path is not None:
            assert case.path in [LINE_FORMAT.match(line)["path"] for line in problems], result.stderr
    elif case.kind == "option":                 # click's one line (Invalid value for '--x', Missing option, ...)
        errors = [line for line in lines if line.startswith("Error: ")]
        assert len(errors) == 1, text
        assert all(line.startswith(("Error: ", "Usage: ", "Try ")) for line in lines), text
    else:                                       # the command's own one line (and a summary before it)
        own = [line for line in lines if line.startswith(("Error: ", "andyc", str(tmp_path), "/dev/"))]
        assert own, text
        assert len([line for line in lines if line.startswith(("Error: ", "andyc: "))]) <= 1, text
    after = _tree(tmp_path)
    made = sorted(set(after) - set(before))
    assert made == sorted(str(Path(w.replace("{d}/", ""))) for w in case.writes if not w.startswith("{")), made
    for name, content in before.items():        # every input unchanged
        assert after.get(name) == content, f"{name} changed"
