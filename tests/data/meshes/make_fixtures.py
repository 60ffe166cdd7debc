#!/usr/bin/env python3
"""Writes the small mesh fixtures used by tests/mesh_io.rs, tests/formats.rs and tests/fuzz.rs
(run from this directory).

One square pyramid (5 vertices, a quad base and 4 side triangles = 6 triangles) in OBJ, ASCII
PLY, binary little-endian PLY and binary big-endian PLY, with per-vertex normals, uvs and 8-bit
colours; and the same triangles (the base fan-triangulated like the PLY reader does) in glTF
(buffer as a data: URI), GLB, ASCII STL and binary STL, with normals and uvs (glTF) or
positions only (STL). All coordinates are dyadic so that float32 storage is exact, and the OBJ colours are
c / 255 printed with repr(), so every file loads to bit-identical f64 values. Also writes the
broken fixtures in ../bad/.
"""
import base64
import json
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

TRIS = [t for face in FACES for t in ([face[0], face[i], face[i + 1]] for i in range(1, len(face) - 1))]


def gltf_parts():
    """The glTF buffer (positions, normals, uvs with v flipped, u16 indices) and document."""
    buf = b"".join(struct.pack("<3f", *p) for p in P)
    buf += b"".join(struct.pack("<3f", *n) for n in N)
    buf += b"".join(struct.pack("<2f", t[0], 1.0 - t[1]) for t in UV)
    buf += b"".join(struct.pack("<3H", *t) for t in TRIS)
    nv, ni = len(P), 3 * len(TRIS)
    views = [(0, 12 * nv), (12 * nv, 12 * nv), (24 * nv, 8 * nv), (32 * nv, 2 * ni)]
    doc = {
        "asset": {"version": "2.0", "generator": "make_fixtures.py"},
        "scene": 0,
        "scenes": [{"nodes": [0]}],
        "nodes": [{"name": "pyramid", "mesh": 0}],
        "meshes": [{"primitives": [{"attributes": {"POSITION": 0, "NORMAL": 1, "TEXCOORD_0": 2}, "indices": 3}]}],
        "accessors": [
            {"bufferView": 0, "componentType": 5126, "count": nv, "type": "VEC3",
             "min": [-1.0, -1.0, 0.0], "max": [1.0, 1.0, 2.0]},
            {"bufferView": 1, "componentType": 5126, "count": nv, "type": "VEC3"},
            {"bufferView": 2, "componentType": 5126, "count": nv, "type": "VEC2"},
            {"bufferView": 3, "componentType": 5123, "count": ni, "type": "SCALAR"},
        ],
        "bufferViews": [{"buffer": 0, "byteOffset": o, "byteLength": n} for o, n in views],
        "buffers": [{"byteLength": len(buf)}],
    }
    return buf, doc


def gltf(path):
    buf, doc = gltf_parts()
    doc["buffers"][0]["uri"] = "data:application/octet-stream;base64," + base64.b64encode(buf).decode()
    with open(path, "w") as f:
        json.dump(doc, f, indent=1)
        f.write("\n")


def glb(path):
    buf, doc = gltf_parts()
    js = json.dumps(doc).encode()
    js += b" " * (-len(js) % 4)
    buf += b"\0" * (-len(buf) % 4)
    total = 12 + 8 + len(js) + 8 + len(buf)
    with open(path, "wb") as f:
        f.write(struct.pack("<4sII", b"glTF", 2, total))
        f.write(struct.pack("<I4s", len(js), b"JSON") + js)
        f.write(struct.pack("<I4s", len(buf), b"BIN\0") + buf)


def stl_ascii(path):
    with open(path, "w") as f:
        f.write("solid pyramid\n")
        for t in TRIS:
            f.write("  facet normal 0 0 0\n    outer loop\n")
            for i in t:
                f.write("      vertex %s %s %s\n" % tuple(map(fmt, P[i])))
            f.write("    endloop\n  endfacet\n")
        f.write("endsolid pyramid\n")


def stl_binary(path):
    with open(path, "wb") as f:
        f.write(b"solid pyramid (binary; exporters often start the header with 'solid')".ljust(80, b" "))
        f.write(struct.pack("<I", len(TRIS)))
        for t in TRIS:
            f.write(struct.pack("<3f", 0.0, 0.0, 0.0))
            for i in t:
                f.write(struct.pack("<3f", *P[i]))
            f.write(b"\0\0")


gltf("pyramid.gltf")
glb("pyramid.glb")
stl_ascii("pyramid_ascii.stl")
stl_binary("pyramid_binary.stl")

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
