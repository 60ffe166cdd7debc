"""On a CPU without the instructions the build assumes (x86-64-v3, `.cargo/config.toml`) but with
AVX, importing the module raises an ImportError that says so, instead of killing Python with
"illegal instruction": Python run under qemu-user emulating older CPUs (Debian's `qemu-user`;
skipped, saying so, without it unless INIMTRACE_REQUIRE_QEMU is set, as in CI)."""

import os
import platform
import shutil
import subprocess
import sys

import pytest

CHECK = (
    "try:\n"
    "    import inimtrace\n"
    "    print('imported')\n"
    "except ImportError as e:\n"
    "    print('ImportError:', e)\n"
)


def import_on(cpu):
    qemu = shutil.which("qemu-x86_64")
    if qemu is None:
        assert "INIMTRACE_REQUIRE_QEMU" not in os.environ, "INIMTRACE_REQUIRE_QEMU is set: no qemu-x86_64"
        pytest.skip("qemu-x86_64 (Debian's qemu-user) is not installed")
    out = subprocess.run([qemu, "-cpu", cpu, sys.executable, "-c", CHECK], capture_output=True, text=True, timeout=300)
    return out.returncode, out.stdout.strip()


@pytest.mark.skipif(platform.machine() != "x86_64" or sys.platform != "linux", reason="x86_64 Linux only")
def test_an_older_cpu_gets_an_import_error_saying_why():
    # The emulation itself works: a CPU with everything x86-64-v3 has imports the module.
    code, out = import_on("Haswell-noTSX")
    assert (code, out) == (0, "imported")
    # Sandy Bridge has AVX but not AVX2, FMA or BMI. (A CPU without even AVX, before 2011, stops
    # in PyO3's module set-up, which runs before the check: the CLI covers those, tests/cpu.rs.)
    code, out = import_on("SandyBridge")
    assert code == 0, out
    assert out.startswith("ImportError: this inimtrace was built for x86-64-v3 CPUs"), out
    assert "target-cpu=native" in out, out
