"""Derivations independent of andyc's stages, to check them against: tests and benchmarks compare andyc with
these, never these with themselves.

    chains        random serial chains, written as andyc YAML
    kane          the same chains derived with SymPy's KanesMethod (sympy.physics.mechanics)
    closed_forms  exact motions of shipped models (the four-bar's branch, the ball's first integral)
    robots        where the example robots (URDF) of the Pinocchio comparisons are

Nothing here imports andyc's symbolic or codegen stages.
"""
