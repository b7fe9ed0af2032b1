"""Command line: a thin layer over the Python API (andyc.pipeline, andyc.simulate, andyc.analysis).

Here the command group, with what every command shares: text that cannot be encoded is escaped, and a
refused output, Ctrl-C and bugs end with a message and an exit code, not a traceback. One module per
command or family of commands, each a click command over the API:

    build.py      check (validate, print each model's summary) and build
    sim.py        sim (simulate, write the run files, print the run's summary)
    test.py       test (run the models' expectations, andyc.analysis.expectations; JUnit XML)
    formats.py    --format text|json|github: the report of check, build, sim and test
    plot.py       plot (plots, stick figures, animations of a run)
    graph.py      graph (a model's frame tree and hybrid automaton, drawn)
    view.py       view (a run as an HTML page that plays it in 3-D)
    eom.py        eom (the equations written out for reading)
    linearize.py  linearize (A, B and eigenvalues about a point)
    cycle.py      cycle (a periodic orbit through a jump: Newton on its Poincaré map, Floquet multipliers)
    analysis.py   bench (work-precision) and stability (stability maps)
    sweep.py      sweep (grids, Monte Carlo and CSV points on Dask, into a Zarr store), and plot STORE's maps
    common.py     what the commands share: a refused request, a model's problems, a model derived or compiled
    values.py     the options' values, checked; --set's split into parameters and inputs

Exit codes: 0 success, 1 an invalid model or a run that stopped, 2 usage, 130 / 143 / 129 a run interrupted
by SIGINT / SIGTERM / SIGHUP (its samples written), 70 a bug in andyc.
"""

from __future__ import annotations

import gc
import os
import sys

import click

import andyc
from andyc.cli import analysis, build, cycle, eom, graph, linearize, plot, sim, sweep, test, view
from andyc.cli.common import Refused
from andyc.cli.formats import json_command, usage_report
from andyc.outputs import OutputError


class _Andyc(click.Group):
    """The command group: text that cannot be encoded is escaped, not fatal (a message may quote a file name
    with undecodable bytes); an output that must not be written, Ctrl-C and bugs get a message, not a
    traceback (ANDYC_DEBUG=1 shows the traceback of a bug)."""

    def main(self, args=None, *rest, **kwargs):
        for stream in (sys.stdout, sys.stderr):
            try:
                stream.reconfigure(errors="backslashreplace")
            except (AttributeError, ValueError):
                pass
        args = list(sys.argv[1:] if args is None else args)
        self.json_command = json_command(args)
        return super().main(args, *rest, **kwargs)

    def invoke(self, ctx):
        try:
            return self._invoke(ctx)
        except click.ClickException as exc:
            if getattr(self, "json_command", None):     # a usage error under --format json: a JSON document too
                usage_report(self.json_command, exc.format_message(), exc.exit_code)
            raise

    def _invoke(self, ctx):
        try:
            return super().invoke(ctx)
        except OutputError as exc:
            raise Refused(str(exc)) from None
        except KeyboardInterrupt:
            click.echo("andyc: interrupted", err=True)
            ctx.exit(130)
        except RecursionError:
            raise Refused("the input is nested too deeply for andyc to process; simplify it") from None
        except (click.ClickException, click.exceptions.Exit, click.exceptions.Abort, SystemExit):
            raise
        except Exception as exc:
            if os.environ.get("ANDYC_DEBUG"):
                raise
            click.echo(f"andyc: internal error ({type(exc).__name__}: {exc}); this is a bug in andyc: please "
                       f"report it with the command and its input (ANDYC_DEBUG=1 shows the traceback)", err=True)
            ctx.exit(70)


@click.group(cls=_Andyc, context_settings={"help_option_names": ["-h", "--help"]})
@click.version_option(andyc.__version__, prog_name="andyc")
def main():
    """andyc: compile multibody models (YAML or URDF) into fast simulation code.

    \b
    andyc check model.yaml      validate, print a summary (also robot.urdf)
    andyc build model.yaml      write build/<name>/<name>.py
    andyc sim model.yaml        build if needed, simulate, write run files
    andyc test models/          run the models' expectations (expect:); JUnit with --junit
    andyc plot run.h5           plot states and energy
    andyc graph model.yaml      draw the frame tree and the hybrid automaton
    andyc view run.h5           a run as an HTML page that plays it in 3-D
    andyc linearize model.yaml  A, B and eigenvalues about a state
    andyc cycle model.yaml      a periodic orbit through a jump (--section), its Floquet multipliers
    andyc bench model.yaml      work-precision: error against cost per method
    andyc stability model.yaml  stability map: step against method, failures named
    andyc eom model.yaml        M, G, constraint Jacobian, per element (LaTeX)
    andyc sweep model.yaml      run a grid or Monte Carlo sweep on Dask into a Zarr store
    """


for _command in (build.check, build.build, sim.sim, test.test, sweep.sweep, plot.plot, graph.graph, view.view,
                 linearize.linearize, cycle.cycle, analysis.bench, analysis.stability, eom.eom):
    main.add_command(_command)



def run():
    """The `andyc` console script: main, then an exit that skips Python's last garbage collection.

    A warm run loads a few hundred thousand objects with Numba's cache (types, signatures, LLVM
    modules), and Python's teardown traces them all once more before the process ends: a tenth of a
    warm `andyc sim`. gc.freeze moves them out of that collection. The cost is that an object kept
    alive only by a reference cycle is not finalized at exit, which is why andyc closes each file it
    writes itself (andyc.outputs); atexit handlers still run. Not in main: a process that goes on
    after main (tests, an application embedding the CLI) keeps its collector as it was.
    """
    try:
        main()
    finally:
        gc.freeze()


__all__ = ["main", "run", "Refused"]
