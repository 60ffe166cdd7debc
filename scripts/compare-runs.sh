#!/usr/bin/env bash
# Shows that two inimtrace binaries produce the same outputs: every experiment in experiments/,
# every study in studies/ and sweeps/tiny.toml, run by each binary from this tree's files, then
# compared: EXR files decoded (every channel's pixels bit for bit, every `inimtrace:*` attribute but
# the build's own version and revision), CSV and JSON rows with their timing, host and build
# columns left out, report.html with its numbers masked (it is built from the files compared),
# every other file byte for byte.
#
#   scripts/compare-runs.sh OLD_BIN NEW_BIN [NAME...]
#
# NEW_BIN `-` only runs OLD_BIN (its outputs are kept for a later comparison).
# NAME picks runs by name (`paper`, `studies/paper`, `sweeps/tiny`); none: all of them. Outputs go
# to target/compare-runs/{old,new}/; a run already there is reused when its binary is unchanged
# (delete the folder to run again). Runs use --quiet and 2 threads (INIMTRACE_THREADS to change).
# Needs python3 with venv (Debian: python3-venv); OpenEXR's Python bindings and NumPy are installed
# into target/compare-runs/venv on first use. Exits 0 when everything is the same, 1 otherwise.
set -euo pipefail
top=$(git rev-parse --show-toplevel)
cd "$top"
old=$(realpath "${1:?usage: scripts/compare-runs.sh OLD_BIN NEW_BIN [NAME...]}")
new=${2:?usage: scripts/compare-runs.sh OLD_BIN NEW_BIN [NAME...]}
[ "$new" = - ] || new=$(realpath "$new")
shift 2
threads=${INIMTRACE_THREADS:-2}
work="$top/target/compare-runs"
mkdir -p "$work"

