"""`andyc view`: the page's data against the run (decimation, positions, sticks, events, ground, plane), the
page self-contained (no script or style from elsewhere), and the page in a real headless browser (Debian's
chromium driven by Playwright, with the network off): the canvas is drawn, the shapes' pixels move between
two playback times, the status line names the time and the active flow, and no request leaves the file.
The browser tests skip, saying why, where chromium or Playwright is missing (.ci/run installs chromium
when apt can)."""

import json
import re
import shutil
from pathlib import Path

import numpy as np
import pytest
from click.testing import CliRunner
from PIL import Image

import andyc
from andyc import cli

pytest.importorskip("meshcat")
from andyc.plot.view import ground_planes, view_data, view_html  # noqa: E402
from andyc.runtime.run import Run  # noqa: E402

CHROMIUM = shutil.which("chromium") or shutil.which("chromium-browser")


def walker_run(n=601, ground={"axis": 1, "height": 0.0}) -> Run:
    """A planar two-legged stick walker over 3 s: hip (parent world) and two feet (parent hip) in the
    x-y plane, flows stance1/stance2 swapped at t = 1 and 2 by jumps strike2, strike1."""
    t = np.linspace(0.0, 3.0, n)
    hip = np.column_stack([0.4 * t, 1.0 + 0.03 * np.sin(6 * t), 0 * t])
    foot1 = np.column_stack([0.4 * t + 0.3 * np.sin(2 * t), 0.05 * np.abs(np.sin(3 * t)), 0 * t])
    foot2 = np.column_stack([0.4 * t - 0.3 * np.sin(2 * t), 0 * t, 0 * t])
    flow = (t >= 1.0).astype(int) - (t >= 2.0).astype(int)
    state = np.column_stack([hip[:, 0], hip[:, 1], np.full(n, 0.4), 0.18 * np.cos(6 * t)])
    k = np.searchsorted(t, [1.0, 2.0])
    events = {"time": np.array([1.0, 2.0]), "jump": np.array([0, 1], np.int32),
              "from_flow": np.array([0, 1], np.int32), "to_flow": np.array([1, 0], np.int32),
              "state_before": state[k - 1], "state_after": state[k], "discrete_after": np.zeros((2, 0))}
    return Run(model="walker", spec_sha256="0" * 64, method="rk4", dt=t[1] - t[0], nq=2, nv=2, rtol=0, atol=0,
               t_end=3.0, parameters={}, inputs={}, state_names=["x", "y", "x_dot", "y_dot"], time=t, state=state,
               energy=np.ones(n), frames={"hip": hip, "foot1": foot1, "foot2": foot2},
               frame_parents={"hip": "world", "foot1": "hip", "foot2": "hip"}, flow=flow,
               flow_names=["stance1", "stance2"], jump_names=["strike2", "strike1"], events=events,
               display={"ground": ground})


# -- the data ------------------------------------------------------------------------------------------

def test_the_data_holds_the_runs_frames_at_the_samples_kept_and_decimates_a_long_run():
    run = walker_run()
    data = view_data(run, fps=30)
    assert len(data["time"]) == 91                                # 3 s at 30 per second, both ends
    kept = np.searchsorted(run.time, np.array(data["time"]) + run.time[0] - 1e-12)
    for name in run.frames:
        assert np.allclose(data["frames"][name], run.frames[name][kept], rtol=1e-4, atol=1e-9)
    assert data["edges"] == [["hip", "foot1"], ["hip", "foot2"]]
    assert data["flow"] == [int(f) for f in run.flow[kept]] and data["flow_names"] == ["stance1", "stance2"]
    assert data["events"] == [[1.0, "strike2"], [2.0, "strike1"]]
    assert data["planar"] and data["up"] == 1 and data["ground"] == 0.0 and data["hybrid"]
    assert data["trails"] == ["foot1", "foot2"] and data["follow"] is None          # the end frames by default
    assert data["shapes"] == [] and data["rotations"] == {}
    short = view_data(run, fps=30, max_samples=20)
    assert len(short["time"]) == 20 and short["time"][-1] == pytest.approx(3.0)
    assert view_data(walker_run(ground=None))["ground"] is None       # no ground in the model: no grid


