"""A white NumPy array handed to `simulate` comes back white wherever rays land on the LCD, and
black where they miss it (a ray that misses the LCD carries black)."""

import numpy as np

import inimtrace
from conftest import SMALL_DISPLAY


def chief_ray_lands(display, n, half_tangent):
    """Where the pinhole eye's ray of each retina pixel lands on the LCD, by eq. (1) written out
    independently here: the ray through the pupil centre keeps its slope t to the lenslet plane,
    refracts at the nearest lenslet (w2 = w1 - (x2 - xc) / f) and travels v2 to the LCD."""
    v1, v2, f = display.eye_to_lenslets_mm, display.lenslets_to_lcd_mm, display.focal_length_mm
    pitch = display.lenslet_pitch_matrix_mm[0]
    w, h = display.lcd_size_mm
    t = -half_tangent + (np.arange(n) + 0.5) * 2 * half_tangent / n
    tx, ty = np.meshgrid(t, -t)  # row 0 at the top: ty decreases down the rows

    def to_lcd(slope):
        x2 = slope * v1
        xc = pitch * np.floor(x2 / pitch + 0.5)
        return x2 + (slope - (x2 - xc) / f) * v2

    x3, y3 = to_lcd(tx), to_lcd(ty)
    margin = 1e-9
    lands = (np.abs(x3) <= w / 2 - margin) & (np.abs(y3) <= h / 2 - margin)
    misses = (np.abs(x3) > w / 2 + margin) | (np.abs(y3) > h / 2 + margin)
    return lands, misses


def test_white_comes_back_white_where_rays_land_pinhole():
    display = inimtrace.Display.paper(set=SMALL_DISPLAY)
    white = np.ones(display.image_shape, np.float32)
    n, half_tangent = 64, 0.6  # a wide field: the outer pixels' rays miss the LCD
    sim = inimtrace.simulate(white, display, inimtrace.Eye(pinhole=True, retina=n, half_tangent=half_tangent))
    lands, misses = chief_ray_lands(display, n, half_tangent)
    assert lands.sum() > 1000 and misses.sum() > 1000
    assert np.all(sim[lands] == 1.0)
    assert np.all(sim[misses] == 0.0)


def test_white_comes_back_white_everywhere_when_every_ray_lands():
    display = inimtrace.Display.paper(set=SMALL_DISPLAY)
    for value in [1.0, 0.25]:
        image = np.full(display.image_shape, value, np.float32)
        eye = inimtrace.Eye(focus_mm=400, pupil=5, pupil_grid=8, retina=48, half_tangent=0.2, retina_samples=2)
        sim = inimtrace.simulate(image, display, eye)
        assert sim.shape == (48, 48, 3)
        assert np.all(sim == np.float32(value))


def test_partial_landing_stays_between_black_and_white():
    display = inimtrace.Display.paper(set=SMALL_DISPLAY)
    white = np.ones(display.image_shape, np.float32)
    sim = inimtrace.simulate(white, display, inimtrace.Eye(focus_mm=400, retina=48, half_tangent=0.6, pupil_grid=4))
    assert sim.min() == 0.0 and sim.max() == 1.0
    assert np.all((sim >= 0) & (sim <= 1))
    assert np.all(sim[20:28, 20:28] == 1.0)  # the centre of the field: every ray lands
