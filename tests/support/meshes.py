"""A model with a shape, and mesh files, for the tests of shapes and of the mesh rule (no mesh library needed)."""

import struct

PENDULUM = """\
name: shaped
parameters: {L: 0.7, m: 1.0, g: 9.81}
coordinates: {q: {initial: 0.5}}
gravity: [0, -g, 0]
frames:
  - {name: arm, parent: world, revolute: q,
     shape: SHAPE}
  - {name: tip, parent: arm, translation: [0, -L, 0]}
bodies:
  - {name: bob, frame: tip, mass: m, shape: {sphere: {radius: L/10}, colour: red}}
"""


def with_shape(shape: str) -> str:
    """The pendulum with `shape` (a YAML flow mapping or list) on its arm."""
    return PENDULUM.replace("SHAPE", shape)


def binary_stl(triangles) -> bytes:
    """A binary STL of `triangles` [(a, b, c)], each corner three floats (the format's 80-byte header, count,
    then per triangle a normal, three corners and a 2-byte attribute)."""
    out = b"andyc test".ljust(80, b" ") + struct.pack("<I", len(triangles))
    for tri in triangles:
        out += struct.pack("<3f", 0, 0, 0) + b"".join(struct.pack("<3f", *p) for p in tri) + b"\0\0"
    return out
