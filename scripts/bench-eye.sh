#!/usr/bin/env bash
# The schematic eye's cost: experiments/navarro.toml (Navarro 1985, polychromatic, converged)
# against experiments/paper-converged.toml (the thin lens, same targets), run alternately
# (RUNS times each, default 2) with the same thread count (THREADS, default 2). Prints each run's
# wall and CPU seconds and peak memory (/usr/bin/time -v), then the ratios of the medians.
# Needs: apt-get install time
set -euo pipefail
cd "$(dirname "$0")/.."
cargo build --release --quiet
bin=target/release/inimtrace
out=$(mktemp -d /tmp/inimtrace-bench-eye.XXXXXX)
echo "load before: $(uptime)"
for i in $(seq "${RUNS:-2}"); do
    for e in paper-converged navarro; do
        /usr/bin/time -v "$bin" --quiet assess "experiments/$e.toml" --threads "${THREADS:-2}" \
            --out "$out/$e" >/dev/null 2>"$out/$e-$i.time"
        awk -v e="$e" -F': ' '/Elapsed/ { n = split($2, t, ":"); wall = n == 3 ? t[1] * 3600 + t[2] * 60 + t[3] : t[1] * 60 + t[2] }
            /User time/ { user = $2 } /System time/ { sys = $2 } /Maximum resident/ { mem = $2 }
            END { printf "%s %.2f %.2f %d\n", e, wall, user + sys, mem }' "$out/$e-$i.time" >>"$out/runs"
    done
done
echo "load after: $(uptime)"
echo "experiment wall_s cpu_s peak_kb"
cat "$out/runs"
awk '{ w[$1] = w[$1] " " $2; c[$1] = c[$1] " " $3; m[$1] = m[$1] " " $4 }
    function median(s,   a, n, i, j, t) { n = split(s, a, " ");
        for (i = 1; i <= n; i++) for (j = i + 1; j <= n; j++) if (a[j] < a[i]) { t = a[i]; a[i] = a[j]; a[j] = t }
        return n % 2 ? a[(n + 1) / 2] : (a[n / 2] + a[n / 2 + 1]) / 2 }
    END { printf "navarro / paper-converged (medians): wall %.2fx, CPU %.2fx, peak memory %.2fx\n",
        median(w["navarro"]) / median(w["paper-converged"]), median(c["navarro"]) / median(c["paper-converged"]),
        median(m["navarro"]) / median(m["paper-converged"]) }' "$out/runs"
