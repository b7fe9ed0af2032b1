"""Meshes for `andyc view`'s page, simplified above a face budget (issue 43: Go1's page was 52 MB, its trunk
alone 351k faces in a 29 MB DAE). A mesh above the budget is decimated by quadric error (trimesh's
`simplify_quadric_decimation`, which runs the `fast-simplification` package) and stored as binary STL, the
most compact format MeshCat's bundle reads; a mesh at or under the budget keeps its file's bytes. The
decimated mesh has no colour of its own (STL has none), so the page draws it in the shape's colour or grey.
Without fast-simplification (or trimesh) every mesh stays at full resolution, with one warning."""

from __future__ import annotations

import io
import warnings

FACE_BUDGET = 10_000        # per distinct mesh; Go1's seven meshes then fit a page of a few MB

_warned = False


def simplified(data: bytes, fmt: str, budget: int | None = FACE_BUDGET) -> tuple[bytes, str, int | None]:
    """(bytes, format, faces): the mesh `data` (format 'stl', 'obj' or 'dae') with at most `budget`
    faces, as binary STL if it was decimated; unchanged when `budget` is None, when it is under the budget,
    or when it cannot be read or decimated (faces None when it was not read)."""
    global _warned
    if budget is None:
        return data, fmt, None
    try:
        import trimesh
        mesh = trimesh.load(io.BytesIO(data), file_type=fmt, force="mesh")
    except Exception:        # noqa: BLE001 - an unreadable mesh is drawn as it is, by the browser's loader
        return data, fmt, None
    faces = len(mesh.faces)
    if faces <= budget:
        return data, fmt, faces
    try:
        import fast_simplification  # noqa: F401 - trimesh's decimation imports it; ask first for a clear warning
        small = mesh.simplify_quadric_decimation(face_count=budget)
    except ImportError:
        if not _warned:
            warnings.warn("andyc view: meshes are drawn at full resolution because the fast-simplification "
                          "package is missing (pip install 'andyc[view]'); the page may be large", stacklevel=2)
            _warned = True
        return data, fmt, faces
    return small.export(file_type="stl"), "stl", len(small.faces)
