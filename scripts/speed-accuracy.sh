#!/usr/bin/env bash
# Regenerates the speed-and-accuracy report docs/SPEED.md in one command: builds the release
# binary, runs the full `inimtrace bench` (the paper's scene and display at the paper's sizes;
# several minutes), copies its reports and plots to docs/bench/, and replaces the block of
# docs/SPEED.md between the `speed-accuracy:begin` and `speed-accuracy:end` markers with
# docs/bench/summary.md. Commit first: the reports name the git revision they measured (`-dirty`
# when the tree had uncommitted changes).
# Usage: scripts/speed-accuracy.sh [extra `inimtrace bench` arguments, e.g. --threads 2]
set -euo pipefail
cd "$(dirname "$0")/.."
page=docs/SPEED.md
for m in begin end; do
    grep -q "<!-- speed-accuracy:$m" "$page" || { echo "$page lacks the speed-accuracy:$m marker" >&2; exit 1; }
done
cargo build --release --quiet
out=out/bench
docs=docs/bench
rm -rf "$out"
mkdir -p "$out" "$docs"
SECONDS=0
target/release/inimtrace bench --quiet --out "$out" "$@" > "$out/stdout.md"
echo "inimtrace bench: ${SECONDS} s wall" >&2
for f in bench.md summary.md bench.csv builds.csv bench.json \
    speed_psnr speed_ssim la_grid pupil_grid retina_samples precision; do
    case $f in
        *.*) cp "$out/$f" "$docs/" ;;
        *) cp "$out/$f.png" "$out/$f.svg" "$docs/" ;;
    esac
done
awk -v f="$docs/summary.md" '
    /<!-- speed-accuracy:begin/ { print; while ((getline line < f) > 0) print line; skip = 1; next }
    /<!-- speed-accuracy:end/ { skip = 0 }
    !skip { print }' "$page" > "$page.new"
mv "$page.new" "$page"
echo "wrote $docs/ and the generated block of $page" >&2
