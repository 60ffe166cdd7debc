"""Arrays are not copied on the way out: each returned array owns the buffer the library
rendered into, and rendering the paper's display image raises the peak memory by the image and
its depth plane only (a copy would add the image's 56 MB again)."""

import subprocess
import sys

import numpy as np

import inimtrace
from conftest import SMALL_DISPLAY

PEAK = r"""
import resource, sys
import inimtrace
scene, display = inimtrace.Scene.paper(), inimtrace.Display.paper()
inimtrace.render_display(scene, inimtrace.Display.paper(set={"display.lcd.resolution": [54, 54]}), "LC")
before = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
img = inimtrace.render_display(scene, display, "LC", threads=1)
after = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
print((after - before) * 1024, img.nbytes, img.flags.owndata)
"""


def not_a_numpy_copy(a):
    """The array's memory belongs to the Rust buffer it was built on, not to NumPy."""
    return not a.flags.owndata and a.base is not None and not isinstance(a.base, np.ndarray)


def test_returned_arrays_wrap_the_rendered_buffers():
    scene, display = inimtrace.Scene.paper(), inimtrace.Display.paper(set=SMALL_DISPLAY)
    img, z = inimtrace.render_display(scene, display, "LC", depth=True)
    eye = inimtrace.Eye(pinhole=True, retina=32)
    for a in [img, z, inimtrace.simulate(img, display, eye), inimtrace.ground_truth(scene, eye)]:
        assert not_a_numpy_copy(a)
        assert a.flags.c_contiguous and a.flags.writeable and a.dtype == np.float32
    exp = inimtrace.Experiment.paper_grid(
        set={**SMALL_DISPLAY, "eye.retina_resolution": 16, "eye.pupil_grid": 2, "methods": ["LC"]}
    )
    result = inimtrace.assess(exp)
    assert all(not_a_numpy_copy(a) for a in result.images.values())


def test_peak_memory_of_a_display_image_is_the_image_and_its_depth_plane():
    out = subprocess.run([sys.executable, "-c", PEAK], capture_output=True, text=True, check=True).stdout.split()
    peak, image_bytes, owndata = int(out[0]), int(out[1]), out[2]
    assert image_bytes == 2160 * 2160 * 3 * 4 and owndata == "False"
    depth_bytes = image_bytes // 3
    # Measured: 74.8 MB = 56.0 MB image + 18.7 MB depth plane. One more copy would be >= 130 MB.
    assert peak < image_bytes + depth_bytes + image_bytes // 4, f"peak rose by {peak / 1e6:.1f} MB"
