"""The eigenvalues of a sweep of linearizations (`andyc linearize --sweep ... -o DIR`): their real parts and
their imaginary parts against the swept value, with the changes of stability marked."""

from __future__ import annotations

import numpy as np
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure

from andyc.outputs import write_atomic


def plot_eigenvalues(name: str, values: np.ndarray, eigenvalues: np.ndarray, changes: list, out,
                     title: str = "") -> None:
    """Write to `out` (PNG) the real (top) and imaginary (bottom) parts of `eigenvalues` (len(values), n)
    against `values` of `name`; `changes`: the values where stability changes (vertical lines)."""
    fig = Figure(figsize=(7, 6))
    FigureCanvasAgg(fig)
    top, bottom = fig.subplots(2, 1, sharex=True)
    for ax, part, label in ((top, eigenvalues.real, "real part"), (bottom, eigenvalues.imag, "imaginary part")):
        ax.plot(values, part, "o", ms=2.5, color="#1d3557")
        ax.axhline(0.0, color="0.6", lw=0.8)
        for value in changes:
            ax.axvline(value, color="#e76f51", lw=1.0, ls="--")
        ax.set_ylabel(label)
    bottom.set_xlabel(name)
    top.set_title(title or f"eigenvalues along {name}" + (f"; stability changes at {', '.join(f'{v:.6g}' for v in changes)}"
                                                          if changes else ""), fontsize=9)
    with write_atomic(out) as tmp:
        fig.savefig(tmp, dpi=110)
