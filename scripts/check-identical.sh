#!/usr/bin/env bash
# Shows that two revisions produce identical outputs: the same pixels (bit for bit, every channel of
# every EXR), the same EXR attributes, the same PNGs, tables and scores.
#
#   scripts/check-identical.sh BASE [HEAD]
#
# BASE and HEAD are git revisions; HEAD defaults to the working tree. Each is built in release mode
# (in a temporary worktree, with its own target directory under target/identical/) and runs
# `inimtrace assess` on experiments/paper.toml and experiments/framework-2020.toml from its own
# tree. EXR files are compared decoded (pixels and `inimtrace:*` attributes), not byte for byte:
# the order of attributes in an EXR header is not part of its content. Needs python3 with venv
# (Debian: python3-venv); OpenEXR's own Python bindings and NumPy are installed into
# target/identical/venv on first use. Exits 0 when everything is identical, 1 otherwise.
set -euo pipefail
top=$(git rev-parse --show-toplevel)
cd "$top"
base=${1:?usage: scripts/check-identical.sh BASE [HEAD]}
head=${2:-}
work="$top/target/identical"
mkdir -p "$work"
experiments=(paper framework-2020)

# build_and_run NAME TREE TARGET_DIR: builds TREE and writes its outputs to $work/out-NAME/<experiment>.
build_and_run() {
    local name=$1 tree=$2 target=$3
    (cd "$tree" && CARGO_TARGET_DIR="$target" cargo build --release --quiet --bin inimtrace)
    rm -rf "$work/out-$name"
    for e in "${experiments[@]}"; do
        (cd "$tree" && "$target/release/inimtrace" --quiet assess "experiments/$e.toml" --out "$work/out-$name/$e" >/dev/null)
    done
}

checkout() { # checkout NAME REV -> prints the worktree path
    local dir="$work/tree-$1"
    git worktree remove --force "$dir" >/dev/null 2>&1 || rm -rf "$dir"
    git worktree add --quiet --detach "$dir" "$2"
    echo "$dir"
}

build_and_run base "$(checkout base "$base")" "$work/target-base"
if [ -n "$head" ]; then
    build_and_run head "$(checkout head "$head")" "$work/target-head"
else
    build_and_run head "$top" "$top/target"
fi

if [ ! -x "$work/venv/bin/python" ]; then
    python3 -m venv "$work/venv"
    "$work/venv/bin/pip" install --quiet OpenEXR numpy
fi

"$work/venv/bin/python" - "$work/out-base" "$work/out-head" <<'PY'
import hashlib, pathlib, sys
import numpy as np
import OpenEXR

base, head = map(pathlib.Path, sys.argv[1:3])
problems = []
names = sorted({p.relative_to(base) for p in base.rglob("*") if p.is_file()} |
               {p.relative_to(head) for p in head.rglob("*") if p.is_file()})
checked = 0
for rel in names:
    a, b = base / rel, head / rel
    if not a.exists() or not b.exists():
        problems.append(f"{rel}: only in {'head' if b.exists() else 'base'}")
        continue
    checked += 1
    if rel.suffix == ".exr":
        with OpenEXR.File(str(a)) as fa, OpenEXR.File(str(b)) as fb:
            ha = {k: v for k, v in fa.header().items() if k.startswith("inimtrace:")}
            hb = {k: v for k, v in fb.header().items() if k.startswith("inimtrace:")}
            if ha != hb:
                problems.append(f"{rel}: attributes differ: {sorted(set(ha.items()) ^ set(hb.items()))}")
            ca, cb = fa.channels(), fb.channels()
            if ca.keys() != cb.keys():
                problems.append(f"{rel}: channels {list(ca)} vs {list(cb)}")
                continue
            for k in ca:
                pa, pb = ca[k].pixels, cb[k].pixels
                if pa.shape != pb.shape or pa.dtype != pb.dtype or not np.array_equal(
                        pa.view(np.uint8), pb.view(np.uint8)):
                    problems.append(f"{rel}: channel {k} pixels differ")
    elif rel.name == "results.csv":
        rows = lambda p: [l for l in p.read_text().splitlines() if not l.startswith("stage,")]
        if rows(a) != rows(b):
            problems.append(f"{rel}: score rows differ")
    elif rel.name == "results.json":
        continue  # holds wall times; its scores are the CSV's
    elif hashlib.sha256(a.read_bytes()).digest() != hashlib.sha256(b.read_bytes()).digest():
        problems.append(f"{rel}: contents differ")
for p in problems:
    print("DIFFERENT", p)
print(f"{checked} files compared, {len(problems)} differences")
sys.exit(1 if problems else 0)
PY
