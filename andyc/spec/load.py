"""YAML model (or URDF) -> Spec: read, check against the JSON Schema, build the sections in order.

A `.urdf` file, or a YAML model with a `urdf:` key, is first turned into the
same model dictionary by andyc.spec.urdf.

Every problem is collected with its line and document path; the loader raises
one SpecError carrying all of them, so `andyc check` can print them at once.
`build_spec` lists the stages; each section's checks live in their own module
(scope, frames, elements, constraints, hybrid, closed_form, simulate, expect) and each stage
hands the next what it needs, the name scope first of all.
"""

from __future__ import annotations

import dataclasses
import hashlib
from pathlib import Path

import sympy as sp

from andyc.errors import Diagnostic, SpecError
from andyc.spec import urdf
from andyc.spec.closed_form import build_closed_form
from andyc.spec.constraints import (FrameQuantities, build_constraints, check_conservative, check_energy_law,
                                    check_work_names)
from andyc.spec.contacts import build_contacts, stops_inside
from andyc.spec.elements import build_elements
from andyc.spec.energy_law import build_energy_laws
from andyc.spec.expect import build_expect
from andyc.spec.frames import build_frames
from andyc.spec.geometry import expand_shapes, ground_plane
from andyc.spec.hybrid import build_hybrid, check_nonlinear_impacts
from andyc.spec.meaning import meaning_sha256
from andyc.spec.model import Spec
from andyc.spec.schema_errors import schema, schema_problems
from andyc.spec.simulate import build_simulate
from andyc.spec.shapes import build_shapes
from andyc.spec.scope import Report, check_names, declare_constants, declare_states, driven_inputs, warn_unused
from andyc.spec.yamlpos import MAX_YAML_BYTES, SourceMap, load_yaml

__all__ = ["load", "schema", "build_spec"]

MAX_URDF_BYTES = urdf.MAX_URDF_BYTES


def load(path, unlock: bool = False) -> Spec:
    """Load and validate a model file. Raises SpecError listing every problem.

    `unlock`: ignore the `lock:` of a YAML model's `urdf:` key (the robot with every joint free, for
    `andyc check` to count what locking saved)."""
    path = Path(path)
    file = str(path)
    try:
        if path.exists() and not path.is_file():         # a folder, a pipe (reading it would wait), a device
            raise SpecError([Diagnostic(file, 1, "", "this is a " + ("folder" if path.is_dir() else "special file")
                                        + ", not a model file", "give the path of a YAML model or a URDF")])
        size = path.stat().st_size
        limit = MAX_URDF_BYTES if path.suffix.lower() == ".urdf" else MAX_YAML_BYTES
        if size > limit:
            raise SpecError([Diagnostic(file, 1, "", f"the file has {size / 1e6:.1f} MB, past the limit of "
                                        f"{limit / 1e6:g} MB for a {'URDF' if limit == MAX_URDF_BYTES else 'model'} "
                                        "file", "check that this is the model file")])
        raw = path.read_bytes()
    except OSError as exc:
        raise SpecError([Diagnostic(file, 1, "", f"cannot read the file ({exc.strerror})",
                                    "check the path")])
    if path.suffix.lower() == ".urdf":              # a URDF: its own reader, the same builder
        robot = urdf.read(path, raw=raw)
        return build_spec(robot.data, robot.source, hashlib.sha256(raw).hexdigest(), robot)
    try:
        text = raw.decode("utf-8")
    except UnicodeDecodeError:
        raise SpecError([Diagnostic(file, 1, "", "the file is not UTF-8 text", "save it as UTF-8")])
    data, smap, duplicates = load_yaml(text, file)
    if not isinstance(data, dict):
        raise SpecError([Diagnostic(file, 1, "", "the document is not a mapping",
                                    "a model starts with keys such as 'name:', 'coordinates:', 'frames:'")])
    problems = schema_problems(data, smap) + duplicates
    if problems:
        raise SpecError(sorted(problems, key=lambda d: d.line))
    if "urdf" in data:                              # start from a URDF, then the YAML's own keys
        if unlock and isinstance(data["urdf"], dict):
            data = {**data, "urdf": {k: v for k, v in data["urdf"].items() if k != "lock"}}
        data, smap, robot = urdf.merge(data, smap, path)
        problems = schema_problems(data, smap)
        if problems:
            raise SpecError(sorted(problems, key=lambda d: (d.file, d.line)))
        return build_spec(data, smap, hashlib.sha256(raw + robot.raw).hexdigest(), robot)
    return build_spec(data, smap, hashlib.sha256(raw).hexdigest())


