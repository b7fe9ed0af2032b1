"""`andyc graph`: the frame tree and the hybrid automaton (andyc.plot.structure, andyc.plot.graph) against
the model files themselves, read independently with pyyaml: every frame a node, every link an edge from
its parent labelled by the joint the file writes, every body where the file puts it; every flow a node
with its constraints, every jump an edge with its guard and direction as written. The passive walker's
automaton has 6 flows and 6 jumps, a cycle. The drawing has a labelled artist per node and edge, and the
command writes SVG/PNG, refuses other suffixes (exit 2) and reports a bad model (exit 1)."""

import itertools
import re
from pathlib import Path

import pytest
import yaml
from click.testing import CliRunner

import andyc
from andyc import cli

pytest.importorskip("networkx")
from andyc.plot.graph import graph_figure  # noqa: E402
from andyc.plot.structure import automaton, frame_tree  # noqa: E402

MODELS = Path(__file__).resolve().parents[1] / "models"
YAML_MODELS = sorted(p for p in MODELS.glob("*.yaml"))
JOINTS = ("dh", "revolute", "prismatic", "ball", "floating", "nonholonomic")


def raw(path) -> dict:
    return yaml.safe_load(Path(path).read_text())


@pytest.mark.parametrize("path", YAML_MODELS, ids=lambda p: p.stem)
def test_frame_tree_is_the_files_frames_links_and_bodies(path):
    data = raw(path)
    tree = frame_tree(andyc.load(path))
    frames = data.get("frames") or []
    assert [n["name"] for n in tree["nodes"]][0] == "world"
    assert {n["name"] for n in tree["nodes"]} == {"world"} | {f["name"] for f in frames}
    assert {(e["parent"], e["child"]) for e in tree["edges"]} == {(f["parent"], f["name"]) for f in frames}
    kinds = {e["child"]: e["kind"] for e in tree["edges"]}
    for f in frames:
        written = [k for k in JOINTS if k in f]
        if written:
            assert kinds[f["name"]] == written[0]
        else:               # no joint: fixed, or moving when its translation or rotation holds a coordinate or t
            coordinates = set(data.get("coordinates") or {}) | {"t"}
            text = str(f.get("translation", "")) + str(f.get("rotation", ""))
            moves = bool(coordinates & set(re.findall(r"[A-Za-z_][A-Za-z0-9_]*", text)))
            assert kinds[f["name"]] == ("moving" if moves else "fixed"), f["name"]
    attached = {n["name"]: n["attached"] for n in tree["nodes"]}
    for b in data.get("bodies") or []:
        assert f"body {b['name']}" in attached[b["frame"]]
    assert sum(len(a) for a in attached.values()) >= len(data.get("bodies") or [])


@pytest.mark.parametrize("path", YAML_MODELS, ids=lambda p: p.stem)
def test_automaton_is_the_files_flows_and_jumps(path):
    data = raw(path)
    graph = automaton(andyc.load(path))
    hybrid = data.get("hybrid")
    if data.get("contacts"):
        assert _contact_modes(graph) == _contact_modes_of_file(data)
        return
    if not hybrid:      # one flow, every constraint active, no jump
        assert [(n["name"], n["constraints"]) for n in graph["nodes"]] == [
            ("default", [c["name"] for c in data.get("constraints") or []])] or len(graph["nodes"]) == 1
        assert graph["edges"] == []
        return
    assert [n["name"] for n in graph["nodes"]] == [f["name"] for f in hybrid["flows"]]
    for node, flow in zip(graph["nodes"], hybrid["flows"]):
        assert set(node["constraints"]) == set(flow.get("constraints") or [])
    initial = hybrid.get("initial", hybrid["flows"][0]["name"])
    assert [n["name"] for n in graph["nodes"] if n["initial"]] == [initial]
    assert [(e["name"], e["source"], e["target"], e["guard"], e["direction"]) for e in graph["edges"]] == [
        (j["name"], j["from"], j["to"], str(j["guard"]), j.get("direction", "either")) for j in hybrid["jumps"]]


def _contact_modes(graph) -> tuple:
    return ({(n["name"], frozenset(n["constraints"]), n["initial"]) for n in graph["nodes"]},
            {(e["source"], e["target"], e["guard"], e["direction"]) for e in graph["edges"]})


