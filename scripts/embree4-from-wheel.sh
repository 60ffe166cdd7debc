#!/usr/bin/env sh
# Puts Intel Embree 4 (4.4.0, with its TBB) into target/embree4/ for `cargo build --features embree4`
# on a system without its own Embree 4 (Debian 12 ships only Embree 3). The library comes from
# the `embreex` wheel on PyPI (manylinux_2_28, x86-64), pinned by version and sha256: downloaded
# with pip, checked, unpacked, its embreex.libs/ copied, and libembree4.so / libembree4.so.4
# linked to the library for the linker. build.rs finds target/embree4/ and gives the binaries
# an rpath to it, so no LD_LIBRARY_PATH is needed. Exits non-zero when it cannot (no pip, no
# PyPI, wrong checksum); scripts/install-deps.sh then only warns.
set -eu
cd "$(dirname "$0")/.."
WHEEL=embreex-4.4.0.post1-cp311-cp311-manylinux_2_27_x86_64.manylinux_2_28_x86_64.whl
SHA256=2cd0f7d5c6342e6247e31f700761689cae7829454d8c6de0c41e62124a023e1f
DEST=target/embree4
if [ -e "$DEST/libembree4.so" ] && [ -e "$DEST/.from-$SHA256" ]; then
    echo "Embree 4 already in $DEST"
    exit 0
fi
if [ "$(uname -m)" != x86_64 ]; then
    echo "error: the embreex wheel is for x86-64 Linux; set EMBREE4_DIR to an Embree 4 install instead" >&2
    exit 1
fi
TMP=$(mktemp -d)
trap 'rm -rf "$TMP"' EXIT
# pip from a throwaway venv (Debian's python3 has no pip of its own; python3-venv brings one).
# The wheel's platform and interpreter are pinned so that every machine gets this same file.
python3 -m venv "$TMP/venv"
"$TMP/venv/bin/python" -m pip download --quiet --no-deps --only-binary=:all: --dest "$TMP" \
    --platform manylinux_2_28_x86_64 --python-version 3.11 --implementation cp --abi cp311 \
    embreex==4.4.0.post1
echo "$SHA256  $TMP/$WHEEL" | sha256sum -c --quiet -
python3 -m zipfile -e "$TMP/$WHEEL" "$TMP/unpacked"
LIB=$(cd "$TMP/unpacked/embreex.libs" && ls libembree4-*.so.4)
mkdir -p "$DEST"
rm -f "$DEST"/lib*.so*
cp "$TMP/unpacked/embreex.libs/"lib*.so* "$DEST/"
ln -s "$LIB" "$DEST/libembree4.so.4"
ln -s "$LIB" "$DEST/libembree4.so"
rm -f "$DEST"/.from-*
touch "$DEST/.from-$SHA256"
echo "Embree 4.4.0 from the embreex wheel is in $DEST ($LIB)"
