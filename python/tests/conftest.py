"""Shared fixtures of the Python package's tests: the CLI binary that cargo built (the reference
for the bit-for-bit checks), an independent EXR reader (OpenEXR's Python bindings), and small
settings so that every test runs in seconds."""

import json
import os
import subprocess
from pathlib import Path

import numpy as np
import pytest

ROOT = Path(__file__).resolve().parents[2]

# Small sizes: a 540 x 540 LCD (same optics, a quarter of the pixels), a 64 x 64 retina and a
# 4 x 4 pupil grid.
SMALL_LCD = [540, 540]
SMALL_DISPLAY = {"display.lcd.resolution": SMALL_LCD}
SMALL_DISPLAY_ARGS = ["--set", "display.lcd.resolution=[540, 540]"]
RETINA = 64
PUPIL_GRID = 4


@pytest.fixture(scope="session")
def cli():
    """Runs the `inimtrace` binary built by `cargo build --release` (or $INIMTRACE_CLI)."""
    exe = Path(os.environ.get("INIMTRACE_CLI", ROOT / "target" / "release" / "inimtrace"))
    if not exe.exists():
        pytest.fail(f"no CLI binary at {exe}: run `cargo build --release` first (or set INIMTRACE_CLI)")

    def run(*args, check=True):
        r = subprocess.run([str(exe), "--quiet", *map(str, args)], capture_output=True, text=True, cwd=ROOT)
        if check and r.returncode != 0:
            raise AssertionError(f"inimtrace {' '.join(map(str, args))} failed: {r.stderr}")
        return r

    return run


def read_exr(path):
    """RGB as a (rows, columns, 3) float32 array and Z as (rows, columns) or None, read by
    OpenEXR's own Python bindings (not by inimtrace)."""
    import OpenEXR

    with OpenEXR.File(str(path)) as f:
        ch = f.channels()
        rgb = np.ascontiguousarray(ch["RGB"].pixels, dtype=np.float32)
        z = ch.get("Z")
        return rgb, (None if z is None else np.ascontiguousarray(z.pixels, dtype=np.float32))


def same_bits(a, b):
    """Equal bit for bit (so +inf equals +inf, and 0.0 differs from -0.0)."""
    a, b = np.asarray(a), np.asarray(b)
    return a.shape == b.shape and a.dtype == b.dtype and np.array_equal(a.view(np.uint32), b.view(np.uint32))


def load_json(path):
    return json.loads(Path(path).read_text())
