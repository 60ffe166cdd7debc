#!/usr/bin/env bash
# Sweeps samples per retina pixel, samples per display pixel and the pupil diameter around the
# paper's stated settings, and prints the PSNR (mean of channels) of every variant as a Markdown
# table next to the paper's Table 1. Usage: scripts/sweep-table1.sh [OUTDIR]   (about a minute)
set -euo pipefail
cd "$(dirname "$0")/.."
out=${1:-out/sweep-table1}
mkdir -p "$out"
cargo build --release --quiet
bin=target/release/inimtrace
root=$PWD
variant() { # name, sed expression applied to experiments/paper.toml
    sed -e "s#\.\./scenes#$root/scenes#; s#\.\./displays#$root/displays#; s/^name = \"paper\"/name = \"$1\"/" \
        experiments/paper.toml | sed "$2" > "$out/$1.toml"
    "$bin" assess "$out/$1.toml" --out "$out/$1" --quiet > /dev/null
}
variant stated 's/^x//'
variant retina4x4 's/retina_samples = 1 /retina_samples = 4 /'
variant display2x2 's/samples_per_pixel = 1 /samples_per_pixel = 2 /'
variant retina4x4-display2x2 's/retina_samples = 1 /retina_samples = 4 /; s/samples_per_pixel = 1 /samples_per_pixel = 2 /'
variant pupil2mm 's/pupil_diameter = 5.0/pupil_diameter = 2.0/'
variant pupil2mm-retina4x4-display2x2 's/pupil_diameter = 5.0/pupil_diameter = 2.0/; s/retina_samples = 1 /retina_samples = 4 /; s/samples_per_pixel = 1 /samples_per_pixel = 2 /'
python3 - "$out" <<'PY'
import json, sys, os
out = sys.argv[1]
paper = {"Pin": (21.48, 22.31, 22.87), "Near": (24.08, 20.85, 24.13), "Cen": (24.06, 22.17, 24.36), "Far": (24.77, 21.54, 24.90)}
names = ["stated", "retina4x4", "display2x2", "retina4x4-display2x2", "pupil2mm", "pupil2mm-retina4x4-display2x2"]
print("| settings | " + " | ".join(f"{c} LC / PC / LA" for c in paper) + " | mean abs. diff. to paper (dB) |")
print("|---|" + "---|" * (len(paper) + 1))
print("| paper's Table 1 | " + " | ".join(" / ".join(f"{v:.2f}" for v in paper[c]) for c in paper) + " | 0 |")
for n in names:
    r = json.load(open(os.path.join(out, n, "results.json")))
    s = {(x["eye_case"], x["method"]): x["psnr"]["mean"] for x in r["scores"]}
    cells, diffs = [], []
    for c in paper:
        vals = [s[(c, m)] for m in ("LC", "PC", "LA")]
        diffs += [abs(a - b) for a, b in zip(vals, paper[c])]
        cells.append(" / ".join(f"{v:.2f}" for v in vals))
    print(f"| {n} | " + " | ".join(cells) + f" | {sum(diffs)/len(diffs):.2f} |")
PY
