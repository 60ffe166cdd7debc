#!/usr/bin/env bash
# Times sweeps/pupil-focus.toml (the paper's experiment for one eye: 6 pupils x 8 focus
# distances, 48 points) three ways and prints the sweep's overhead per point:
#   1. `inimtrace sweep` on all cores of this machine;
#   2. the same 48 points as bare `inimtrace assess` runs (each point's --set arguments from
#      sweep.json), whose stage timings give the work the sweep does: the display images once,
#      then per point the ground truth, the perceived images and the metrics;
#   3. the sweep through Slurm (`--slurm --wait`) when a cluster answers (scripts/slurm-local.sh).
# Overhead per point = (sweep wall time - that work) / 48, also as a share of the work.
# Usage: scripts/bench-sweep.sh [OUT]   (default out/bench-sweep; needs python3)
set -euo pipefail
cd "$(dirname "$0")/.."
OUT="${1:-out/bench-sweep}"
BIN=target/release/inimtrace
SWEEP=sweeps/pupil-focus.toml
cargo build --release -q
rm -rf "$OUT"
mkdir -p "$OUT"
now() { date +%s.%N; }
echo "machine: $(nproc) cores, load $(cut -d' ' -f1-3 /proc/loadavg); inimtrace $(git rev-parse --short HEAD 2>/dev/null || echo '?')"

t0=$(now)
"$BIN" --quiet sweep "$SWEEP" --out "$OUT/local" >"$OUT/local.txt" 2>"$OUT/local.log"
t1=$(now)
local_s=$(echo "$t1 - $t0" | bc -l)
printf 'sweep, local:  %7.1f s for 48 points (%.2f s per point)\n' "$local_s" "$(echo "$local_s / 48" | bc -l)"

python3 - "$OUT" "$BIN" <<'EOF'
import json, subprocess, sys, time, csv, os
out, binary = sys.argv[1], sys.argv[2]
sweep = json.load(open(f"{out}/local/sweep.json"))
eye_work, display_work, walls = 0.0, None, []
for p in sweep["points"]:
    d = f"{out}/assess/{p['index']}"
    t = time.time()
    subprocess.run([binary, "--quiet", "assess", sweep["experiment_file"], "--out", d] + p["assess_args"],
                   check=True, stdout=subprocess.DEVNULL)
    walls.append(time.time() - t)
    stages = {}
    for row in csv.DictReader(open(f"{d}/results.csv")):
        if row["record"] == "stage":
            stages[row["stage"]] = stages.get(row["stage"], 0.0) + float(row["seconds"])
    eye_work += sum(stages.get(s, 0.0) for s in ("ground_truth", "simulate_all_methods", "metrics"))
    if display_work is None:
        display_work = stages.get("render_display", 0.0) + stages.get("pack_display_images", 0.0)
    subprocess.run(["rm", "-rf", d])
work = display_work + eye_work
local = float(open(f"{out}/local.log").read().split(" run in ")[1].split(" s")[0])
print(f"bare assess:   {sum(walls):7.1f} s for 48 runs ({sum(walls)/48:.2f} s per point, images included)")
print(f"same work in assess: {work:.1f} s (display images once {display_work:.2f} s + per point ground truth, "
      f"perceived images, metrics {eye_work/48:.3f} s)")
print(f"sweep points (its own timer): {local:.1f} s; overhead per point {(local - work)/48*1000:+.1f} ms "
      f"({(local/work - 1)*100:+.1f}% of the work)")
EOF

if scripts/slurm-local.sh status >/dev/null 2>&1 || sinfo >/dev/null 2>&1; then
    t0=$(now)
    "$BIN" --quiet sweep "$SWEEP" --out "$OUT/slurm" --slurm --wait --array-max 4 --cpus-per-task 1 \
        >"$OUT/slurm.txt" 2>"$OUT/slurm.log"
    t1=$(now)
    slurm_s=$(echo "$t1 - $t0" | bc -l)
    printf 'sweep, Slurm:  %7.1f s for 48 points (array of 4 tasks, 1 core each; submit to collected)\n' "$slurm_s"
    sed 's/,[^,]*$//' "$OUT/local/sweep.csv" >"$OUT/a.csv"    # without the seconds
    sed 's/,[^,]*$//' "$OUT/slurm/sweep.csv" >"$OUT/b.csv"
    if cmp -s "$OUT/a.csv" "$OUT/b.csv"; then echo "sweep.csv: Slurm and local identical (apart from seconds)"; else echo "sweep.csv: Slurm and local DIFFER"; fi
else
    echo "Slurm: no cluster answers (scripts/slurm-local.sh start brings up one); skipped"
fi
