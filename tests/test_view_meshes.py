"""andyc view's mesh simplification (andyc.plot.meshes, issue 43): a mesh above the face budget is decimated
to at most the budget, keeps its bounding box, and a mesh under it keeps its file's bytes."""

import io

import numpy as np
import trimesh

from andyc.plot.meshes import simplified


def test_a_mesh_above_the_budget_is_decimated_and_keeps_its_extent():
    big = trimesh.creation.icosphere(subdivisions=5)            # 20480 faces
    big.apply_scale([0.3, 0.1, 0.05])
    data, fmt, faces = simplified(big.export(file_type="stl"), "stl", budget=2000)
    small = trimesh.load(io.BytesIO(data), file_type="stl")
    assert fmt == "stl" and faces == len(small.faces) <= 2000
    assert np.allclose(small.bounds, big.bounds, rtol=0.03, atol=0.003)


def test_a_mesh_under_the_budget_or_with_no_budget_is_unchanged():
    data = trimesh.creation.box().export(file_type="stl")
    assert simplified(data, "stl", budget=2000)[0] == data
    big = trimesh.creation.icosphere(subdivisions=5).export(file_type="stl")
    assert simplified(big, "stl", budget=None) == (big, "stl", None)
