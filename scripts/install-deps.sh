#!/usr/bin/env sh
# Installs the Debian 12 packages inimtrace needs (run as root, or with sudo available).
#   scripts/install-deps.sh            everything below
#   scripts/install-deps.sh packages   the Debian packages only (enough to build)
#   scripts/install-deps.sh extras     the rest: the Python venvs under target/ and Embree 4 (only
#                                      tests and `--features embree4` need them; CI fetches them
#                                      while the first build compiles)
#   libembree-dev libclang-dev   Embree backend: bindgen over wrapper.h, libembree3 (+ TBB)
#   glmark2-data                 the Stanford bunny mesh for scenes/bunny.toml
#   assimp-testmodels            tests/assimp_corpus.rs: Assimp's test models (a real third-party
#                                corpus of OBJ, PLY, STL and glTF files) must render or be refused
#                                in one line
#   pkg-config libfontconfig1-dev libfreetype-dev fontconfig fonts-dejavu-core
#                                plotters' text rendering (figure labels, plots)
#   build-essential              C toolchain for crates that build C
#   mold                         a fast linker: CI links its two builds of the ~80 test binaries with
#                                it (`mold -run` in .ci/run); plain builds use the default linker
#   slurm-wlm munge              `inimtrace sweep --slurm` and its tests: scripts/slurm-local.sh runs
#                                a single-node Slurm cluster on this machine
#   qemu-user                    tests/cpu.rs and python/tests: the binary and the Python module
#                                on emulated older CPUs say what they lack (no "illegal instruction")
#   (no package)                 `cargo build --features embree4` needs Embree 4, which Debian 12 lacks:
#                                scripts/embree4-from-wheel.sh puts the library of PyPI's `embreex`
#                                wheel into target/embree4/ when the system has no libembree4.so
#                                (only a warning when PyPI cannot be reached)
#   openexr                      exrheader, OpenEXR's own tool: tests/exr_output.rs checks that it
#                                reads every numeric attribute of our EXRs as a number
#   time util-linux              tests/memory_limits.rs: /usr/bin/time -v measures a run's peak
#                                memory, prlimit caps its address space
#   python3-venv                 a venv under target/venv-exr with OpenEXR's Python bindings
#                                (pip: OpenEXR numpy), with which tests/exr_output.rs checks
#                                that other tools read our EXR files; skipped with a warning
#                                when pip cannot reach PyPI (the test then skips too); and the
#                                venvs the Python package installs into (`pip install .` builds
#                                it with maturin from PyPI and this Rust toolchain; no headers
#                                needed: the module uses CPython's stable ABI, abi3)
#   chromium                     tests/report_html.rs: a real browser (headless, driven over the
#                                DevTools protocol by scripts/browse-report.py with Python's standard
#                                library alone) opens the report.html of an assess, a resolution and a
#                                sweep run
#   (pip, no package)            target/venv-perception: the perceptual metrics' reference
#                                implementations for tests/perception_reference.rs, NVIDIA's FLIP
#                                (flip-evaluator) and the authors' ColorVideoVDP (cvvdp, with PyTorch:
#                                about 6 GB and two minutes); skipped with a warning when pip cannot
#                                reach PyPI (the test then skips too, unless CI requires it)
set -eu
STAGE=${1:-all}
case "$STAGE" in
    all | packages | extras) ;;
    *) echo "usage: scripts/install-deps.sh [packages | extras]" >&2; exit 2 ;;
esac
SUDO=""
if [ "$(id -u)" != 0 ]; then SUDO=sudo; fi
export DEBIAN_FRONTEND=noninteractive
if [ "$STAGE" != extras ]; then
    $SUDO apt-get update
    $SUDO apt-get install -y --no-install-recommends \
        build-essential pkg-config libembree-dev libclang-dev glmark2-data assimp-testmodels \
        libfontconfig1-dev libfreetype-dev fontconfig fonts-dejavu-core python3-venv slurm-wlm munge qemu-user \
        time util-linux openexr chromium mold
fi
if [ "$STAGE" = packages ]; then exit 0; fi
cd "$(dirname "$0")/.."
if [ ! -x target/venv-exr/bin/python ] || ! target/venv-exr/bin/python -c "import OpenEXR, numpy" 2>/dev/null; then
    mkdir -p target
    { python3 -m venv target/venv-exr && target/venv-exr/bin/pip install --quiet OpenEXR numpy; } \
        || echo "warning: could not install OpenEXR's Python bindings; tests/exr_output.rs will skip its OpenEXR check" >&2
fi
if [ ! -x target/venv-perception/bin/python ] \
    || ! target/venv-perception/bin/python -c "import flip_evaluator, pycvvdp, numpy" 2>/dev/null; then
    mkdir -p target
    { python3 -m venv target/venv-perception \
        && target/venv-perception/bin/pip install --quiet numpy flip-evaluator cvvdp; } \
        || echo "warning: could not install flip-evaluator and cvvdp; tests/perception_reference.rs will skip" >&2
fi
if ! ldconfig -p 2>/dev/null | grep -q 'libembree4\.so '; then
    scripts/embree4-from-wheel.sh \
        || echo "warning: could not fetch Embree 4 into target/embree4; \`--features embree4\` builds need EMBREE4_DIR" >&2
fi
