"""Plots of runs (matplotlib, no screen needed)."""

from __future__ import annotations

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from andyc.runtime.run import Run  # noqa: E402


def plot_run(run: Run, out) -> None:
    """Coordinates, speeds and energy (with its drift) against time."""
    nq = len(run.state_names) // 2
    fig, axes = plt.subplots(3, 1, figsize=(9, 8), sharex=True)
    for j in range(nq):
        axes[0].plot(run.time, run.state[:, j], label=run.state_names[j])
        axes[1].plot(run.time, run.state[:, nq + j], label=run.state_names[nq + j])
    axes[0].set_ylabel("coordinates")
    axes[1].set_ylabel("speeds")
    e = run.energy
    axes[2].plot(run.time, e, color="k", label="E(t)")
    axes[2].set_ylabel("energy, J")
    drift = axes[2].twinx()
    scale = max(abs(e[0]), np.abs(e).max(), 1e-300)
    drift.plot(run.time, (e - e[0]) / scale, color="tab:red", lw=0.8, label="(E - E0) / max|E|")
    drift.set_ylabel("relative change", color="tab:red")
    for ax in axes[:2]:
        ax.legend(loc="upper right", fontsize="small", ncol=min(nq, 4))
    axes[2].legend(loc="upper left", fontsize="small")
    axes[2].set_xlabel("time, s")
    fig.suptitle(f"{run.model} — {run.method}, dt = {run.dt:g} s — {run.status}")
    fig.tight_layout()
    fig.savefig(out, dpi=110)
    plt.close(fig)