def _contact_modes_of_file(data) -> tuple:
    """The automaton a model's contacts: stand for, read from the file: one flow per combination of the contacts'
    states (open or closed; with friction open, stick, slip_pos or slip_neg), named by the closed ones ('open' for
    none; the model's own constraints active in each, and a sticking contact's stick row), and from each flow an
    impact of every open contact (its gap falling through zero; the impact solver picks the mode after), a liftoff
    of every closed one (its normal force, the multiplier, falling through zero) to the flow without it, and with
    friction: from stick a slip each way (mu lam_n +- lam_t falling through zero), from a slip its stop (the slip
    speed through zero, falling forwards, rising backwards) to stick. Spatial friction (slip: a list of two):
    open, stick, slip; from stick a slip where mu^2 lam_n^2 - lam_1^2 - lam_2^2 falls through zero, from slip its
    stop where s . d does (d the slip's direction, two discrete states)."""
    contacts = data["contacts"]
    own = {c["name"] for c in data.get("constraints") or []}
    suffix = ["", "_stick", "_slip_pos", "_slip_neg"]
    spatial = [isinstance(c.get("slip"), list) for c in contacts]
    choices = [range(3) if s else range(4) if "friction" in c else range(2) for c, s in zip(contacts, spatial)]
    nodes, edges = set(), set()

    def name_of(states):
        return "+".join(c["name"] + (("", "_stick", "_slip")[s] if flat else suffix[s] if "friction" in c else "")
                        for c, s, flat in zip(contacts, states, spatial) if s) or "open"

    for states in itertools.product(*choices):
        name = name_of(states)
        rows = {c["name"] for c, s in zip(contacts, states) if s}
        rows |= {c["name"] + "_stick" for c, s in zip(contacts, states) if s == 1 and "friction" in c}
        nodes.add((name, frozenset(own | rows), not any(states)))
        for k, c in enumerate(contacts):
            other = lambda state: name_of(states[:k] + (state,) + states[k + 1:])     # noqa: E731
            normal = c.get("multiplier", f"lambda_{c['name']}")
            if states[k] == 0:
                edges.add((name, name, str(c["gap"]), "falling"))
                continue
            edges.add((name, other(0), normal, "falling"))
            if "friction" not in c:
                continue
            if spatial[k]:
                f1, f2 = c.get("friction_multiplier", [f"friction_{c['name']}_{j}" for j in (1, 2)])
                d1, d2 = f"{c['name']}_slip_dir_1", f"{c['name']}_slip_dir_2"
                edges.add((name, other(2), f"({c['friction']})**2*{normal}**2 - {f1}**2 - {f2}**2", "falling")
                          if states[k] == 1 else (name, other(1), f"({c['slip'][0]})*{d1} + ({c['slip'][1]})*{d2}",
                                                  "falling"))
                continue
            friction = c.get("friction_multiplier", f"friction_{c['name']}")
            if states[k] == 1:
                edges.add((name, other(2), f"{c['friction']}*{normal} + {friction}", "falling"))
                edges.add((name, other(3), f"{c['friction']}*{normal} - {friction}", "falling"))
            else:
                edges.add((name, other(1), str(c["slip"]), "falling" if states[k] == 2 else "rising"))
    return nodes, edges


def test_passive_walker_automaton_is_a_cycle_of_six_flows_and_six_jumps():
    data = raw(MODELS / "passive_walker.yaml")
    graph = automaton(andyc.load(MODELS / "passive_walker.yaml"))
    assert len(graph["nodes"]) == 6 and len(graph["edges"]) == 6
    guards = {j["name"]: str(j["guard"]) for j in data["hybrid"]["jumps"]}
    assert {e["name"]: e["guard"] for e in graph["edges"]} == guards
    assert guards["strike_outer_foot"] == "ofoot.y" and guards["lock_outer_knee"] == "qo2 - qo1"
    # each flow left by one jump and entered by one: the gait's cycle
    assert sorted(e["source"] for e in graph["edges"]) == sorted(n["name"] for n in graph["nodes"])
    assert sorted(e["target"] for e in graph["edges"]) == sorted(n["name"] for n in graph["nodes"])
    impacts = {e["name"]: e["impact"] for e in graph["edges"]}
    assert impacts == {j["name"]: j.get("impact", "none") for j in data["hybrid"]["jumps"]}


