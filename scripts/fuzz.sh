#!/usr/bin/env bash
# Runs the proptest-driven fuzz targets of tests/fuzz.rs with many more cases than the ordinary
# test run. Usage: scripts/fuzz.sh [CASES_PER_TARGET]   (default 20000). Prints each target's time.
set -euo pipefail
cd "$(dirname "$0")/.."
cases=${1:-20000}
cargo test --release --test fuzz --no-run --quiet
for t in fuzz_experiment_toml fuzz_display_toml fuzz_display_yaml fuzz_scene_toml fuzz_obj fuzz_ply_ascii fuzz_ply_binary fuzz_exr; do
    start=$(date +%s%N)
    if PROPTEST_CASES=$cases cargo test --release --quiet --test fuzz "$t" -- --exact > /tmp/fuzz-$t.log 2>&1; then r=ok; else r=FAILED; fi
    ms=$(( ($(date +%s%N) - start) / 1000000 ))
    printf '%-22s %6s cases  %7d ms  %s\n' "$t" "$cases" "$ms" "$r"
done
