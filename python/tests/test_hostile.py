"""Hostile inputs to the Python package: values that once crashed or hung the interpreter.
Each case that could kill the interpreter runs in a child Python, so that a crash fails the test
(a negative return code names the signal) instead of ending the test run.

- `set=` values that contain themselves or nest too deep are a ValueError, not a SIGSEGV.
- Ctrl-C (SIGINT) during any long call raises KeyboardInterrupt within a second, and the module
  works afterwards.
- NumPy's C API is loaded at import: a later failure to import NumPy's modules cannot surface
  as a panic in the middle of a call.
- Masked arrays are refused (their mask would be ignored).
- Arrays whose copy would not fit in memory are an `OutOfMemoryError` (a `MemoryError` and an
  `inimtrace.Error`), as are settings over the memory budget.
"""

import subprocess
import sys
import textwrap

import numpy as np
import pytest

import inimtrace
from conftest import SMALL_DISPLAY


def child(code, timeout=120):
    """Runs `code` in a child Python; returns its stdout, failing on a crash or an error."""
    r = subprocess.run(
        [sys.executable, "-c", textwrap.dedent(code)], capture_output=True, text=True, timeout=timeout
    )
    assert r.returncode == 0, f"child exited with {r.returncode} (negative: killed by that signal)\n{r.stderr}"
    return r.stdout


def nested(depth):
    """A list nested `depth` deep: [[[...[1.0]...]]]."""
    value = 1.0
    for _ in range(depth):
        value = [value]
    return value


def test_set_values_that_contain_themselves_are_value_errors():
    out = child(
        """
        import inimtrace
        loop = [1.0]
        loop.append(loop)
        table = {"a": 1}
        table["self"] = table
        inner = {"x": [0]}
        inner["x"].append(inner)
        for value in [loop, table, inner, [[loop]]]:
            try:
                inimtrace.Display.paper(set={"display.lcd.size": value})
            except ValueError as e:
                assert "contains itself" in str(e) and "display.lcd.size" in str(e), e
                print("refused")
        try:
            inimtrace.Experiment.paper_grid(set=table)
        except ValueError as e:
            assert "contains itself" in str(e), e
            print("refused")
        """
    )
    assert out.split() == ["refused"] * 5


def test_set_values_nest_at_most_64_deep():
    # The crash was at about 5,000 levels; the limit is 64, well above any setting.
    out = child(
        """
        import inimtrace
        def nested(depth):
            value = 1.0
            for _ in range(depth):
                value = [value]
            return value
        for depth in [65, 5000, 100000]:
            try:
                inimtrace.Display.paper(set={"display.lcd.size": nested(depth)})
            except ValueError as e:
                assert "nested more than 64 deep" in str(e), e
                print("refused")
        """
    )
    assert out.split() == ["refused"] * 3
    # At the limit the value is converted, then refused by the setting's own type check.
    with pytest.raises(inimtrace.ConfigError, match="display.lcd.size"):
        inimtrace.Display.paper(set={"display.lcd.size": nested(64)})
    # The same list twice side by side is no cycle.
    pair = [54, 54]
    with pytest.raises(inimtrace.ConfigError, match="display.lcd.resolution"):
        inimtrace.Display.paper(set={"display.lcd.resolution": [pair, pair]})


INTERRUPT = """
import os, signal, threading, time
import numpy as np
import inimtrace

SMALL_DISPLAY = {"display.lcd.resolution": [540, 540]}
scene, display = inimtrace.Scene.paper(), inimtrace.Display.paper()
grid = inimtrace.Experiment.paper_grid(set=SMALL_DISPLAY)
converged = inimtrace.Experiment.paper(set=SMALL_DISPLAY)
img = np.full((2160, 2160, 3), 0.25, np.float32)
big_eye = inimtrace.Eye(focus_mm=400, retina=2048, pupil_grid=16)
kill = {}

def interrupt_in(prefix):
    # At the first progress report of the stage named `prefix...`: its work is running. SIGINT
    # to the process, as a terminal's Ctrl-C sends it.
    def report(stage, done, total):
        if stage.startswith(prefix) and not kill:
            kill["at"] = time.monotonic()
            os.kill(os.getpid(), signal.SIGINT)
    return report

calls = {
    "render_display": lambda: inimtrace.render_display(
        scene, display, "LA", samples_per_pixel=4, progress=interrupt_in("display image")
    ),
    "simulate": lambda: inimtrace.simulate(img, display, big_eye, progress=interrupt_in("simulate")),
    "ground_truth": lambda: inimtrace.ground_truth(scene, big_eye, progress=interrupt_in("ground truth")),
    "assess_grid": lambda: inimtrace.assess(grid, progress=interrupt_in("simulate")),
    "assess_converged": lambda: inimtrace.assess(converged, progress=interrupt_in("measure")),
    "resolution": lambda: inimtrace.resolution(out=OUT, progress=interrupt_in("eye rays")),
}
for name, call in calls.items():
    kill.clear()
    try:
        call()
        print(name, "finished")
    except KeyboardInterrupt:
        print(name, "interrupted", time.monotonic() - kill["at"])

# Without a progress callback: a timer thread sends SIGINT while assess works (and writes).
def later():
    time.sleep(1.0)
    kill["at"] = time.monotonic()
    os.kill(os.getpid(), signal.SIGINT)
threading.Thread(target=later, daemon=True).start()
try:
    inimtrace.assess(inimtrace.Experiment.paper_grid(), out=OUT + "-assess")
    print("timer finished")
except KeyboardInterrupt:
    print("timer interrupted", time.monotonic() - kill["at"])
print("folder", os.path.exists(OUT + "-assess/results.json"))

# The module works after being interrupted, and so does the folder of the interrupted run.
small = inimtrace.Experiment.paper_grid(
    set={**SMALL_DISPLAY, "eye.retina_resolution": 16, "eye.pupil_grid": 2, "methods": ["LC"]}
)
result = inimtrace.assess(small, out=OUT + "-assess")
print("after", len(result.scores), os.path.exists(OUT + "-assess/results.json"))
"""


