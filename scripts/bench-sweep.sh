#!/usr/bin/env bash
# Times sweeps/pupil-focus.toml (the paper's experiment for one eye: 6 pupils x 8 focus
# distances, 48 points) and prints the sweep's overhead per point:
#   1. `inimtrace sweep` on all cores of this machine, and the same 48 points as bare
#      `inimtrace assess` runs (each point's --set arguments from sweep.json; images included);
#   2. the overhead: points 0..8 on one thread (`--threads 1`, so that other load and the
#      scheduling of concurrent points do not blur it) against the same work timed inside
#      8 one-thread `assess` runs: the display images once, then per point the ground truth,
#      the perceived images and the metrics;
#   3. the sweep through Slurm (`--slurm --wait`, 4 tasks of 1 core) when a cluster answers
#      (scripts/slurm-local.sh), and whether its sweep.csv equals the local one.
# Usage: scripts/bench-sweep.sh [OUT]   (default out/bench-sweep; needs python3 and bc)
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

python3 - "$OUT" "$BIN" "$SWEEP" <<'EOF'
import json, subprocess, sys, time, csv
out, binary, sweep_file = sys.argv[1:4]
sweep = json.load(open(f"{out}/local/sweep.json"))

def assess(p, threads=None):
    d = f"{out}/assess/{p['index']}"
    cmd = [binary, "--quiet"] + (["--threads", str(threads)] if threads else [])
    t = time.time()
    subprocess.run(cmd + ["assess", sweep["experiment_file"], "--out", d] + p["assess_args"],
                   check=True, stdout=subprocess.DEVNULL)
    wall = time.time() - t
    stages = {}
    for row in csv.DictReader(open(f"{d}/results.csv")):
        if row["record"] == "stage":
            stages[row["stage"]] = stages.get(row["stage"], 0.0) + float(row["seconds"])
    subprocess.run(["rm", "-rf", d])
    eye = sum(stages.get(s, 0.0) for s in ("ground_truth", "simulate_all_methods", "metrics"))
    return wall, stages.get("render_display", 0.0) + stages.get("pack_display_images", 0.0), eye

walls = [assess(p)[0] for p in sweep["points"]]
print(f"bare assess:   {sum(walls):7.1f} s for 48 runs ({sum(walls)/48:.2f} s per point, images included)")

n = 8
runs = [assess(p, threads=1) for p in sweep["points"][:n]]
work = runs[0][1] + sum(r[2] for r in runs)
log = subprocess.run([binary, "--quiet", "--threads", "1", "sweep", sweep_file, "--out", f"{out}/one-thread",
                      "--points", f"0..{n}"], check=True, capture_output=True, text=True).stderr
points = float(log.split(" run in ")[1].split(" s")[0])
print(f"one thread, points 0..{n}: sweep {points:.2f} s; the same work in assess {work:.2f} s "
      f"(display images once {runs[0][1]:.2f} s + per point {(work - runs[0][1]) / n:.3f} s)")
print(f"overhead per point: {(points - work) / n * 1000:+.1f} ms ({(points / work - 1) * 100:+.1f}% of the work)")
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
