"""Independent reference derivations (sympy.physics.mechanics) used to check andyc.

Nothing here imports andyc's symbolic or codegen stages: `chains` builds random
serial chains, writes them as andyc YAML, and derives the same systems with
Kane's method so tests and benchmarks can compare the two.
"""
