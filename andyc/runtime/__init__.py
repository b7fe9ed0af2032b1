"""Runtime: a compiled model and the arrays its algorithms work in; simulate() and the runs it returns.

    compiled.py    the generated module imported: CompiledModel (immutable) and its work arrays
    simulate.py    simulate(): the entry point over every method
    options.py     Events, Init, Projection: the run's options grouped by concept
    methods.py     the methods by name, and the run sizes andyc refuses
    initial.py     the initial state, flow and discrete state, and their consistency with the constraints
    fixed_step.py  the compiled loop (rk4, projection, lagrange, baumgarte), in chunks
    adaptive.py    SciPy's adaptive solvers, one step at a time, with the compiled event location
    events.py      the jumps as they happen; jump loops, Zeno, stop_after
    status.py      the run's status and its messages (codes from andyc.numerics.status)
    inputs.py      constants, expressions, tables and controllers driving the inputs
    interrupts.py  SIGINT, SIGTERM, the wall-clock limit and the watchdog
    progress.py    the progress line of long work, on a terminal
    run.py         Run, and its HDF5 and CSV files
"""
