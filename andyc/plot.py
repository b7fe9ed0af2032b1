"""Plots of runs (matplotlib, no screen needed)."""

from __future__ import annotations

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from andyc.runtime.run import Run  # noqa: E402


def plot_run(run: Run, out) -> None:
    """Coordinates, speeds, energy and its relative change against time."""
    nq = len(run.state_names) // 2
    fig, axes = plt.subplots(4, 1, figsize=(9, 9), sharex=True, height_ratios=[3, 3, 2, 2])
    for j in range(nq):
        axes[0].plot(run.time, run.state[:, j], label=run.state_names[j])
        axes[1].plot(run.time, run.state[:, nq + j], label=run.state_names[nq + j])
    axes[0].set_ylabel("coordinates")
    axes[1].set_ylabel("speeds")
    for ax in axes[:2]:
        ax.legend(loc="upper right", fontsize="small", ncol=min(nq, 4))
    e = run.energy
    axes[2].plot(run.time, e, color="k")
    axes[2].set_ylabel("energy E, J")
    axes[2].ticklabel_format(axis="y", useOffset=False)
    scale = max(abs(e[0]), np.abs(e).max(), 1e-300)
    axes[3].plot(run.time, (e - e[0]) / scale, color="tab:red", lw=0.8)
    axes[3].set_ylabel("(E - E(0)) / max|E|")
    axes[3].set_xlabel("time, s")
    for ax in axes:
        ax.grid(alpha=0.3)
    fig.suptitle(f"{run.model}: {run.method}, dt = {run.dt:g} s, {run.status}")
    fig.tight_layout()
    fig.savefig(out, dpi=110)
    plt.close(fig)