def test_ctrl_c_cancels_every_long_call_within_a_second(tmp_path):
    out = child(INTERRUPT.replace("OUT", repr(str(tmp_path / "run"))), timeout=300)
    by_name = {line.split()[0]: line.split()[1:] for line in out.splitlines()}
    calls = ["render_display", "simulate", "ground_truth", "assess_grid", "assess_converged", "resolution", "timer"]
    for name in calls:
        status = by_name[name]
        assert status[0] == "interrupted", f"{name}: {status}"
        assert float(status[1]) < 1.0, f"{name} took {status[1]} s to stop after SIGINT"
    # The interrupted run left no results.json; the next run into its folder completes.
    assert by_name["folder"] == ["False"]
    assert by_name["after"] == ["4", "True"]


def test_the_numpy_api_is_loaded_at_import():
    # Once imported, the module never imports NumPy's C-API module again: a call made when that
    # import would fail (as it does with a Ctrl-C pending) still works.
    out = child(
        """
        import sys
        import numpy as np
        import inimtrace
        for name in ["numpy.core.multiarray", "numpy._core.multiarray"]:
            sys.modules[name] = None
        a = np.zeros((16, 16, 3), np.float32)
        print(inimtrace.compare(a, a)["width"])
        """
    )
    assert out.split() == ["16"]


def test_import_without_numpy_is_an_import_error():
    r = subprocess.run(
        [sys.executable, "-c", "import sys; sys.modules['numpy'] = None; import inimtrace"],
        capture_output=True,
        text=True,
    )
    assert r.returncode == 1 and "ImportError" in r.stderr and "needs NumPy" in r.stderr, r.stderr


def test_masked_arrays_are_refused():
    display = inimtrace.Display.paper(set={"display.lcd.resolution": [54, 54]})
    img = np.full((54, 54, 3), 0.5, dtype=np.float32)
    mask = np.zeros(img.shape, bool)
    mask[3, 7, 1] = True
    masked = np.ma.MaskedArray(img, mask=mask)
    eye = inimtrace.Eye(focus_mm=400, retina=16, pupil_grid=2)
    with pytest.raises(ValueError, match="display_image is a masked array"):
        inimtrace.simulate(masked, display, eye)
    with pytest.raises(ValueError, match="b is a masked array"):
        inimtrace.compare(img, masked)
    # Filled, it is an ordinary array.
    assert inimtrace.compare(img, masked.filled(0.5))["psnr_db"]["mean"] == float("inf")


def test_memory_errors_are_both_memory_errors_and_inimtrace_errors():
    assert issubclass(inimtrace.OutOfMemoryError, MemoryError)
    assert issubclass(inimtrace.OutOfMemoryError, inimtrace.Error)
    # A library budget refusal (settings too large for the machine): no longer a ConfigError.
    display = inimtrace.Display.paper(set={"display.lcd.resolution": [60000, 60000]})
    with pytest.raises(inimtrace.OutOfMemoryError) as e:
        inimtrace.render_display(inimtrace.Scene.paper(), display, "LC")
    assert "would need about" in str(e.value) and e.value.field.startswith("lcd.resolution")
    assert not isinstance(e.value, inimtrace.ConfigError)


def test_array_copies_over_the_memory_budget_are_memory_errors():
    # Under an address-space limit of what is mapped plus 1.5 GiB, copies of 4.8 GB (zero-stride
    # views take no memory themselves) are refused before anything is allocated; small ones work.
    out = child(
        """
        import resource
        import numpy as np
        import inimtrace
        vm = next(int(l.split()[1]) * 1024 for l in open("/proc/self/status") if l.startswith("VmSize:"))
        resource.setrlimit(resource.RLIMIT_AS, (vm + (3 << 29), resource.RLIM_INFINITY))
        huge = np.broadcast_to(np.full(3, 0.5, np.float32), (20000, 20000, 3))
        small = np.full((16, 16, 3), 0.5, np.float32)
        print(inimtrace.compare(small, small)["width"])
        for a, b in [(huge, huge), (small, small[:0])]:
            try:
                inimtrace.compare(a, b)
            except MemoryError as e:
                assert isinstance(e, inimtrace.Error) and "compare()" in str(e) and "the copy of `a`" in str(e), e
                assert "RLIMIT_AS" in str(e), e
                print("memory")
            except ValueError:
                print("value")
        display = inimtrace.Display.paper(set={"display.lcd.resolution": [20000, 20000]})
        eye = inimtrace.Eye(pinhole=True, retina=16)
        try:
            inimtrace.simulate(huge, display, eye)
        except MemoryError as e:
            assert "simulate()" in str(e) and "display_image" in str(e), e
            print("memory")
        """
    )
    assert out.split() == ["16", "memory", "value", "memory"]
