"""Leaves that do nothing, for the parts a model has none of (no constraints, no signals, no jumps, no
flow inputs, no closed form): Model takes a function of each kind, and these compile once for all."""

import math

from .model import leaf


@leaf("dynamics_constraints")
def dynamics_constraints(t, x, u, p, d, M, G, S):
    return None


@leaf("constraints_into")
def constraints_into(t, x, u, p, d, S):
    return None


@leaf("signal_rates")
def signal_rates(t, x, u, p, d, xdot):
    return None


@leaf("constraint_gains")
def constraint_gains(p, S):
    return None


@leaf("restitution")
def restitution(p, S):
    return None


@leaf("guard")
def guard(k, t, x, u, p, d, lam):
    return 0.0


@leaf("guard_rate")
def guard_rate(k, t, x, u, p, d, xdot):
    return 0.0


@leaf("enabled")
def enabled(k, t, x, u, p, d, lam):
    return 1.0


@leaf("reset")
def reset(k, t, x, u, p, d):
    return None


@leaf("flow_inputs")
def flow_inputs(p, U):
    return None


@leaf("closed_form")
def closed_form(t, u, p, x):
    return None


@leaf("energy_law")
def energy_law(k, t, x, u, p, d, grad):
    return math.nan


@leaf("drive_power")
def drive_power(t, x, u, p, d, xdot):
    return None


@leaf("forward_dynamics")
def forward_dynamics(t, x, u, p, d, M, G):
    return None
