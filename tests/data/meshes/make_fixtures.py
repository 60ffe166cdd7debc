#!/usr/bin/env python3
"""Writes the small mesh fixtures used by tests/mesh_io.rs (run from this directory).

One square pyramid (5 vertices, a quad base and 4 side triangles = 6 triangles) in OBJ, ASCII
PLY, binary little-endian PLY and binary big-endian PLY, with per-vertex normals, uvs and 8-bit
colours. All coordinates are dyadic so that float32 storage is exact, and the OBJ colours are
c / 255 printed with repr(), so every file loads to bit-identical f64 values. Also writes the
broken fixtures in ../bad/.
"""
import struct

P = [(-1.0, -1.0, 0.0), (1.0, -1.0, 0.0), (1.0, 1.0, 0.0), (-1.0, 1.0, 0.0), (0.0, 0.0, 2.0)]
N = [(0.0, 0.0, -1.0), (0.5, -0.5, 0.25), (0.5, 0.5, 0.25), (-0.5, 0.5, 0.25), (0.0, 0.0, 1.0)]
UV = [(0.0, 0.0), (1.0, 0.0), (1.0, 1.0), (0.0, 1.0), (0.5, 0.5)]
RGB = [(255, 0, 0), (0, 255, 0), (0, 0, 255), (128, 64, 10), (255, 255, 255)]
# Base quad (seen from below, so wound clockwise from above) and four sides.
FACES = [[0, 3, 2, 1], [0, 1, 4], [1, 2, 4], [2, 3, 4], [3, 0, 4]]


def fmt(x):
    return repr(float(x))


def obj(path, objects, mtl=True):
    with open(path, "w") as f:
        f.write("# square pyramid, see make_fixtures.py\n")
        if mtl:
            f.write("mtllib pyramid.mtl\n")
        for p, c in zip(P, RGB):
            f.write("v %s %s %s %s %s %s\n" % (*map(fmt, p), *(fmt(x / 255) for x in c)))
        for t in UV:
            f.write("vt %s %s\n" % tuple(map(fmt, t)))
        for n in N:
            f.write("vn %s %s %s\n" % tuple(map(fmt, n)))
        for name, faces in objects:
            f.write("o %s\n" % name)
            if mtl:
                f.write("usemtl stone\n")
            for face in faces:
                f.write("f " + " ".join("%d/%d/%d" % (i + 1, i + 1, i + 1) for i in face) + "\n")


def ply_header(fmt_name, nverts, nfaces, extra=""):
    return (
        "ply\nformat %s 1.0\ncomment square pyramid, see make_fixtures.py\n"
        "element vertex %d\nproperty float x\nproperty float y\nproperty float z\n"
        "property float nx\nproperty float ny\nproperty float nz\n"
        "property float u\nproperty float v\n"
        "property uchar red\nproperty uchar green\nproperty uchar blue\n%s"
        "element face %d\nproperty list uchar int vertex_indices\nend_header\n"
        % (fmt_name, nverts, extra, nfaces)
    )


def ply_ascii(path):
    with open(path, "w") as f:
        f.write(ply_header("ascii", len(P), len(FACES)))
        for p, n, t, c in zip(P, N, UV, RGB):
            f.write(" ".join(map(fmt, (*p, *n, *t))) + " %d %d %d\n" % c)
        for face in FACES:
            f.write("%d %s\n" % (len(face), " ".join(map(str, face))))


def ply_binary_body(order):
    body = b""
    for p, n, t, c in zip(P, N, UV, RGB):
        body += struct.pack(order + "8f3B", *p, *n, *t, *c)
    for face in FACES:
        body += struct.pack(order + "B%di" % len(face), len(face), *face)
    return body


def ply_binary(path, big):
    name = "binary_big_endian" if big else "binary_little_endian"
    with open(path, "wb") as f:
        f.write(ply_header(name, len(P), len(FACES)).encode())
        f.write(ply_binary_body(">" if big else "<"))


obj("pyramid.obj", [("pyramid", FACES)])
obj("pyramid_two_objects.obj", [("base", FACES[:1]), ("sides", FACES[1:])])
with open("pyramid.mtl", "w") as f:
    f.write("newmtl stone\nKd 0.8 0.8 0.8\nmap_Kd textures/stone.png\n")
ply_ascii("pyramid_ascii.ply")
ply_binary("pyramid_le.ply", False)
ply_binary("pyramid_be.ply", True)

# Two zero-area triangles (a repeated index and three collinear points) and one good one.
with open("degenerate.obj", "w") as f:
    f.write("v 0 0 0\nv 1 0 0\nv 0 1 0\nv 2 0 0\nf 1 2 3\nf 1 1 2\nf 1 2 4\n")

# ---- broken fixtures ---------------------------------------------------------------------
bad = "../bad/"
open(bad + "empty.obj", "w").close()
with open(bad + "bad_number.obj", "w") as f:
    f.write("# malformed number on line 3\nv 0 0 0\nv 1.0 1.x 0\nv 0 1 0\nf 1 2 3\n")
with open(bad + "index_out_of_range.obj", "w") as f:
    f.write("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\nf 1 2 7\n")
with open(bad + "nan_vertex.obj", "w") as f:
    f.write("v 0 0 0\nv 1 0 0\nv 0 nan 0\nf 1 2 3\n")
with open(bad + "bad_header.ply", "w") as f:
    f.write("ply\nformat ascii 1.0\nelement vertex 3\nproperty flaot x\nproperty float y\n"
            "property float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n"
            "0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n")
with open(bad + "inf_vertex.ply", "w") as f:
    f.write("ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
            "property float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n"
            "0 0 0\n1 0 0\n0 inf 0\n3 0 1 2\n")
with open(bad + "index_out_of_range.ply", "w") as f:
    f.write("ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
            "property float z\nelement face 2\nproperty list uchar int vertex_indices\nend_header\n"
            "0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n3 0 2 5\n")
with open(bad + "bad_number.ply", "w") as f:
    f.write("ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
            "property float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n"
            "0 0 0\n1 0 zero\n0 1 0\n3 0 1 2\n")
# Binary pyramid cut in the middle of face 3's index list.
full = ply_header("binary_little_endian", len(P), len(FACES)).encode() + ply_binary_body("<")
cut = len(full) - (1 + 4 * 3) - 6  # drop face 4 and 6 bytes of face 3
with open(bad + "truncated.ply", "wb") as f:
    f.write(full[:cut])
