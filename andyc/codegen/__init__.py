"""Code generation: SymbolicModel -> standalone Python/Numba module."""