def test_the_page_is_one_file_with_nothing_from_elsewhere():
    page = view_html(view_data(walker_run()))
    tags = re.findall(r"<(script|link|img|iframe)\b[^>]*>", page)
    assert tags.count("script") == 3                      # the viewer, the data, the page's script
    assert not re.search(r"<script[^>]*\bsrc=", page) and not re.search(r"<link\b", page)
    data = page.split('id="andyc-data">', 1)[1].split("</script>", 1)[0]
    assert "</" not in data


def test_text_in_the_data_cannot_end_its_script_element():
    """Whatever text the data holds, it stays inside its JSON block: no '</script' or '<!--' forms there, and
    the JSON reads back equal."""
    data = view_data(walker_run())
    hostile = '</script><script>alert(1)</script><!--'
    data["model"] = hostile
    page = view_html(data)
    block = page.split('id="andyc-data">', 1)[1].split("</script>", 1)[0]
    assert "<" not in block and json.loads(block)["model"] == hostile


def test_view_command_writes_the_page_and_refuses_what_it_cannot_show(tmp_path):
    path = walker_run().save(tmp_path / "walker.h5")
    result = CliRunner().invoke(cli.main, ["view", str(path)])
    assert result.exit_code == 0, result.output
    assert (tmp_path / "walker.html").stat().st_size > 100_000 and "91 samples of 601" in result.output
    result = CliRunner().invoke(cli.main, ["view", str(path), "-o", str(tmp_path / "w.png")])
    assert result.exit_code == 2 and ".html" in result.output
    bare = walker_run()
    bare.frames, bare.frame_parents = {}, {}
    result = CliRunner().invoke(cli.main, ["view", str(bare.save(tmp_path / "bare.h5"))])
    assert result.exit_code == 2 and "--frames all" in result.output
    for option in ("--follow", "--trails"):
        result = CliRunner().invoke(cli.main, ["view", str(path), option, "knee", "-o", str(tmp_path / "k.html")])
        assert result.exit_code == 2 and "no frame 'knee'" in result.output and option in result.output
    result = CliRunner().invoke(cli.main, ["view", str(path), "--follow", "hip", "--trails", "hip,foot2",
                                           "-o", str(tmp_path / "f.html")])
    assert result.exit_code == 0, result.output
    data = json.loads((tmp_path / "f.html").read_text().split('id="andyc-data">', 1)[1].split("</script>", 1)[0])
    assert data["follow"] == "hip" and data["trails"] == ["hip", "foot2"]


def test_shapes_ride_on_their_frames_rotations(compiled, tmp_path):
    """A double pendulum run: each shape in the data as the model says, each shaped frame's rotation at the
    samples kept as the quaternion (x, y, z, w: three.js's order) of a turn about z by q1 (upper) and q1 + q2
    (lower), written by hand; the sticks only of frames without a shape; a shape on a frame the run did not
    log is listed as not drawn."""
    run = andyc.simulate(compiled("double_pendulum"), 1.0, dt=1e-3, frames="all")
    data = view_data(run, fps=30)
    kept = np.searchsorted(run.time, np.array(data["time"]) + run.time[0] - 1e-12)
    assert data["shapes"] == compiled("double_pendulum").display["shapes"] and data["missing"] == []
    q1, q2 = run.column("q1")[kept], run.column("q2")[kept]
    for name, angle in (("upper", q1), ("lower", q1 + q2), ("elbow", q1), ("tip", q1 + q2)):
        expected = np.column_stack([0 * angle, 0 * angle, np.sin(angle / 2), np.cos(angle / 2)])
        got = np.array(data["rotations"][name])
        sign = np.sign(np.sum(got * expected, axis=1))[:, None]
        assert np.allclose(got, sign * expected, atol=1e-4)              # written with 5 digits
    assert [e for e in data["edges"] if e[1] in ("elbow", "tip", "upper", "lower")] == []
    partial = andyc.simulate(compiled("double_pendulum"), 0.1, dt=1e-3, frames=["upper", "elbow"])
    assert view_data(partial)["missing"] == ["a box on frame 'lower', which the run did not log",
                                             "a sphere on frame 'tip', which the run did not log"]


