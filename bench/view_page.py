"""The size of `andyc view`'s page for a URDF robot with meshes, and the time to write it (issue 43: each
distinct mesh is stored once). Example-robot-data's panda with its fingers locked (as tests/conftest.py's
panda_arm), 2 s under gravity with every frame logged; prints the run file's and the page's size, the meshes
stored in the page against the mesh shapes drawn, and the seconds to write the page (CPU-bound, so a
shared machine's load shows in it: a figure, not a limit).

    python bench/view_page.py [--t-end 2]
"""

from __future__ import annotations

import argparse
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

import andyc  # noqa: E402
from andyc.plot.view import view_data, write_view  # noqa: E402
from tests.support import ROBOTS_DIR  # noqa: E402


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--t-end", type=float, default=2.0)
    args = parser.parse_args()
    with tempfile.TemporaryDirectory() as folder:
        source = Path(folder) / "panda_arm.yaml"
        source.write_text(f"name: panda_arm\nurdf:\n  file: {ROBOTS_DIR / 'panda_description/urdf/panda.urdf'}\n"
                          "  lock: {panda_finger_joint1: 0.02}\n")
        model = andyc.compile_model(source, Path(folder) / "build")[0]
        run = andyc.simulate(model, args.t_end, dt=1e-3, frames="all")
        path = run.save(Path(folder) / "panda.h5")
        data = view_data(run)
        start = time.perf_counter()
        written = write_view(run, Path(folder) / "panda.html")
        seconds = time.perf_counter() - start
        meshes = sum(s["kind"] == "mesh" for s in data["shapes"])
        print(f"panda view page: {written['bytes'] / 1e6:.1f} MB ({len(data['meshes'])} meshes stored for "
              f"{meshes} mesh shapes, {written['samples']} samples), written in {seconds:.2f} s; "
              f"run file {path.stat().st_size / 1e6:.1f} MB")


if __name__ == "__main__":
    main()
