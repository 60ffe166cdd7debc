#!/usr/bin/env sh
# Writes a corpus of mesh files shaped the way real exporters write them, into the folder given
# (created if needed): Windows-style `\` texture paths, texture options before the file name,
# missing and unreadable textures (a folder, a file that is not an image), glTF files whose image
# is missing or broken, PLY and OBJ files with vertex colours that cannot be used, an OBJ in
# Latin-1 and one in UTF-16, and an MTL file that cannot be parsed. Every file here loads: the
# trouble is a warning and the material's base colour. tests/mesh_corpus.rs runs this script
# and checks each file's warnings and colours (see docs/SCENES.md, "Files as exporters write
# them").
#   usage: scripts/make-mesh-corpus.sh OUT_DIR
set -eu
if [ $# -ne 1 ]; then
    echo "usage: $0 OUT_DIR" >&2
    exit 2
fi
out=$1
mkdir -p "$out/textures" "$out/folder.png"
cd "$out"

# A 2 x 2 PNG, sRGB (255, 0, 0): linear red (1, 0, 0).
red_png=iVBORw0KGgoAAAANSUhEUgAAAAIAAAACCAIAAAD91JpzAAAAEElEQVR4nGP4z8AARAwQCgAf7gP9i18U1AAAAABJRU5ErkJggg==
echo "$red_png" | base64 -d > textures/red.png
# Not an image at all, and an image whose data stops after the header.
printf 'this is not a PNG file\n' > garbage.png
echo "$red_png" | base64 -d | head -c 40 > truncated.png

# A unit square (two triangles) with uvs, its corners in the plane z = 0; $1 = usemtl lines
# placed before each triangle, as "mtl_a mtl_b".
square() {
    printf 'v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nvt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\n'
    printf 'usemtl %s\nf 1/1 2/2 3/3\n' "$1"
    printf 'usemtl %s\nf 1/1 3/3 4/4\n' "$2"
}

# 1. `\` as the separator: `.\textures\red.png` exists (as textures/red.png) and loads.
printf 'newmtl Red\nKd 0.8 0.8 0.8\nmap_Kd .\\textures\\red.png\n' > backslash.mtl
{ printf 'mtllib backslash.mtl\n'; square Red Red; } > backslash.obj

# 2. Texture options before the file name (MTL specification: -s, -o, -bm, -clamp ...).
printf 'newmtl Red\nmap_Kd -s 1 1 1 -o 0 0 -bm 0.5 -clamp on textures\\red.png\n' > options.mtl
{ printf 'mtllib options.mtl\n'; square Red Red; } > options.obj

# 3. One texture missing, one a folder, one not an image, one cut short; each material's Kd
#    is its colour then. A material without Kd falls back to the default grey.
{
    printf 'newmtl Missing\nKd 0.2 0.4 0.6\nmap_Kd .\\not-there.jpg\n'
    printf 'newmtl Folder\nKd 0.1 0.2 0.3\nmap_Kd folder.png\n'
    printf 'newmtl Garbage\nKd 0.3 0.2 0.1\nmap_Kd garbage.png\n'
    printf 'newmtl Truncated\nmap_Kd truncated.png\n'
} > bad-textures.mtl
{
    printf 'mtllib bad-textures.mtl\n'
    printf 'v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 2 0 0\nv 2 1 0\nvt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\n'
    printf 'usemtl Missing\nf 1/1 2/2 3/3\nusemtl Folder\nf 1/1 3/3 4/4\n'
    printf 'usemtl Garbage\nf 2/1 5/2 6/3\nusemtl Truncated\nf 2/1 6/3 3/4\n'
} > bad-textures.obj

# 4. The material library itself missing, and one that cannot be parsed (an unnamed
#    `newmtl`, as Blender 2.61 wrote it, with an unnamed `usemtl` in the OBJ).
{ printf 'mtllib .\\no-such-library.mtl\n'; square Red Red; } > missing-mtl.obj
printf 'newmtl \nKd 0.8 0.8 0.8\n' > unnamed.mtl
{ printf 'mtllib unnamed.mtl\n'; square '' ''; } > unnamed-mtl.obj

# 5. OBJ vertex colours on some vertices only: dropped with a warning (base colour).
printf 'newmtl Blue\nKd 0.1 0.1 0.9\n' > blue.mtl
printf 'mtllib blue.mtl\nv 0 0 0 1 0 0\nv 1 0 0\nv 1 1 0 0 1 0\nusemtl Blue\nf 1 2 3\n' > partial-colors.obj
# Non-finite vertex colours: dropped with a warning.
printf 'v 0 0 0 nan 0 0\nv 1 0 0 1 0 0\nv 1 1 0 1 0 0\nf 1 2 3\n' > nan-colors.obj

# 6. Text encodings: Latin-1 material names (as 3ds Max wrote them), UTF-16 with a BOM.
printf 'newmtl Terraind\346k\nKd 0.25 0.5 0.75\n' > latin1.mtl
printf 'mtllib latin1.mtl\nv 0 0 0\nv 1 0 0\nv 1 1 0\nusemtl Terraind\346k\nf 1 2 3\n' > latin1.obj
printf 'v 0 0 0\nv 1 0 0\nv 1 1 0\nf 1 2 3\n' | iconv -f UTF-8 -t UTF-16 > utf16.obj

# 7. PLY vertex colours that cannot be used; the geometry loads, the colour is the default.
ply_triangle() { # $1 = vertex property lines, $2..$4 = the three vertex lines
    printf 'ply\nformat ascii 1.0\nelement vertex 3\n%belement face 1\nproperty list uchar int vertex_indices\nend_header\n' "$1"
    printf '%s\n%s\n%s\n3 0 1 2\n' "$2" "$3" "$4"
}
xyz='property float x\nproperty float y\nproperty float z\n'
# red and green, no blue
ply_triangle "${xyz}property uchar red\nproperty uchar green\n" '0 0 0 255 0' '1 0 0 255 0' '1 1 0 255 0' \
    > ply-two-channels.ply
# a colour given as a list
ply_triangle "${xyz}property list uchar uchar red\nproperty uchar green\nproperty uchar blue\n" \
    '0 0 0 1 255 0 0' '1 0 0 1 255 0 0' '1 1 0 1 255 0 0' > ply-list-color.ply
# NaN float colours
ply_triangle "${xyz}property float red\nproperty float green\nproperty float blue\n" \
    '0 0 0 nan 0 0' '1 0 0 1 0 0' '1 1 0 1 0 0' > ply-nan-color.ply
# channels of different types (uchar red, float green, ushort blue): each by its own type
ply_triangle "${xyz}property uchar red\nproperty float green\nproperty ushort blue\n" \
    '0 0 0 255 0 0' '1 0 0 255 0 0' '1 1 0 255 0 0' > ply-mixed-types.ply

# 8. glTF: a triangle whose material's image is missing, broken (bad base64), or not an image;
#    the baseColorFactor is the colour then.
tri_b64=AAAAAAAAAAAAAAAAAACAPwAAAAAAAAAAAACAPwAAgD8AAAAAAAAAAAAAAAAAAIA/AAAAAAAAgD8AAIA/
gltf() { # $1 = the image object
    cat <<EOF
{
  "asset": {"version": "2.0"},
  "scene": 0, "scenes": [{"nodes": [0]}], "nodes": [{"mesh": 0}],
  "meshes": [{"primitives": [{"attributes": {"POSITION": 0, "TEXCOORD_0": 1}, "material": 0}]}],
  "materials": [{"name": "Painted", "pbrMetallicRoughness": {"baseColorFactor": [0.1, 0.5, 0.9, 1.0],
                 "baseColorTexture": {"index": 0}}}],
  "textures": [{"source": 0}],
  "images": [$1],
  "buffers": [{"byteLength": 60, "uri": "data:application/octet-stream;base64,$tri_b64"}],
  "bufferViews": [{"buffer": 0, "byteOffset": 0, "byteLength": 36}, {"buffer": 0, "byteOffset": 36, "byteLength": 24}],
  "accessors": [
    {"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3", "min": [0, 0, 0], "max": [1, 1, 0]},
    {"bufferView": 1, "componentType": 5126, "count": 3, "type": "VEC2"}
  ]
}
EOF
}
gltf '{"uri": "not-there.png"}' > gltf-missing-image.gltf
gltf '{"uri": "data:image/png;base64,@@@not base64@@@"}' > gltf-bad-data-uri.gltf
gltf '{"uri": "garbage.png"}' > gltf-garbage-image.gltf
gltf '{"uri": "textures/red.png"}' > gltf-good-image.gltf
