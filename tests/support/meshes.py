"""Mesh files for the tests of shapes and of the mesh rule, written here (no mesh library needed)."""

import struct


def binary_stl(triangles) -> bytes:
    """A binary STL of `triangles` [(a, b, c)], each corner three floats (the format's 80-byte header, count,
    then per triangle a normal, three corners and a 2-byte attribute)."""
    out = b"andyc test".ljust(80, b" ") + struct.pack("<I", len(triangles))
    for tri in triangles:
        out += struct.pack("<3f", 0, 0, 0) + b"".join(struct.pack("<3f", *p) for p in tri) + b"\0\0"
    return out