def test_a_mesh_goes_into_the_page_whole(tmp_path):
    """A mesh shape's file is in the page as its bytes in base64, read from the run file, not the disk; two
    files with the same bytes are one mesh in the page."""
    import base64

    run = walker_run()
    stl = bytes(range(256)) * 3
    run.frame_rotations = {name: np.tile([1.0, 0, 0, 0], (len(run.time), 1)) for name in run.frames}
    run.display = {"ground": None, "shapes": [{"frame": "hip", "kind": "mesh", "file": str(tmp_path / "gone.stl"),
                                               "format": "stl", "scale": [1, 1, 1], "xyz": [0, 0, 0],
                                               "rpy": [0, 0, 0], "rgba": None}]}
    run.meshes = {str(tmp_path / "gone.stl"): stl}
    data = view_data(run)
    assert data["shapes"][0]["mesh"] == 0 and "file" not in data["shapes"][0]
    assert base64.b64decode(data["meshes"][0]["base64"]) == stl and data["meshes"][0]["format"] == "stl"
    twin = dict(run.display["shapes"][0], frame="foot1", file=str(tmp_path / "twin.stl"))
    run.display["shapes"].append(twin)
    run.meshes[twin["file"]] = stl
    data = view_data(run)                             # the same bytes under two names: stored once
    assert [s["mesh"] for s in data["shapes"]] == [0, 0] and len(data["meshes"]) == 1
    run.display["shapes"].pop()
    run.meshes = {}
    assert view_data(run)["missing"] == [f"the mesh {tmp_path / 'gone.stl'} (in neither the run file nor on disk)"]


# -- in a browser ----------------------------------------------------------------------------------------

@pytest.fixture(scope="module")
def browser():
    if CHROMIUM is None:
        pytest.skip("chromium is not installed (apt-get install chromium; .ci/run does it where apt can)")
    playwright = pytest.importorskip("playwright.sync_api", reason="Playwright is not installed (andyc[test])")
    with playwright.sync_playwright() as p:
        b = p.chromium.launch(executable_path=CHROMIUM, args=["--headless", "--no-sandbox", "--disable-gpu",
                                                              "--disable-background-networking"])
        yield b
        b.close()


def screenshots(browser, page_file: Path, times, out_dir: Path):
    """[(pixels, status text)] at each playback time, in a context with the network off; the requests
    the page made."""
    context = browser.new_context(offline=True, viewport={"width": 800, "height": 600})
    requests = []
    context.on("request", lambda r: requests.append(r.url))
    page = context.new_page()
    errors = []
    page.on("pageerror", lambda e: errors.append(str(e)))
    page.goto(page_file.resolve().as_uri())
    page.wait_for_function("window.andycView && window.andycView.ready", timeout=60_000)
    shots = []
    for i, t in enumerate(times):
        page.evaluate(f"window.andycView.seek({t})")
        # The status line follows on the next animation frame: wait for it, however busy the machine.
        page.wait_for_function(f"document.getElementById('status').textContent.includes('t = {t:.2f} s')",
                               timeout=120_000)
        png = out_dir / f"{page_file.stem}_{i}.png"
        page.locator("canvas").first.screenshot(path=str(png))
        with Image.open(png) as im:
            shots.append((np.asarray(im.convert("RGB")).astype(int), page.inner_text("#status")))
    context.close()
    assert errors == []
    return shots, requests


def moved(a, b) -> int:
    """Pixels that differ between two screenshots by more than a little in any channel."""
    return int(np.count_nonzero(np.abs(a - b).max(axis=2) > 24))


def coloured(pixels, test) -> np.ndarray:
    """The mask of the pixels whose (r, g, b) pass `test` (the background is a blue gradient)."""
    r, g, b = pixels[..., 0], pixels[..., 1], pixels[..., 2]
    return test(r, g, b)


def check_shapes_move(shots, test, least: int):
    """The shapes' pixels (those `test` picks) are drawn at each time, more than `least`, and move between."""
    (a, _), (b, _) = shots
    ma, mb = coloured(a, test), coloured(b, test)
    assert ma.sum() > least and mb.sum() > least, (ma.sum(), mb.sum())
    assert np.count_nonzero(ma != mb) > least // 2