runs=()
for f in experiments/*.toml; do runs+=("$(basename "$f" .toml)"); done
for f in studies/*.toml; do runs+=("studies/$(basename "$f" .toml)"); done
runs+=("sweeps/tiny")
if [ $# -gt 0 ]; then runs=("$@"); fi

# run_one BIN SIDE RUN: writes RUN's outputs to $work/SIDE/RUN (skipped when done by the same binary).
run_one() {
    local bin=$1 side=$2 run=$3 out="$work/$2/$3"
    local stamp
    stamp=$(sha256sum "$bin" | cut -d' ' -f1)
    if [ -f "$out/.done" ] && [ "$(cat "$out/.done")" = "$stamp" ]; then
        return
    fi
    rm -rf "$out"
    mkdir -p "$out"
    case "$run" in
    studies/*) "$bin" --quiet --threads "$threads" resolution "$run.toml" --out "$out" >/dev/null ;;
    sweeps/*) "$bin" --quiet --threads "$threads" sweep "$run.toml" --out "$out" >/dev/null ;;
    *) "$bin" --quiet --threads "$threads" assess "experiments/$run.toml" --out "$out" >/dev/null ;;
    esac
    echo "$stamp" >"$out/.done"
}

for run in "${runs[@]}"; do
    echo "running $run" >&2
    run_one "$old" old "$run"
    [ "$new" = - ] || run_one "$new" new "$run"
done
[ "$new" != - ] || exit 0

if [ ! -x "$work/venv/bin/python" ]; then
    python3 -m venv "$work/venv"
    "$work/venv/bin/pip" install --quiet OpenEXR numpy
fi

"$work/venv/bin/python" - "$work/old" "$work/new" "${runs[@]}" <<'PY'
import csv, hashlib, io, json, pathlib, re, sys
import numpy as np
import OpenEXR

old_root, new_root = map(pathlib.Path, sys.argv[1:3])
runs = sys.argv[3:]
# Keys and columns that record when, where, how fast or by which build a run ran.
VOLATILE = re.compile(r"(seconds|time|elapsed|duration|host|unix|date|version|revision|git|threads|"
                      r"per_second|rate|throughput|memory|rss|finished|started)", re.I)
VOLATILE_ATTRS = {"inimtrace:version", "inimtrace:git_revision", "inimtrace:revision"}


def strip(v):
    if isinstance(v, dict):
        # A listed output file's size and checksum follow its header (the build's revision);
        # the file itself is compared on its own.
        if "crc32" in v and "bytes" in v:
            v = {k: x for k, x in v.items() if k not in ("crc32", "bytes", "sha256")}
        return {k: strip(x) for k, x in v.items() if not VOLATILE.search(k)}
    if isinstance(v, list):
        return [strip(x) for x in v]
    return v


def csv_rows(p):
    rows = list(csv.reader(io.StringIO(p.read_text())))
    if not rows:
        return rows
    keep = [i for i, h in enumerate(rows[0]) if not VOLATILE.search(h)]
    # results.csv holds stage timings as rows starting with "stage".
    return [[r[i] for i in keep if i < len(r)] for r in rows if not (r and r[0] == "stage")]


problems, checked = [], 0
for run in runs:
    a_dir, b_dir = old_root / run, new_root / run
    names = sorted({p.relative_to(a_dir) for p in a_dir.rglob("*") if p.is_file()} |
                   {p.relative_to(b_dir) for p in b_dir.rglob("*") if p.is_file()})
    for rel in names:
        if rel.name == ".done" or rel.suffix in (".png", ".svg", ".log") or "logs" in rel.parts:
            continue  # plots and previews carry timings or fonts; their data are the CSV/JSON/EXR
        a, b = a_dir / rel, b_dir / rel
        where = f"{run}/{rel}"
        if not a.exists() or not b.exists():
            problems.append(f"{where}: only in {'new' if b.exists() else 'old'}")
            continue
        checked += 1
        if rel.suffix == ".exr":
            with OpenEXR.File(str(a), separate_channels=True) as fa, OpenEXR.File(str(b), separate_channels=True) as fb:
                for part, (pa_, pb_) in enumerate(zip(fa.parts, fb.parts)):
                    ha = {k: str(v) for k, v in pa_.header.items() if k.startswith("inimtrace:") and k not in VOLATILE_ATTRS}
                    hb = {k: str(v) for k, v in pb_.header.items() if k.startswith("inimtrace:") and k not in VOLATILE_ATTRS}
                    ha = {k: v for k, v in ha.items() if not VOLATILE.search(k)}
                    hb = {k: v for k, v in hb.items() if not VOLATILE.search(k)}
                    if ha != hb:
                        diff = sorted(k for k in set(ha) | set(hb) if ha.get(k) != hb.get(k))
                        problems.append(f"{where} part {part}: attributes differ: {diff}")
                    ca, cb = pa_.channels, pb_.channels
                    if ca.keys() != cb.keys():
                        problems.append(f"{where} part {part}: channels {sorted(ca)} vs {sorted(cb)}")
                        continue
                    for k in ca:
                        x, y = ca[k].pixels, cb[k].pixels
                        if x.shape != y.shape or x.dtype != y.dtype or not np.array_equal(x.view(np.uint8), y.view(np.uint8)):
                            problems.append(f"{where} part {part}: channel {k} pixels differ")
                if len(fa.parts) != len(fb.parts):
                    problems.append(f"{where}: {len(fa.parts)} parts vs {len(fb.parts)}")
        elif rel.suffix == ".csv":
            if csv_rows(a) != csv_rows(b):
                problems.append(f"{where}: rows differ")
        elif rel.suffix == ".json":
            ja, jb = strip(json.loads(a.read_text())), strip(json.loads(b.read_text()))
            if ja != jb:
                problems.append(f"{where}: values differ")
        elif rel.suffix in (".md", ".txt"):
            # Tables may print timings: compare the lines without digits-with-units of time.
            t = lambda p: [l for l in p.read_text().splitlines() if not re.search(r"\d\s*(s|ms|min)\b|seconds|time", l)]
            if t(a) != t(b):
                problems.append(f"{where}: text differs")
        elif rel.name == "report.html":
            # The page is built from the files compared above, and prints the run's timings and
            # the sizes and hashes of files that hold timings: its text with every number masked.
            t = lambda p: re.sub(r"[0-9a-f]{8,}|\d+(\.\d+)?", "#", p.read_text())
            if t(a) != t(b):
                problems.append(f"{where}: text differs beyond its numbers")
        elif hashlib.sha256(a.read_bytes()).digest() != hashlib.sha256(b.read_bytes()).digest():
            problems.append(f"{where}: contents differ")
for p in problems:
    print("DIFFERENT", p)
print(f"{checked} files compared over {len(runs)} runs, {len(problems)} differences")
sys.exit(1 if problems else 0)
PY
