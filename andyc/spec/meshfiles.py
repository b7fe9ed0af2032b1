"""Which mesh files a model may name, and reading them.

A model file may come from anyone (andyc runs in other projects' CI), and a mesh's bytes travel into the
run file and the page `andyc view` writes, which people share. So a mesh is read only when it passes this
rule, checked on the path the name resolves to (every symbolic link followed), never on the name as
written:

- it lies inside one of the model's mesh roots: for a YAML `shape:`, the model file's folder; for a URDF,
  the package folder a `package://PKG/...` name was found in (or the search path itself, for a name found
  directly under it), and for a relative or absolute name the URDF's package (the nearest folder above the
  URDF that holds a `package.xml`, else the URDF's own folder) or a folder of `urdf: {package_paths}`;
- it is a regular file (not a device, a pipe or a folder), whose resolved name ends in .stl, .obj or .dae;
- it is at most MAX_MESH_BYTES long (its size read from the file system, before any byte is read).

So `evil.stl -> /etc/passwd`, a chain `b.obj -> a.dae -> /etc/passwd`, `package://p/../../../x.stl` and
`../secret.stl` beside a YAML model are all refused, with the reason.
"""

from __future__ import annotations

import os
import stat
from pathlib import Path

MESH_FORMATS = {".stl": "stl", ".obj": "obj", ".dae": "dae"}
MAX_MESH_BYTES = 32 * 2**20          # a robot's finest link mesh is a few MB; a scene's is not a mesh file


class MeshRefused(ValueError):
    """A mesh file that breaks the rule above; its text says which part and what to do."""


def checked_mesh(path: Path, roots) -> tuple[Path, str]:
    """(the resolved path, its format) of a mesh file that keeps the rule above; MeshRefused otherwise.
    `roots` are folders (they are resolved too)."""
    if "\0" in str(path):                     # (no file system's name holds one; os calls raise ValueError)
        raise MeshRefused("has a NUL character in its name, which no file's name can hold")
    try:
        resolved = Path(path).resolve(strict=True)
    except (OSError, RuntimeError):           # missing, or a loop of links
        raise MeshRefused("does not exist") from None
    inside = [r for r in roots if _inside(resolved, r)]
    if not inside:
        raise MeshRefused(f"resolves to {resolved}, outside the folders a mesh may come from "
                          f"({', '.join(str(Path(r).resolve()) for r in roots)})")
    info = os.stat(resolved)
    if not stat.S_ISREG(info.st_mode):
        raise MeshRefused(f"resolves to {resolved}, which is not a regular file")
    fmt = MESH_FORMATS.get(resolved.suffix.lower())
    if fmt is None:
        raise MeshRefused(f"resolves to {resolved}, which is not STL, OBJ or DAE by its name")
    if info.st_size > MAX_MESH_BYTES:
        raise MeshRefused(f"is {info.st_size / 2**20:.0f} MB, past andyc's limit of {MAX_MESH_BYTES // 2**20} MB "
                          "for one mesh")
    return resolved, fmt


def read_mesh(file: str) -> bytes | None:
    """The bytes of a mesh file a spec accepted (by its resolved path, as the shapes hold it); None when it
    is gone or no longer a regular mesh file within the size limit (it changed since the model was read).
    The file is opened without following a link at its last component, and read no further than the
    limit, so a file swapped since the check still cannot leak a device or another file's bytes."""
    path = Path(file)
    if "\0" in str(file) or MESH_FORMATS.get(path.suffix.lower()) is None:
        return None
    try:
        fd = os.open(path, os.O_RDONLY | getattr(os, "O_NOFOLLOW", 0) | getattr(os, "O_NONBLOCK", 0))
    except OSError:
        return None
    with os.fdopen(fd, "rb") as f:
        info = os.fstat(f.fileno())
        if not stat.S_ISREG(info.st_mode) or info.st_size > MAX_MESH_BYTES:
            return None
        data = f.read(MAX_MESH_BYTES + 1)
    return data if len(data) <= MAX_MESH_BYTES else None


def package_root(folder: Path) -> Path:
    """The ROS package a URDF sits in: the nearest folder from `folder` up that holds a package.xml, else
    `folder` itself."""
    folder = Path(folder).resolve()
    for candidate in (folder, *folder.parents):
        if (candidate / "package.xml").is_file():
            return candidate
    return folder


def _inside(path: Path, root) -> bool:
    try:
        path.relative_to(Path(root).resolve())
        return True
    except (ValueError, OSError):
        return False