def check_shots(shots, requests):
    (a, _), (b, _) = shots
    for pixels, _ in shots:
        assert len(np.unique(pixels.reshape(-1, 3), axis=0)) > 50   # drawn: not one colour
        assert pixels.std() > 10
    assert moved(a, b) > 100                                         # the sticks and joints moved
    assert all(url.startswith("file:") for url in requests), requests


def test_a_hybrid_walker_plays_offline_with_its_flow_named(browser, tmp_path):
    out = tmp_path / "walker.html"
    CliRunner().invoke(cli.main, ["view", str(walker_run().save(tmp_path / "walker.h5")), "-o", str(out)])
    shots, requests = screenshots(browser, out, [0.5, 1.5], tmp_path)
    check_shots(shots, requests)
    assert "t = 0.50 s" in shots[0][1] and "flow stance1" in shots[0][1]
    assert "t = 1.50 s" in shots[1][1] and "flow stance2" in shots[1][1]


def test_a_swing_bar_run_plays_offline(browser, compiled, tmp_path):
    run = andyc.simulate(compiled("swing_bar"), t_end=2.0, dt=1e-3, frames="all")
    out = tmp_path / "swing_bar.html"
    CliRunner().invoke(cli.main, ["view", str(run.save(tmp_path / "swing_bar.h5")), "-o", str(out)])
    shots, requests = screenshots(browser, out, [0.3, 1.2], tmp_path)
    check_shots(shots, requests)
    assert "t = 0.30 s" in shots[0][1] and "flow" not in shots[0][1]


def grey(r, g, b):
    """Near-white or grey, neither blue (the background) nor coloured: the panda's meshes."""
    return (np.abs(r - b) < 40) & (np.abs(r - g) < 40) & (r > 90)


def test_the_panda_with_its_meshes_plays_offline(browser, panda_arm, tmp_path):
    """example-robot-data's panda (fingers locked) falling under gravity, drawn with its DAE visual meshes
    (inlined in the page from the run file): the canvas is drawn, the meshes' pixels move, nothing is
    fetched."""
    run = andyc.simulate(panda_arm, t_end=1.5, dt=1e-3, frames="all")
    out = tmp_path / "panda.html"
    result = CliRunner().invoke(cli.main, ["view", str(run.save(tmp_path / "panda.h5")), "-o", str(out)])
    assert result.exit_code == 0 and "11 shapes" in result.output, result.output
    shots, requests = screenshots(browser, out, [0.2, 1.4], tmp_path)
    check_shots(shots, requests)
    check_shapes_move(shots, grey, 2000)


def test_a_double_pendulum_with_shapes_plays_offline(browser, compiled, tmp_path):
    """The YAML model's shape: keys: its red spheres (the masses) are drawn and move between two times."""
    run = andyc.simulate(compiled("double_pendulum"), t_end=2.0, dt=1e-3, frames="all")
    out = tmp_path / "double_pendulum.html"
    result = CliRunner().invoke(cli.main, ["view", str(run.save(tmp_path / "dp.h5")), "-o", str(out),
                                           "--trails", "tip"])
    assert result.exit_code == 0 and "4 shapes" in result.output, result.output
    shots, requests = screenshots(browser, out, [0.2, 1.0], tmp_path)
    check_shots(shots, requests)
    check_shapes_move(shots, lambda r, g, b: (r > 150) & (g < 90) & (b < 90), 200)


# -- the camera frames the run -----------------------------------------------------------------------------

PROJECT = """() => {
  // The scene as drawn now (all but the trails, the ground and the force arrows), its box's eight corners
  // through the page's camera into normalized device coordinates: inside the canvas is |x|, |y| <= 1.
  const v = window.andycView.viewer, THREE = MeshCat.THREE, box = new THREE.Box3();
  v.scene.updateMatrixWorld(true);
  for (const k of ["world", "frames", "bodies", "sticks", "fixed"]) box.expandByObject(v.scene_tree.find(["andyc", k]).object);
  const out = [];
  for (const x of [box.min.x, box.max.x]) for (const y of [box.min.y, box.max.y]) for (const z of [box.min.z, box.max.z]) {
    const p = new THREE.Vector3(x, y, z).project(v.camera);
    out.push([p.x, p.y, p.z]);
  }
  return out;
}"""


