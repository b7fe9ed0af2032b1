"""The integration methods by name, and the sizes of a run andyc refuses (light: no SciPy, no Numba)."""

FIXED_STEP = ("rk4", "projection", "lagrange", "baumgarte")
ADAPTIVE = ("DOP853", "Radau", "LSODA", "RK45", "BDF")          # SciPy's, by their names there
TIME_STEPPING = ("moreau",)                                     # andyc.runtime.timestepping
METHODS = FIXED_STEP + ADAPTIVE + TIME_STEPPING
MAX_STEPS = 1e11            # a day at 10^6 steps per second
MAX_LOG_BYTES = 16e9
