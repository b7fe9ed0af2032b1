"""The options of a run, grouped by concept into small frozen objects (as diffrax's SaveAt and its step-size
controllers), each passed to simulate() as one argument:

    andyc.simulate(model, 10.0, events=andyc.Events(stop_after={"strike": 10}), init=andyc.Init("project"),
                   projection=andyc.Projection(energy_correction=False))

Events      where guard crossings are located, and when jumps stop a run
Init        what a constrained run does with an initial state off its constraint manifold
Projection  what the fixed-step methods correct after each step
TimeStepping  the moreau method's theta

Light: importing this imports neither NumPy nor Numba nor SciPy.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Mapping

from andyc.errors import SimulationError

INIT_MODES = ("check", "project", "as-is")


@dataclass(frozen=True)
class Events:
    """Event location and the stops of hybrid runs (every method; a model without jumps ignores them).

    tol                guard crossings are located to this many seconds (relative beyond t = 1 s); jumps
                       closer together than this count as one instant
    max_instant_jumps  the run stops, keeping its samples, after more than this many jumps at one instant
                       (a loop such as a -> b -> a)
    zeno_tol           the run stops when the jump times accumulate (Zeno: the last intervals shrink
                       geometrically) at a point less than this many seconds ahead
    stop_after         {jump name: n}: the run ends, with the status "finished", right after the n-th
                       occurrence of that jump, the state just after it being the last sample (step maps);
                       None: no such end
    """
    tol: float = 1e-12
    max_instant_jumps: int = 100
    zeno_tol: float = 1e-6
    stop_after: Mapping[str, int] | None = None


@dataclass(frozen=True)
class Init:
    """A constrained run's initial state: its distance from the constraint manifold is measured first.

    Attributes
    ----------
    mode : str
        "check": refuse the run when a residual (position or velocity level) exceeds tol;
        "project": move the state onto the manifold (Braun & Goldfarb's corrections, repeated to
        round-off: the smallest change in the mass-matrix metric); "as-is": start from it anyway
    tol : float
        the largest initial residual "check" accepts
    """
    mode: str = "check"
    tol: float = 1e-6

    def __post_init__(self):
        if self.mode not in INIT_MODES:
            raise SimulationError(f"unknown init '{self.mode}'; use one of: {', '.join(INIT_MODES)}")


@dataclass(frozen=True)
class Projection:
    """What the fixed-step methods correct after each step (the adaptive methods correct nothing).

    Attributes
    ----------
    normalize : bool
        renormalize the quaternion signals (every fixed-step method; the adaptive methods'
        norm drift stays within their tolerances and never reaches the dynamics, whose
        rotation matrices are exact for any norm)
    energy_correction : bool or None
        the projection method's energy correction (Braun & Goldfarb eq. 5-6) to each flow's law
        (its energy_law, else E - E0 - W); None: on when the method is projection and the model
        declares conserves_energy or an energy_law; True needs the projection method
    energy_tol : float
        the energy correction applies only where 2T exceeds this (Braun & Goldfarb eq. 6)
    """
    normalize: bool = True
    energy_correction: bool | None = None
    energy_tol: float = 1e-6


@dataclass(frozen=True)
class TimeStepping:
    """The moreau method's scheme (andyc.runtime.timestepping; the other methods ignore it).

    theta  in [1/2, 1]: where in the step M and the forces are taken, q_{k+theta} = q_k + theta h v_k, and
           q_{k+1} = q_k + h ((1 - theta) v_k + theta v_{k+1}); 1/2 (trapezoidal) is second order in smooth
           motion and keeps a free oscillation's energy, 1 (backward Euler in the speeds) damps it
    """
    theta: float = 0.5
