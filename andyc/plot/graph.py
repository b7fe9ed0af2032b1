"""The drawings of `andyc graph`: a model's frame tree (ANDY Fig. 5) and its hybrid automaton (ANDY
Fig. 8), from the plain data of andyc.plot.structure, laid out with networkx and drawn with matplotlib's
object API on an Agg canvas (no pyplot; networkx's own drawing functions import pyplot, so they are not
used). networkx is an optional dependency (`pip install andyc[graph]`); `graph_figure` says so when it
is missing.

- `graph_figure(spec)`: one figure, the frame tree on the left and, for a model with a hybrid section,
  the automaton on the right; `plot_graph(spec, out)` saves it (.svg, .png or .pdf).
- `tree_layout(tree)`: the frame tree's positions (a tidy layered layout: depth down, leaves side by
  side in depth-first order, a parent above the middle of its children).
"""

from __future__ import annotations

import textwrap
from pathlib import Path

import numpy as np
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure
from matplotlib.patches import FancyArrowPatch

from andyc.outputs import write_atomic
from andyc.plot.structure import automaton, frame_tree

FORMATS = (".svg", ".png", ".pdf")
KIND_COLOURS = {"fixed": "0.45", "moving": "tab:olive", "revolute": "tab:blue", "prismatic": "tab:orange",
                "dh": "tab:purple", "ball": "tab:red", "floating": "tab:green", "nonholonomic": "tab:brown"}


def networkx():
    """The networkx module; ImportError with the fix when it is not installed."""
    try:
        import networkx
    except ImportError:
        raise ImportError("andyc graph needs networkx, which is not installed; install it with "
                          "`pip install 'andyc[graph]'` (or `pip install networkx`)") from None
    return networkx


def plot_graph(spec, out) -> None:
    """Write `graph_figure(spec)` to `out` (.svg, .png or .pdf; ValueError for another suffix)."""
    suffix = Path(out).suffix.lower()
    if suffix not in FORMATS:
        raise ValueError(f"{out}: a graph is written as {', '.join(FORMATS)}, not '{suffix or 'no suffix'}'")
    fig = graph_figure(spec)
    with write_atomic(out) as tmp:
        fig.savefig(tmp, format=suffix[1:], dpi=110)


def is_hybrid_spec(spec) -> bool:
    """Whether the model declares a hybrid automaton (more than one flow, or a jump)."""
    return len(spec.flows) > 1 or bool(spec.jumps)


def graph_figure(spec) -> Figure:
    """The frame tree (left) and, for a hybrid model, the automaton (right), each an axes with gid
    'frame_tree' / 'automaton'. Node texts have gid 'frame:NAME' / 'flow:NAME', edge labels
    'link:CHILD' / 'jump:NAME'. On an Agg canvas of its own (no pyplot)."""
    tree = frame_tree(spec)
    hybrid = is_hybrid_spec(spec)
    pos = tree_layout(tree)
    xs, ys = zip(*pos.values())
    width = float(np.clip(1.9 * (max(xs) - min(xs) + 1), 5, 22))
    height = float(np.clip(1.35 * (max(ys) - min(ys) + 1), 4, 16))
    fig = Figure(figsize=(width + (9 if hybrid else 0), max(height, 8 if hybrid else 0)), layout="constrained")
    grid = fig.add_gridspec(1, 2 if hybrid else 1, width_ratios=[width, 9] if hybrid else [1])
    _draw_tree(fig.add_subplot(grid[0], gid="frame_tree"), tree, pos)
    if hybrid:
        _draw_automaton(fig.add_subplot(grid[1], gid="automaton"), automaton(spec))
    fig.suptitle(f"{spec.name}: frame tree" + (" and hybrid automaton" if hybrid else ""))
    FigureCanvasAgg(fig)
    return fig


def tree_layout(tree: dict) -> dict:
    """{frame: (x, y)}: y = -depth; the leaves at x = 0, 1, 2, ... in depth-first order (children in
    the model's order), each parent at the mean x of its children."""
    nx = networkx()
    g = nx.DiGraph()
    g.add_nodes_from(n["name"] for n in tree["nodes"])
    g.add_edges_from((e["parent"], e["child"]) for e in tree["edges"])
    pos, leaf = {}, [0]

    def place(name, depth):
        children = list(g.successors(name))
        for child in children:
            place(child, depth + 1)
        x = float(np.mean([pos[c][0] for c in children])) if children else float(leaf[0])
        leaf[0] += 0 if children else 1
        pos[name] = (x, -float(depth))

    for root in (n for n in g.nodes if g.in_degree(n) == 0):
        place(root, 0)
    return pos


def _node(ax, xy, title: str, lines: list, gid: str, colour: str, width: int = 28):
    """A node: its title and, in smaller type, its lines, in a rounded box; returns the text."""
    body = "\n".join(line if len(line) <= width else line[:width - 1] + "…" for line in lines)
    text = ax.text(*xy, title + ("\n" + body if body else ""), ha="center", va="center", fontsize=8,
                   family="DejaVu Sans", gid=gid, zorder=3,
                   bbox=dict(boxstyle="round,pad=0.4", fc=colour, ec="0.3", lw=0.8))
    return text


