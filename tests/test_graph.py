"""`andyc graph`: the frame tree and the hybrid automaton (andyc.plot.structure, andyc.plot.graph) against
the model files themselves, read independently with pyyaml: every frame a node, every link an edge from
its parent labelled by the joint the file writes, every body where the file puts it; every flow a node
with its constraints, every jump an edge with its guard and direction as written. The passive walker's
automaton has 6 flows and 6 jumps, a cycle. The drawing has a labelled artist per node and edge, and the
command writes SVG/PNG, refuses other suffixes (exit 2) and reports a bad model (exit 1)."""

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
# (the models written in YAML whole: a model made from a URDF, models/go1.yaml, has its frames and contacts there)
YAML_MODELS = sorted(p for p in MODELS.glob("*.yaml") if "urdf" not in yaml.safe_load(p.read_text()))
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
    """The flows and jumps the file writes; its contacts listed beside them (they open and close in every flow,
    their jumps are not edges: test_contact_jumps_are_the_files_contacts)."""
    data = raw(path)
    graph = automaton(andyc.load(path))
    hybrid = data.get("hybrid")
    assert graph["contacts"] == [c["name"] for c in data.get("contacts") or []]
    contact_rows = {c["name"] for c in data.get("contacts") or []} | {
        c["name"] + "_stick" for c in data.get("contacts") or [] if "slip" in c}
    if not hybrid:      # one flow, every constraint but the contacts' active, no jump of the user's
        assert [(n["name"], n["constraints"]) for n in graph["nodes"]] == [
            ("default", [c["name"] for c in data.get("constraints") or [] if c["name"] not in contact_rows])
        ] or len(graph["nodes"]) == 1
        assert graph["edges"] == []
        return
    assert [n["name"] for n in graph["nodes"]] == [f["name"] for f in hybrid["flows"]]
    for node, flow in zip(graph["nodes"], hybrid["flows"]):
        assert set(node["constraints"]) == set(flow.get("constraints") or [])
    initial = hybrid.get("initial", hybrid["flows"][0]["name"])
    assert [n["name"] for n in graph["nodes"] if n["initial"]] == [initial]
    assert [(e["name"], e["source"], e["target"], e["guard"], e["direction"]) for e in graph["edges"]] == [
        (j["name"], j["from"], j["to"], str(j["guard"]), j.get("direction", "either")) for j in hybrid["jumps"]]


@pytest.mark.parametrize("path", [p for p in YAML_MODELS if raw(p).get("contacts")], ids=lambda p: p.stem)
def test_contact_jumps_are_the_files_contacts(path):
    """Each contact's own jumps, from and to every flow, each considered only in the modes it leaves (its mode a
    discrete state: 0 open, 1 closed or sticking, 2 (3) slipping forwards (backwards)), read from the file: an
    impact while open (its gap falling through zero; the impact solver picks the modes after), a liftoff while
    closed (its normal force, the multiplier, falling through zero); with planar friction, from stick a slip each
    way (mu lam_n +- lam_t falling through zero) and from either slip its stop (the slip speed times +1 forwards,
    -1 backwards, falling through zero); spatial friction (slip: a list of two): from stick a slip where
    mu^2 lam_n^2 - lam_1^2 - lam_2^2 falls through zero, from slipping its stop where s . d does (d the slip's
    direction, two discrete states)."""
    data = raw(path)
    spec = andyc.load(path)
    found = {(j.name, j.source, j.target, str(j.text["guard"]), j.direction, j.mode)
             for j in spec.jumps if j.kind}
    expected = set()
    for c in data["contacts"]:
        name, mode = c["name"], f"{c['name']}_mode"
        normal = c.get("multiplier", f"lambda_{name}")
        expected.add((f"{name}_impact", "*", "*", str(c["gap"]), -1, (mode, 0b1)))
        expected.add((f"{name}_liftoff", "*", "*", normal, -1, (mode, 0b1110)))
        if "friction" not in c:
            continue
        if isinstance(c["slip"], list):
            f1, f2 = c.get("friction_multiplier", [f"friction_{name}_{j}" for j in (1, 2)])
            d1, d2 = f"{name}_slip_dir_1", f"{name}_slip_dir_2"
            expected.add((f"{name}_slip", "*", "*", f"({c['friction']})**2*{normal}**2 - {f1}**2 - {f2}**2", -1,
                          (mode, 0b10)))
            expected.add((f"{name}_stop", "*", "*", f"({c['slip'][0]})*{d1} + ({c['slip'][1]})*{d2}", -1,
                          (mode, 0b100)))
            continue
        friction = c.get("friction_multiplier", f"friction_{name}")
        expected.add((f"{name}_slip_pos", "*", "*", f"{c['friction']}*{normal} + {friction}", -1, (mode, 0b10)))
        expected.add((f"{name}_slip_neg", "*", "*", f"{c['friction']}*{normal} - {friction}", -1, (mode, 0b10)))
        expected.add((f"{name}_stop", "*", "*", f"(5 - 2*{mode})*({c['slip']})", -1, (mode, 0b1100)))
    assert found == expected


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


def _label_overlaps(fig) -> list:
    """[(gid, gid)] of the figure's labelled texts (nodes, links, jumps) whose drawn boxes overlap by more
    than a pixel each way, as matplotlib renders them."""
    import itertools

    fig.canvas.draw()
    renderer = fig.canvas.get_renderer()
    out = []
    for ax in fig.axes:
        boxes = [(t.get_gid(), (t.get_bbox_patch() or t).get_window_extent(renderer)) for t in ax.texts if t.get_gid()]
        for (ga, a), (gb, b) in itertools.combinations(boxes, 2):
            if min(a.x1, b.x1) - max(a.x0, b.x0) > 1 and min(a.y1, b.y1) - max(a.y0, b.y0) > 1:
                out.append((ga, gb))
    return out


def test_no_two_labels_overlap_in_any_shipped_models_graph():
    overlapping = {p.stem: _label_overlaps(graph_figure(andyc.load(p))) for p in YAML_MODELS}
    assert {k: v for k, v in overlapping.items() if v} == {}


def test_the_overlap_check_sees_two_labels_drawn_on_each_other():
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    fig = Figure()
    FigureCanvasAgg(fig)
    ax = fig.add_subplot()
    for gid in ("a", "b"):
        ax.text(0.5, 0.5, "a label", gid=gid, bbox=dict(boxstyle="round"))
    ax.text(0.1, 0.1, "apart", gid="c", bbox=dict(boxstyle="round"))
    assert _label_overlaps(fig) == [("a", "b")]


def test_a_urdf_robots_locked_joints_are_drawn_as_locked_links():
    """g1.yaml locks its waist and arms (urdf: {lock: ...}): their links have no joint step left; the tree
    draws them as fixed links labelled locked (andyc graph failed on them), its legs' joints as revolute."""
    spec = andyc.load(MODELS / "g1.yaml")
    locked = set(raw(MODELS / "g1.yaml")["urdf"]["lock"])
    edges = {e["child"]: e for e in frame_tree(spec)["edges"]}
    assert "waist_yaw_joint" in locked and edges["waist_yaw_link"] == {**edges["waist_yaw_link"], "kind": "fixed",
                                                                      "label": "revolute, locked"}
    assert edges["left_knee_link"]["kind"] == "revolute"
    assert graph_figure(spec).axes
