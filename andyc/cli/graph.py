"""`andyc graph`: a model's frame tree and hybrid automaton, drawn (andyc.plot.graph)."""

from __future__ import annotations

from pathlib import Path

import click

import andyc
from andyc.cli.common import Refused, fail_spec
from andyc.errors import SpecError, plural
from andyc.outputs import check_output


@click.command()
@click.argument("model_file", type=click.Path(exists=True, dir_okay=False))
@click.option("-o", "--out", default=None, help="The drawing: FILE.svg, FILE.png or FILE.pdf; default "
              "MODEL_graph.svg beside the model.")
def graph(model_file, out):
    """Draw MODEL_FILE's frame tree (frames as nodes, links as edges labelled by their joint, bodies and
    elements where they sit) and, for a hybrid model, its automaton (flows with their active
    constraints, jumps with guard, direction, resets and impact). Needs networkx (andyc[graph])."""
    from andyc.plot.graph import FORMATS, networkx, plot_graph

    out = out or str(Path(model_file).with_name(Path(model_file).stem + "_graph.svg"))
    if Path(out).suffix.lower() not in FORMATS:
        raise click.BadParameter(f"{out}: write the graph as {', '.join(FORMATS)}", param_hint="'-o' / '--out'")
    try:
        networkx()
    except ImportError as exc:
        raise Refused(str(exc)) from None
    try:
        spec = andyc.load(model_file)
    except SpecError as exc:
        fail_spec(exc)
    check_output(out, [model_file, *spec.files], "graph")
    plot_graph(spec, out)
    frames = len([f for f in spec.frames if not f.internal])
    click.echo(f"wrote {out} ({plural(frames, 'frame')}, {plural(len(spec.flows), 'flow')}, "
               f"{plural(len(spec.jumps), 'jump')})")