def _arrow(ax, a, b, box_a, box_b, colour, rad: float = 0.0, style: str = "-|>", ls: str = "-"):
    arrow = FancyArrowPatch(a, b, arrowstyle=style, mutation_scale=12, color=colour, lw=1.3, ls=ls,
                            connectionstyle=f"arc3,rad={rad}", patchA=box_a, patchB=box_b, zorder=4)
    ax.add_patch(arrow)
    return arrow


def _draw_tree(ax, tree: dict, pos: dict) -> None:
    boxes = {}
    for n in tree["nodes"]:
        colour = "0.85" if n["name"] == "world" else "#e8f0fa"
        boxes[n["name"]] = _node(ax, pos[n["name"]], n["name"], n["attached"], f"frame:{n['name']}", colour)
    for e in tree["edges"]:
        a, b = pos[e["parent"]], pos[e["child"]]
        colour = KIND_COLOURS.get(e["kind"], "k")
        _arrow(ax, a, b, boxes[e["parent"]].get_bbox_patch(), boxes[e["child"]].get_bbox_patch(), colour)
        ax.text((a[0] + b[0]) / 2, (a[1] + b[1]) / 2, textwrap.fill(e["label"], 26), ha="center", va="center",
                fontsize=7, color=colour, gid=f"link:{e['child']}", zorder=5,
                bbox=dict(boxstyle="square,pad=0.1", fc="white", ec="none", alpha=0.85))
    _frame_axes(ax, pos.values())
    ax.set_title("frames (links labelled by their joint; bodies and elements where they sit)", fontsize=9)


def _draw_automaton(ax, graph: dict) -> None:
    names = [n["name"] for n in graph["nodes"]]
    if len(names) == 1:
        pos = {names[0]: np.zeros(2)}
    else:   # the flows round a circle, clockwise from the top, in the model's order (ANDY Fig. 8's cycle)
        angles = np.pi / 2 - 2 * np.pi * np.arange(len(names)) / len(names)
        pos = {name: np.array([np.cos(a), np.sin(a)]) for name, a in zip(names, angles)}
    boxes = {}
    for n in graph["nodes"]:
        lines = (textwrap.wrap("constraints: " + ", ".join(n["constraints"]), 24) if n["constraints"]
                 else ["no constraints"])
        lines += textwrap.wrap("contacts: " + ", ".join(graph.get("contacts", [])), 24) if graph.get("contacts") else []
        colour = "#fff2cc" if n["initial"] else "#f4f4f4"
        boxes[n["name"]] = _node(ax, pos[n["name"]], n["name"] + (" (initial)" if n["initial"] else ""), lines,
                                 f"flow:{n['name']}", colour)
    pairs = {(e["source"], e["target"]) for e in graph["edges"]}
    seen = {}
    for k, e in enumerate(graph["edges"]):
        colour = f"C{k % 10}"
        a, b = pos[e["source"]], pos[e["target"]]
        repeat = seen.get((e["source"], e["target"]), 0)
        seen[(e["source"], e["target"])] = repeat + 1
        if e["source"] == e["target"]:     # a self-loop above the node
            box = boxes[e["source"]].get_bbox_patch()
            _arrow(ax, a + [-0.06, 0.0], a + [0.06, 0.0], box, box, colour, rad=-4.0 - repeat)
            where = a + [0.0, 0.3 + 0.12 * repeat]
        else:
            rad = (0.15 if (e["target"], e["source"]) in pairs else 0.08) + 0.12 * repeat
            _arrow(ax, a, b, boxes[e["source"]].get_bbox_patch(), boxes[e["target"]].get_bbox_patch(), colour, rad)
            d = b - a
            where = (a + b) / 2 + 0.5 * rad * np.array([d[1], -d[0]])   # on the arc3 curve (its middle)
        ax.text(*where, _jump_text(e), ha="center", va="center", fontsize=7, color=colour, gid=f"jump:{e['name']}",
                zorder=5, bbox=dict(boxstyle="round,pad=0.2", fc="white", ec=colour, lw=0.6, alpha=0.9))
    _frame_axes(ax, [tuple(p) for p in pos.values()], pad=0.55)
    ax.set_title("hybrid automaton (flows with their active constraints; jumps with guard, direction, impact)",
                 fontsize=9)


def _jump_text(e: dict) -> str:
    """A jump's label: name; guard and direction (↓ falling, ↑ rising, ↕ either); conditions; resets; impact."""
    arrow = {"falling": "↓", "rising": "↑", "either": "↕"}[e["direction"]]
    lines = [e["name"], f"guard {e['guard']} {arrow} {e['direction']}"]
    lines += [f"if {c}" for c in e["enabled"]]
    if e["reset"]:
        lines.append("reset " + ", ".join(f"{k} = {v}" for k, v in e["reset"].items()))
    lines.append(f"impact {e['impact']}")
    return "\n".join(textwrap.shorten(line, 40, placeholder="…") for line in lines)


def _frame_axes(ax, points, pad: float = 0.6) -> None:
    xs, ys = zip(*points)
    ax.set_xlim(min(xs) - pad, max(xs) + pad)
    ax.set_ylim(min(ys) - pad, max(ys) + pad)
    ax.set_axis_off()