def test_link_labels_name_the_coordinates_as_written():
    tree = frame_tree(andyc.load(MODELS / "passive_walker.yaml"))
    label = {e["child"]: e["label"] for e in tree["edges"]}
    assert label["ithigh"] == "revolute qi1"
    assert label["ishank"] in ("revolute -qi1 + qi2", "revolute qi2 - qi1")
    assert label["hip"] == "translation [qx, qy, 0]"
    swing = {e["child"]: e for e in frame_tree(andyc.load(MODELS / "swing_bar.yaml"))["edges"]}
    assert swing["ball"]["kind"] == "ball" and "quaternion ball_qw" in swing["ball"]["label"]


def test_figure_draws_every_node_and_edge():
    spec = andyc.load(MODELS / "passive_walker.yaml")
    fig = graph_figure(spec)
    gids = {t.get_gid(): t.get_text() for ax in fig.axes for t in ax.texts}
    for f in spec.frames:
        assert f"frame:{f.name}" in gids or f.internal
        assert f"link:{f.name}" in gids or f.internal
    for flow in spec.flows:
        assert f"flow:{flow.name}" in gids
    for j in spec.jumps:
        assert j.text["guard"] in gids[f"jump:{j.name}"]
    assert {ax.get_gid() for ax in fig.axes} == {"frame_tree", "automaton"}
    plain = graph_figure(andyc.load(MODELS / "double_pendulum.yaml"))
    assert [ax.get_gid() for ax in plain.axes] == ["frame_tree"]


def test_graph_command_writes_svg_and_png(tmp_path):
    out = tmp_path / "walker.svg"
    result = CliRunner().invoke(cli.main, ["graph", str(MODELS / "passive_walker.yaml"), "-o", str(out)])
    assert result.exit_code == 0, result.output
    svg = out.read_text()
    for name in ("jump:strike_outer_foot", "flow:IFixOOpen", "frame:ofoot", "link:ithigh"):
        assert f'id="{name}"' in svg
    png = tmp_path / "swing.png"
    result = CliRunner().invoke(cli.main, ["graph", str(MODELS / "swing_bar.yaml"), "-o", str(png)])
    assert result.exit_code == 0 and png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_graph_command_refuses_bad_suffix_and_reports_bad_model(tmp_path):
    result = CliRunner().invoke(cli.main, ["graph", str(MODELS / "swing_bar.yaml"), "-o", str(tmp_path / "g.txt")])
    assert result.exit_code == 2 and "svg" in result.output
    bad = tmp_path / "bad.yaml"
    bad.write_text("name: bad\nframes:\n  - {name: a, parent: nowhere}\n")
    result = CliRunner().invoke(cli.main, ["graph", str(bad)])
    assert result.exit_code == 1 and "bad.yaml:3" in result.output and "nowhere" in result.output
    assert not (tmp_path / "bad_graph.svg").exists()


def test_a_urdf_robots_tree_is_its_links_and_joints():
    robots = pytest.importorskip("andyc.independent.robots")
    try:
        path = robots.robots_dir() / "panda_description/urdf/panda.urdf"
    except Exception as exc:        # example-robot-data not installed
        pytest.skip(f"no example-robot-data: {exc}")
    if not path.exists():
        pytest.skip(f"{path} is missing")
    from xml.etree import ElementTree

    joints = ElementTree.parse(path).getroot().findall("joint")
    tree = frame_tree(andyc.load(path))
    assert {(e["parent"], e["child"]) for e in tree["edges"]} >= {
        (j.find("parent").get("link"), j.find("child").get("link")) for j in joints}
    kinds = {e["child"]: e["kind"] for e in tree["edges"]}
    for j in joints:
        want = {"revolute": "revolute", "continuous": "revolute", "prismatic": "prismatic"}.get(j.get("type"), "fixed")
        assert kinds[j.find("child").get("link")] == want, j.get("name")