def projected_boxes(browser, page_file: Path, count: int = 9) -> list:
    """[(t, [[x, y, z] in NDC per corner of the scene's box])] at `count` times spread over the run (its start,
    and between: times that need not be samples)."""
    context = browser.new_context(offline=True, viewport={"width": 800, "height": 600})
    page = context.new_page()
    errors = []
    page.on("pageerror", lambda e: errors.append(str(e)))
    page.goto(page_file.resolve().as_uri())
    page.wait_for_function("window.andycView && window.andycView.ready", timeout=60_000)
    duration = page.evaluate("window.andycView.duration")
    out = []
    for t in np.linspace(0.0, 0.98 * duration, count):     # (the very end wraps to the start: the clip loops)
        page.evaluate(f"window.andycView.seek({t})")
        page.wait_for_function(f"document.getElementById('status').textContent.includes('t = {t:.2f} s')",
                               timeout=120_000)
        out.append((t, page.evaluate(PROJECT)))
    context.close()
    assert errors == []
    return out


def check_framed(boxes):
    """Every corner of the scene's box, at every time, inside the canvas and between the near and far planes;
    and the scene is not a speck (the box spans at least a tenth of the canvas at some time)."""
    for t, corners in boxes:
        c = np.array(corners)
        assert np.all(np.abs(c[:, :2]) <= 1.0), (t, c)
        assert np.all(np.abs(c[:, 2]) <= 1.0), (t, c)
    spans = [np.ptp(np.array(c)[:, :2], axis=0).max() for _, c in boxes]
    assert max(spans) > 0.2, spans


def test_the_camera_keeps_the_double_pendulum_in_the_canvas_at_every_time(browser, compiled, tmp_path):
    """The double pendulum's tip ran off the bottom of the canvas: now the camera frames the box of every
    sample of the run."""
    run = andyc.simulate(compiled("double_pendulum"), t_end=3.0, dt=1e-3, frames="all")
    out = tmp_path / "dp.html"
    assert CliRunner().invoke(cli.main, ["view", str(run.save(tmp_path / "dp.h5")), "-o", str(out)]).exit_code == 0
    check_framed(projected_boxes(browser, out))


def test_the_camera_keeps_a_hopper_in_the_canvas_at_every_time(browser, compiled, tmp_path):
    run = andyc.simulate(compiled("hopper_contact"), t_end=1.0, dt=1e-4, frames="all")
    out = tmp_path / "hopper.html"
    assert CliRunner().invoke(cli.main, ["view", str(run.save(tmp_path / "h.h5")), "-o", str(out)]).exit_code == 0
    check_framed(projected_boxes(browser, out))


@pytest.mark.parametrize("name, t_end", [("slider_crank", 2.0), ("fourbar", 2.0), ("compass_gait", 2.0),
                                          ("bouncing_ball_contact", 1.5), ("block_incline", 1.0),
                                          ("rimless_wheel_contact", 2.0)])
def test_the_camera_keeps_more_shipped_models_in_the_canvas_at_every_time(browser, compiled, tmp_path, name, t_end):
    run = andyc.simulate(compiled(name), t_end=t_end, dt=1e-3, frames="all")
    out = tmp_path / f"{name}.html"
    assert CliRunner().invoke(cli.main, ["view", str(run.save(tmp_path / "r.h5")), "-o", str(out)]).exit_code == 0
    check_framed(projected_boxes(browser, out, count=5))


def test_the_camera_keeps_the_panda_in_the_canvas_at_every_time(browser, panda_arm, tmp_path):
    run = andyc.simulate(panda_arm, t_end=1.5, dt=1e-3, frames="all")
    out = tmp_path / "panda.html"
    assert CliRunner().invoke(cli.main, ["view", str(run.save(tmp_path / "p.h5")), "-o", str(out)]).exit_code == 0
    check_framed(projected_boxes(browser, out))


def test_the_camera_keeps_a_followed_walker_in_the_canvas(browser, tmp_path):
    """--follow: the scene slides under the camera; the framing is of the scene as it is drawn then."""
    out = tmp_path / "walker.html"
    CliRunner().invoke(cli.main, ["view", str(walker_run().save(tmp_path / "w.h5")), "-o", str(out),
                                  "--follow", "hip"])
    check_framed(projected_boxes(browser, out))


