#!/usr/bin/env bash
# Embree 4 against Embree 3 inside inimtrace, side by side: runs
# `EMBREE4_BINARY bench --backends --embree-only --also EMBREE3_BINARY` RUNS times (default 5) on
# 2 threads (RAYON_NUM_THREADS=2; Embree's own build threads are its TBB default, one per core),
# each run measuring both binaries one after the other, and prints the medians per scene and
# library of the build seconds and the nearest-hit and occlusion rays per second (the median
# pass after the first, and the first pass right after the build), with the ratio
# Embree 4 / Embree 3, and the load average before and after. Every run's backends.csv stays in
# OUT/run-N (default OUT: out/bench-embree-versions). Extra arguments go to `bench --backends`
# (e.g. --scene scenes/bunny.toml, --embree-input DIR for scripts/embree-bare.sh).
#
#   scripts/bench-embree-versions.sh EMBREE4_BINARY EMBREE3_BINARY [RUNS [OUT]] [-- BENCH_ARGS...]
set -euo pipefail
E4=${1:?usage: scripts/bench-embree-versions.sh EMBREE4_BINARY EMBREE3_BINARY [RUNS [OUT]] [-- BENCH_ARGS...]}
E3=${2:?usage: scripts/bench-embree-versions.sh EMBREE4_BINARY EMBREE3_BINARY [RUNS [OUT]] [-- BENCH_ARGS...]}
shift 2
RUNS=5
OUT=out/bench-embree-versions
if [ $# -gt 0 ] && [ "$1" != -- ]; then RUNS=$1; shift; fi
if [ $# -gt 0 ] && [ "$1" != -- ]; then OUT=$1; shift; fi
if [ $# -gt 0 ] && [ "$1" = -- ]; then shift; fi
echo "load before: $(uptime)"
for i in $(seq "$RUNS"); do
    RAYON_NUM_THREADS=2 "$E4" --quiet bench --backends --embree-only --also "$E3" --out "$OUT/run-$i" "$@" >/dev/null
    echo "run $i of $RUNS done: $(uptime)" >&2
done
echo "load after: $(uptime)"
python3 - "$OUT" "$RUNS" <<'EOF'
import csv, statistics, sys
out, runs = sys.argv[1], int(sys.argv[2])
rows = {}
for i in range(1, runs + 1):
    with open(f"{out}/run-{i}/backends.csv", newline="") as f:
        for r in csv.DictReader(f):
            if r["backend"] == "embree":
                rows.setdefault((r["scene"], r["library"]), []).append(r)
print(f"medians of {runs} runs, 2 threads")
print("| scene | library | build s | nearest-hit rays/s | first pass | occlusion rays/s | first pass | LA image s (process) |")
print("|---|---|---:|---:|---:|---:|---:|---:|")
med = {}
for (scene, lib), rs in sorted(rows.items()):
    m = {k: statistics.median(float(r[k]) for r in rs) for k in ["build_s", "nearest_rays_per_s", "nearest_cold_rays_per_s", "occluded_rays_per_s", "occluded_cold_rays_per_s", "la_process_s"]}
    med[(scene, lib[:8])] = m
    print(f"| {scene} | {lib} | {m['build_s']:.3f} | {m['nearest_rays_per_s']:,.0f} | {m['nearest_cold_rays_per_s']:,.0f} | "
          f"{m['occluded_rays_per_s']:,.0f} | {m['occluded_cold_rays_per_s']:,.0f} | {m['la_process_s']:.2f} |")
for scene in sorted({s for s, _ in med}):
    a, b = med.get((scene, "Embree 4")), med.get((scene, "Embree 3"))
    if a and b:
        print(f"{scene}: Embree 4 / Embree 3: build {a['build_s'] / b['build_s']:.3f}, nearest {a['nearest_rays_per_s'] / b['nearest_rays_per_s']:.3f}, "
              f"occlusion {a['occluded_rays_per_s'] / b['occluded_rays_per_s']:.3f}; first pass: nearest "
              f"{a['nearest_cold_rays_per_s'] / b['nearest_cold_rays_per_s']:.3f}, occlusion {a['occluded_cold_rays_per_s'] / b['occluded_cold_rays_per_s']:.3f}")
EOF
