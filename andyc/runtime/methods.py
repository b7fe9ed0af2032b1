"""The integration methods by name (light: no SciPy, no Numba)."""

FIXED_STEP = ("rk4", "projection", "lagrange", "baumgarte")
ADAPTIVE = ("DOP853", "Radau", "LSODA", "RK45", "BDF")          # SciPy's, by their names there
TIME_STEPPING = ("moreau",)                                     # andyc.runtime.timestepping
METHODS = FIXED_STEP + ADAPTIVE + TIME_STEPPING
