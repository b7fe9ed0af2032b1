"""Runtime: compiled model + workspace, integrators, run files."""