def build_spec(data: dict, smap: SourceMap, sha: str, robot: urdf.UrdfModel | None = None) -> Spec:
    """A model document that fits the schema -> Spec; raises SpecError listing every problem.

    `sha`: of the bytes read; `robot`: the URDF the document was made from (the document is then the
    URDF's, merged with a YAML model's own keys, if any)."""
    # Colliding shapes become contacts and frames, read below as if written by hand (andyc.spec.geometry).
    data, smap, found, noted = expand_shapes(data, smap, bool(robot and robot.collides))
    report = Report(smap)
    report.problems += found
    report.warnings += noted
    # Names are unique and not reserved; the constants come first, then the states written with them.
    declared = check_names(data, report)
    scope = declare_states(data, declare_constants(data, report, declared))
    input_expressions, driven = driven_inputs(data, scope)
    # Frames, parents before children; their links' signals are states too, usable from here on.
    frames, signals = build_frames(data["frames"], scope)
    scope = scope.with_frames({"world"} | {f["name"] for f in data["frames"]}, signals)
    # (A URDF's bodies were checked by its reader, and are kept as written.)
    elements = build_elements(data, scope, len(robot.data.get("bodies", [])) if robot else 0)
    # Frame quantities (F.x, F.vy, ...) are named once for the constraints and the jumps together.
    quantities = FrameQuantities(scope, data.get("bodies") or [])
    # (A URDF's joint-limit stops that its joints start beyond are left out: None, keeping the entries' places.)
    written_contacts = stops_inside(data.get("contacts") or [], robot, scope)
    constraints = build_constraints(data.get("constraints") or [], scope, quantities, written_contacts)
    # The user's flows and jumps; then the contacts': each contact's mode is a discrete state that its jumps
    # (impact, liftoff, slip, stop; from and to every flow) change (andyc.spec.contacts).
    contact_rows = frozenset(c["name"] for c in written_contacts if c) | frozenset(
        f"{c['name']}_stick" for c in written_contacts if c and "slip" in c)
    flows, jumps, initial_flow = build_hybrid(data.get("hybrid"), constraints, scope, quantities, contact_rows)
    contacts, contact_jumps = build_contacts(written_contacts, constraints, scope)
    jumps = jumps + [dataclasses.replace(j, priority=len(jumps) + k) for k, j in enumerate(contact_jumps)]
    check_nonlinear_impacts(constraints, jumps, contacts, scope)
    closed_form = build_closed_form(data.get("closed_form"), jumps, scope, input_expressions)
    simulate = build_simulate(data.get("simulate"), scope, jumps)
    expect = build_expect(data.get("expect"), scope, constraints, jumps, closed_form, simulate)
    conserves = bool(data.get("conserves_energy", False))
    if conserves:
        check_conservative(elements, constraints, frames, data.get("constraints") or [], scope)
    check_energy_law(data, frames, constraints, flows, initial_flow, scope)
    energy_laws = build_energy_laws(data, flows, constraints, scope, quantities)
    check_work_names(data, jumps, scope)
    shapes = build_shapes(data, scope, smap.file)
    ground = ground_plane(data.get("ground"), lambda *problem: None)    # (its problems reported with the shapes')
    gravity = (scope.vector(data["gravity"], ("gravity",), scope.parameter_names, "only parameters are allowed here")
               if "gravity" in data else sp.zeros(3, 1))
    if report.problems:     # (the contacts made from one option or shape may each report it: once)
        raise SpecError(sorted(dict.fromkeys(report.problems), key=lambda p: p.line))
    warn_unused(scope)
    if robot is None:
        origin = dict(meaning_sha256=meaning_sha256(data), files=(smap.file,), warnings=report.warnings)
    else:
        # The URDF's bytes count whole: what the reader takes from them is more than the document shows.
        # Its fixed and locked joints' bodies are merged before deriving (reduce).
        urdf_sha = hashlib.sha256(robot.raw).hexdigest()
        origin = dict(meaning_sha256=meaning_sha256({**data, "reduce": True, "urdf_sha256": urdf_sha}),
                      files=tuple(dict.fromkeys((smap.file, robot.file))), warnings=robot.warnings + report.warnings,
                      visuals=robot.visuals, locked=robot.locked, reduce=True)
    return Spec(name=data["name"], description=data.get("description", ""), file=smap.file, sha256=sha,
                source=smap, parameters=scope.parameters, inputs=scope.inputs, coordinates=scope.coordinates,
                speeds=scope.speeds, signals=scope.signals, gravity=gravity,
                frames=frames + elements.offset_frames, bodies=elements.bodies, loads=elements.loads,
                actuators=elements.actuators, dampers=elements.dampers, springs=elements.springs,
                potentials=elements.potentials,
                constraints=constraints, conserves_energy=conserves, discrete=scope.discrete, flows=flows,
                jumps=jumps, initial_flow=initial_flow, contacts=contacts, input_expressions=input_expressions, shapes=shapes,
                ground=ground,
                driven_inputs=driven, closed_form=closed_form, simulate=simulate, expect=expect,
                energy_laws=energy_laws, **origin)
