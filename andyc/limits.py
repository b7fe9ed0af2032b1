"""The sizes of a run andyc refuses, shared by every stage that checks them (the model's simulate: section, the
command line, the runtime); outside the stages' layers so that each may import it."""

MAX_STEPS = 1e11            # a day at 10^6 steps per second
MAX_LOG_BYTES = 16e9
