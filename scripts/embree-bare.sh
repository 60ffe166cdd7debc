#!/usr/bin/env bash
# Embree 3 against Embree 4 in a bare C loop (scripts/embree-bare.c), without inimtrace: tells
# the libraries' own speed from inimtrace's overhead on them.
#
#   scripts/embree-bare.sh DIR [RUNS [THREADS [EMBREE4_CONFIG [MODE]]]]
#
# DIR holds the scenes' `<scene>.embree-input` files that
# `inimtrace bench --backends --embree-input DIR` wrote. The script compiles embree-bare.c twice,
# against the system's Embree 3 (libembree-dev) and against Embree 4 (the embree4-sys crate's
# headers, the library in EMBREE4_DIR or target/embree4/), runs the two alternately RUNS times
# (default 5) on THREADS threads (default 2) per input, and prints every run and the medians of
# build seconds and nearest-hit and occlusion rays per second, with the ratio Embree 4 / Embree 3.
# EMBREE4_CONFIG is a device configuration string for Embree 4 only (e.g. `isa=avx2`); MODE is
# plan (inimtrace's packet plan, default), packets or single.
set -euo pipefail
cd "$(dirname "$0")/.."
DIR=${1:?usage: scripts/embree-bare.sh DIR [RUNS [THREADS [EMBREE4_CONFIG [MODE]]]]}
RUNS=${2:-5}
THREADS=${3:-2}
CONFIG4=${4:-}
MODE=${5:-plan}
LIB4=${EMBREE4_DIR:-$PWD/target/embree4}
[ -e "$LIB4/libembree4.so" ] || LIB4=$LIB4/lib
[ -e "$LIB4/libembree4.so" ] || { echo "error: no libembree4.so in EMBREE4_DIR or target/embree4/" >&2; exit 1; }
# The embree4-sys crate ships the Embree 4 headers that inimtrace's `embree4` feature binds.
HEADERS=$(cargo metadata --format-version 1 --features embree4 --locked 2>/dev/null | python3 -c '
import json, os, sys
for p in json.load(sys.stdin)["packages"]:
    if p["name"] == "embree4-sys":
        print(os.path.join(os.path.dirname(p["manifest_path"]), "lib"))')
[ -e "$HEADERS/embree4/rtcore.h" ] || { echo "error: embree4-sys's headers not found (cargo fetch first)" >&2; exit 1; }
BIN=$(mktemp -d)
trap 'rm -rf "$BIN"' EXIT
gcc -O2 -std=c11 -Wall -Wextra -o "$BIN/bare3" scripts/embree-bare.c -lembree3 -lpthread
gcc -O2 -std=c11 -Wall -Wextra -DINIM_EMBREE4 -I"$HEADERS" -o "$BIN/bare4" scripts/embree-bare.c \
    -L"$LIB4" -Wl,-rpath,"$LIB4" -lembree4 -lpthread
median() { sort -g | awk '{a[NR] = $1} END {print (NR % 2) ? a[(NR + 1) / 2] : (a[NR / 2] + a[NR / 2 + 1]) / 2}'; }
field() { tr ' ' '\n' | sed -n "s/^$1=//p"; }
echo "load: $(uptime)"
for input in "$DIR"/*.embree-input; do
    : >"$BIN/3" && : >"$BIN/4"
    for _ in $(seq "$RUNS"); do
        "$BIN/bare3" "$input" "$THREADS" "" "$MODE" | tee -a "$BIN/3"
        "$BIN/bare4" "$input" "$THREADS" "$CONFIG4" "$MODE" | tee -a "$BIN/4"
    done
    for f in build_s nearest_rays_per_s nearest_cold_rays_per_s occluded_rays_per_s occluded_cold_rays_per_s; do
        a=$(field "$f" <"$BIN/3" | median)
        b=$(field "$f" <"$BIN/4" | median)
        echo "$(basename "$input" .embree-input) $f median: Embree 3 $a, Embree 4 $b, Embree 4 / Embree 3 $(awk "BEGIN {printf \"%.3f\", $b / $a}")"
    done
done
echo "load: $(uptime)"