# -- the ground -------------------------------------------------------------------------------------------

GROUNDLESS = {"newtons_cradle": "its contacts are between the balls (gaps of two frames), none on a ground"}


def test_every_shipped_model_with_contacts_on_a_ground_has_its_plane():
    """andyc.spec.display.contact_planes, for every shipped model with contacts: a plane (a unit normal) for
    at least one of them, but for the models listed with why; the block's incline is the slope's plane."""
    from andyc.spec.display import contact_planes
    from andyc.spec.load import load

    models = Path(andyc.__file__).parent.parent / "models"
    seen = 0
    for path in sorted(models.glob("*.yaml")):
        spec = load(path)
        if not spec.contacts:
            continue
        seen += 1
        planes = contact_planes(spec)
        assert bool(planes) != (path.stem in GROUNDLESS), path.stem
        for p in planes:
            assert np.linalg.norm(p["normal"]) == pytest.approx(1.0)
    assert seen >= 10
    incline = contact_planes(load(models / "block_incline.yaml"))[0]
    assert np.allclose(incline["normal"], [-np.sin(0.5), np.cos(0.5), 0]) and incline["offset"] == 0.0
    assert np.allclose(incline["tangents"], [[np.cos(0.5), np.sin(0.5), 0]])


def test_a_model_with_a_ground_section_draws_that_ground_not_its_feets_centres():
    """Go1's feet are spheres of radius 0.02 m (its URDF's <collision>): their contact planes are their
    centres', 2 cm up; the ground the page draws is the model's `ground:`, at height 0. A damaged record of
    the ground falls back to the contacts' planes."""
    from andyc.spec.display import display
    from andyc.spec.load import load

    shown = display(load(Path(andyc.__file__).parent.parent / "models" / "go1.yaml"))
    assert {c["offset"] for c in shown["contacts"] if c["name"].endswith("foot_sphere")} == {-0.02}
    run = walker_run(n=11)
    run.display = {**run.display, "contacts": shown["contacts"], "plane": shown["plane"]}
    assert ground_planes(run) == [{"normal": [0.0, 0.0, 1.0], "offset": 0.0}]
    run.display["plane"] = {"normal": [0.0, 0.0, 2.0], "offset": 0.0}           # not a unit normal: damaged
    assert ground_planes(run) == [{"normal": [0.0, 0.0, 1.0], "offset": -0.02}]
    run.display["plane"] = None
    assert ground_planes(run) == [{"normal": [0.0, 0.0, 1.0], "offset": -0.02}]


def ground_in_page(browser, page_file: Path) -> tuple:
    """(<body data-ground-planes>, the number of three.js objects named 'andyc-ground' in the scene)."""
    context = browser.new_context(offline=True, viewport={"width": 800, "height": 600})
    page = context.new_page()
    page.goto(page_file.resolve().as_uri())
    page.wait_for_function("window.andycView && window.andycView.ready", timeout=60_000)
    out = page.evaluate("""() => { let k = 0;
      window.andycView.viewer.scene.traverse((o) => { if (o.name === "andyc-ground") k++; });
      return [document.body.dataset.groundPlanes, k]; }""")
    context.close()
    return tuple(out)


def test_the_page_draws_the_ground_of_a_contact_model_and_none_without(browser, compiled, tmp_path):
    for model, expected in (("bouncing_ball_contact", 1), ("block_incline", 1), ("double_pendulum", 0)):
        run = andyc.simulate(compiled(model), t_end=0.5, dt=1e-3, frames="all")
        data = view_data(run)
        assert len(data["planes"]) == expected, model
        out = tmp_path / f"{model}.html"
        out.write_text(view_html(data))
        assert ground_in_page(browser, out) == (str(expected), expected), model


# -- the contacts' forces ---------------------------------------------------------------------------------

ARROWS = """() => { const out = [];
  window.andycView.viewer.scene.traverse((o) => { if (o.name === "andyc-force")
    out.push([o.userData.contact, o.userData.kind, o.visible, o.visible ? o.line.scale.y : 0,
              new MeshCat.THREE.Vector3(0, 1, 0).applyQuaternion(o.quaternion).toArray()]); });
  return out; }"""


