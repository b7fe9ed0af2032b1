"""The size of `andyc view`'s page for URDF robots with meshes, the time to write it, and the time a headless
Chromium takes to open it (issue 43: each distinct mesh stored once, meshes above a face budget decimated).

    panda   example-robot-data's panda with its fingers locked (as tests/conftest.py's panda_arm), 2 s under
            gravity with every frame logged
    go1     example-robot-data's Go1 with its visual meshes (the DAE files, 52 MB of page at full resolution),
            falling freely for 1 s, every frame logged (its first build takes a few minutes)

For each robot: the run file's size; the page's size with the meshes decimated (the default) and at full
resolution (`andyc view --full-meshes`); the meshes stored against the mesh shapes drawn; the seconds to write
each page and to open it in headless Chromium until the viewer reports ready (Playwright; skipped, saying
why, without chromium). Both are CPU-bound, so a shared machine's load shows in them: figures, not limits.

    python bench/view_page.py [--robots panda,go1] [--t-end 2]
"""

from __future__ import annotations

import argparse
import shutil
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

import andyc  # noqa: E402
from andyc.plot.view import view_data, write_view  # noqa: E402
from tests.support import ROBOTS_DIR  # noqa: E402


def panda_run(folder: Path, t_end: float):
    source = folder / "panda_arm.yaml"
    source.write_text(f"name: panda_arm\nurdf:\n  file: {ROBOTS_DIR / 'panda_description/urdf/panda.urdf'}\n"
                      "  lock: {panda_finger_joint1: 0.02}\n")
    model = andyc.compile_model(source, folder / "build")[0]
    return andyc.simulate(model, t_end, dt=1e-3, frames="all")


def go1_run(folder: Path, t_end: float):
    source = folder / "go1_meshes.yaml"
    source.write_text(f"name: go1_meshes\nurdf:\n  file: {ROBOTS_DIR / 'go1_description/urdf/go1.urdf'}\n"
                      f"  base: floating\n  package_paths: ['{ROBOTS_DIR.parents[1]}']\n")
    model = andyc.compile_model(source, folder / "build")[0]
    return andyc.simulate(model, min(t_end, 1.0), dt=1e-3, frames="all")


def open_seconds(page_file: Path) -> float | str:
    """Seconds from navigation to the viewer's `ready` in a fresh headless Chromium page, or why not timed."""
    chromium = shutil.which("chromium") or shutil.which("chromium-browser")
    try:
        from playwright.sync_api import sync_playwright
    except ImportError:
        return "Playwright is not installed"
    if chromium is None:
        return "chromium is not installed"
    with sync_playwright() as p:
        browser = p.chromium.launch(executable_path=chromium, args=["--headless", "--no-sandbox", "--disable-gpu"])
        page = browser.new_context(offline=True, viewport={"width": 800, "height": 600}).new_page()
        start = time.perf_counter()
        page.goto(page_file.resolve().as_uri())
        page.wait_for_function("window.andycView && window.andycView.ready", timeout=600_000)
        seconds = time.perf_counter() - start
        browser.close()
    return seconds


def report(name: str, run, folder: Path) -> None:
    path = run.save(folder / f"{name}.h5")
    print(f"{name}: run file {path.stat().st_size / 1e6:.1f} MB")
    for label, budget in (("decimated", "default"), ("full meshes", None)):
        kwargs = {} if budget == "default" else {"face_budget": None}
        data = view_data(run, **kwargs)
        page = folder / f"{name}_{label.replace(' ', '_')}.html"
        start = time.perf_counter()
        written = write_view(run, page, **kwargs)
        wrote = time.perf_counter() - start
        opened = open_seconds(page)
        opened = f"{opened:.2f} s" if isinstance(opened, float) else f"not timed ({opened})"
        meshes = sum(s["kind"] == "mesh" for s in data["shapes"])
        counted = [m["faces"] for m in data["meshes"] if m["faces"] is not None]
        faces = f"{sum(counted)} faces" if len(counted) == len(data["meshes"]) else "faces not counted"
        print(f"  page, {label}: {written['bytes'] / 1e6:.1f} MB ({len(data['meshes'])} meshes, {faces}, "
              f"for {meshes} mesh shapes; {written['samples']} samples); written in {wrote:.2f} s, "
              f"opened headless in {opened}", flush=True)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--robots", default="panda,go1")
    parser.add_argument("--t-end", type=float, default=2.0)
    args = parser.parse_args()
    runs = {"panda": panda_run, "go1": go1_run}
    with tempfile.TemporaryDirectory() as folder:
        for name in args.robots.split(","):
            report(name, runs[name](Path(folder), args.t_end), Path(folder))


if __name__ == "__main__":
    main()
