#!/usr/bin/env bash
# Times the whole default experiment and framework-2020.toml (wall time: median of runs with
# hyperfine; peak memory with /usr/bin/time -v). Needs: apt-get install hyperfine time
set -euo pipefail
cd "$(dirname "$0")/.."
cargo build --release --quiet
bin=target/release/inimtrace
hyperfine --warmup 1 --runs "${RUNS:-10}" --export-markdown /dev/stdout \
    "$bin assess --quiet --out /tmp/inimtrace-bench/paper" \
    "$bin assess experiments/framework-2020.toml --quiet --out /tmp/inimtrace-bench/fw"
for e in "" experiments/framework-2020.toml; do
    /usr/bin/time -v "$bin" assess $e --quiet --out /tmp/inimtrace-bench/mem 2>&1 | grep -E "Maximum resident|Elapsed" | sed "s|^|${e:-paper}: |"
done
"$bin" assess --quiet --timings --out /tmp/inimtrace-bench/paper 2>&1 >/dev/null