def test_force_arrows_show_while_the_hoppers_foot_is_down_and_not_in_flight(browser, compiled, tmp_path):
    """The hopper's foot lands at 0.319 s and lifts off at 0.425 s (models/hopper_contact.yaml): its normal
    force's arrow is shown in stance (pointing up, as long as the largest force's 0.3 of the scene at most) and
    hidden in flight before and after; the "forces" box hides it in stance too. The data's force is the run's
    normal force along the ground's normal."""
    run = andyc.simulate(compiled("hopper_contact"), t_end=0.6, dt=1e-4, frames="all")
    data = view_data(run)
    (c,) = data["forces"]["contacts"]
    kept = np.searchsorted(run.time, np.array(data["time"]) + run.time[0] - 1e-12)
    assert np.allclose(np.array(c["normal"])[:, 1], run.normal_forces[kept, 0], rtol=1e-4, atol=1e-9)
    assert np.allclose(np.array(c["foot"])[:, 1], 0.0) and np.all(np.array(c["friction"]) == 0)
    out = tmp_path / "hopper.html"
    out.write_text(view_html(data))
    context = browser.new_context(offline=True, viewport={"width": 800, "height": 600})
    page = context.new_page()
    page.goto(out.resolve().as_uri())
    page.wait_for_function("window.andycView && window.andycView.ready", timeout=60_000)
    seen = {}
    for t in (0.1, 0.37, 0.55):
        page.evaluate(f"window.andycView.seek({t})")
        page.wait_for_function(f"document.getElementById('status').textContent.includes('t = {t:.2f} s')",
                               timeout=120_000)
        seen[t] = {kind: (visible, length, up) for _, kind, visible, length, up in page.evaluate(ARROWS)}
    page.uncheck("#forces")
    page.evaluate("window.andycView.seek(0.38)")
    page.wait_for_function("document.getElementById('status').textContent.includes('t = 0.38 s')", timeout=120_000)
    unticked = {kind: visible for _, kind, visible, _, _ in page.evaluate(ARROWS)}
    context.close()
    assert seen[0.1]["normal"][0] is False and seen[0.55]["normal"][0] is False      # in flight
    assert seen[0.37]["normal"][0] is True                                           # in stance: up,
    assert 0 < seen[0.37]["normal"][1] <= 0.3 * data["extent"] * (1 + 1e-6)         # scaled
    assert np.allclose(seen[0.37]["normal"][2], [0, 1, 0], atol=1e-6)
    assert seen[0.37]["friction"][0] is False                                        # frictionless
    assert unticked == {"normal": False, "friction": False}


def test_a_damaged_contact_record_draws_nothing_for_it_and_names_stay_data():
    """A run file's display 'contacts' written by hand: entries that are not planes of finite numbers are left
    out (no ground, no arrow for them), not an internal error; a hostile contact name stays inside the JSON."""
    run = walker_run()
    run.contact_names = ["</script><script>alert(1)</script>", "bad"]
    run.contact_rows = [0, 1]
    run.multiplier_names = ["n0", "n1"]
    run.multipliers = np.ones((len(run.time), 2))
    run.contact_stick_rows, run.contact_mu, run.contact_tangents = [-1, -1], [np.nan, np.nan], [0, 0]
    run.slip_speeds = run.slip_speeds_2 = np.full((len(run.time), 2), np.nan)
    run.discrete_names = [f"{c}_mode" for c in run.contact_names]
    run.discrete = np.ones((len(run.time), 2))
    run.display = {"ground": None, "contacts": [
        {"name": run.contact_names[0], "frame": "foot2", "normal": [0, 1, 0], "offset": 0.0, "tangents": []},
        {"name": "bad", "frame": "foot1", "normal": [0, "x", 0], "offset": 0.0},
        {"name": "nan", "frame": "foot1", "normal": [0, 0, 0], "offset": float("nan")}, "not a dict"]}
    data = view_data(run)
    assert data["planes"] == [{"normal": [0.0, 1.0, 0.0], "offset": 0.0}]
    assert [c["name"] for c in data["forces"]["contacts"]] == [run.contact_names[0]]
    block = view_html(data).split('id="andyc-data">', 1)[1].split("</script>", 1)[0]
    assert "<" not in block
