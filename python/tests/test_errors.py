"""Bad inputs raise the right `inimtrace.Error` subclass with the CLI's message (the file and the
field in it); a wrong array shape or dtype, or a value outside a closed set, is a `ValueError`."""

import numpy as np
import pytest

import inimtrace
from conftest import ROOT, SMALL_DISPLAY


def cli_message(cli, *args):
    r = cli(*args, check=False)
    assert r.returncode == 1, r.stderr
    line = [l for l in r.stderr.splitlines() if l.startswith("error: ")][-1]
    return line[len("error: "):]


@pytest.fixture
def files(tmp_path):
    (tmp_path / "bad_display.toml").write_text(
        (ROOT / "displays" / "paper.toml").read_text().replace("focal_length = 6.427", "focal_length = -6.427")
    )
    (tmp_path / "broken.obj").write_text("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 9\n")
    (tmp_path / "mesh_scene.toml").write_text(
        'name = "broken-mesh"\n[[objects]]\nname = "thing"\ntype = "mesh"\nfile = "broken.obj"\n'
        "fit = { size = 50.0, center = [0.0, 0.0, 400.0] }\n"
    )
    (tmp_path / "bad.exr").write_text("not an exr")
    (tmp_path / "exp.toml").write_text(
        'name = "e"\nscene = "mesh_scene.toml"\n[[eye_cases]]\nname = "Pin"\npinhole = true\n'
    )
    return tmp_path


def test_the_classes_form_one_hierarchy():
    for cls in [inimtrace.ConfigError, inimtrace.MeshError, inimtrace.ImageError, inimtrace.OpticsError]:
        assert issubclass(cls, inimtrace.Error) and cls is not inimtrace.Error
    assert issubclass(inimtrace.Error, Exception)
    assert inimtrace.Error.__module__ == "inimtrace"


def test_a_bad_display_file_is_a_config_error_naming_file_and_field(cli, files):
    path = files / "bad_display.toml"
    with pytest.raises(inimtrace.ConfigError) as e:
        inimtrace.Display.load(path)
    assert str(e.value) == cli_message(cli, "info", "--display", path)
    assert str(path) in str(e.value) and "focal_length" in str(e.value)
    assert e.value.source == str(path) and e.value.field.startswith("focal_length")


def test_a_bad_set_key_is_a_config_error_naming_the_key(cli):
    with pytest.raises(inimtrace.ConfigError) as e:
        inimtrace.Display.paper(set={"display.lenslets.pitchh": 1})
    assert str(e.value) == cli_message(cli, "info", "--set", "display.lenslets.pitchh=1")
    assert "display.lenslets.pitchh" in str(e.value)
    with pytest.raises(inimtrace.ConfigError) as e:
        inimtrace.Display.paper(set=["display.lenslets.pitch=-1"])
    assert str(e.value) == cli_message(cli, "info", "--set", "display.lenslets.pitch=-1")
    assert e.value.field == "lenslets.pitch"


def test_a_broken_mesh_is_a_mesh_error_naming_file_and_line(cli, files):
    with pytest.raises(inimtrace.MeshError) as e:
        inimtrace.Scene.load(files / "mesh_scene.toml")
    assert str(e.value) == cli_message(cli, "info", "--scene", files / "mesh_scene.toml")
    assert "broken.obj: line 4" in str(e.value) and e.value.field == "objects[0].file"
    # Also through an experiment that names the scene.
    with pytest.raises(inimtrace.MeshError) as e:
        inimtrace.Experiment.load(files / "exp.toml")
    assert "exp.toml" in str(e.value) and "broken.obj: line 4" in str(e.value)


def test_a_bad_image_file_is_an_image_error(cli, files):
    with pytest.raises(inimtrace.ImageError) as e:
        inimtrace.read_exr(files / "bad.exr")
    assert str(e.value) == cli_message(cli, "simulate", files / "bad.exr", "--pinhole", "--out", files / "s.exr")
    assert e.value.source == str(files / "bad.exr")
    with pytest.raises(inimtrace.ImageError):
        inimtrace.read_exr(files / "missing.exr")


def test_an_impossible_optical_configuration_is_an_optics_error(cli, tmp_path):
    # v2 with 1/v1 + 1/v2 = 1/f: the lenslets image the pupil centre onto the LCD, so PupilCenter
    # is undefined for the eye at the origin (an eye at or beyond the lenslets is refused earlier,
    # as a setting).
    v2 = 1.0 / (1.0 / 6.427 - 1.0 / 20.0)
    scene = inimtrace.Scene.paper()
    display = inimtrace.Display.paper(set={"display.lcd.resolution": [54, 54], "display.lenslets_to_lcd": v2})
    with pytest.raises(inimtrace.OpticsError) as e:
        inimtrace.render_display(scene, display, "PC")
    assert str(e.value) == cli_message(
        cli, "render-display", "--method", "PC",
        "--set", "display.lcd.resolution=[54, 54]", "--set", f"display.lenslets_to_lcd={v2!r}",
        "--out", tmp_path / "p.exr",
    )
    with pytest.raises(inimtrace.OpticsError) as e:
        inimtrace.Experiment.paper(set={"display.lenslets_to_lcd": v2})
    assert "PupilCenter" in str(e.value) and "eye.position" in str(e.value)
    with pytest.raises(inimtrace.ConfigError) as e:
        inimtrace.Experiment.paper(set={"eye.position": [0.0, 0.0, 30.0]})
    assert "eye.position" in str(e.value) and "lenslet plane" in str(e.value)


def test_bad_eye_values_name_the_field():
    with pytest.raises(inimtrace.ConfigError) as e:
        inimtrace.Eye(focus_mm=400, pupil=-1)
    assert e.value.field == "pupil_diameter" and "Eye()" in str(e.value)
    with pytest.raises(inimtrace.ConfigError) as e:
        inimtrace.Eye(pinhole=True, retina=0)
    assert e.value.field == "retina_resolution"
    with pytest.raises(ValueError, match="exactly one of"):
        inimtrace.Eye(focus_mm=400, focus_diopters=2)


def test_a_missing_file_is_an_error_naming_it(tmp_path):
    missing = tmp_path / "nope.toml"
    with pytest.raises(inimtrace.ConfigError, match="nope.toml"):
        inimtrace.Experiment.load(missing)


def test_wrong_array_shape_or_dtype_is_a_value_error():
    display = inimtrace.Display.paper(set=SMALL_DISPLAY)
    eye = inimtrace.Eye(pinhole=True, retina=16)
    good = np.ones(display.image_shape, np.float32)
    cases = [
        good.astype(np.float64),
        good[:, :, :2].copy(),
        good[:-1],
        good[:, :, 0],
        np.ones((540, 540, 3), np.int32),
        good.tolist()[:1],
    ]
    for bad in cases:
        with pytest.raises(ValueError, match=r"float32 array of shape \(540, 540, 3\)"):
            inimtrace.simulate(bad, display, eye)
    # Strided views are fine (and give the same image).
    big = np.ones((540, 1080, 3), np.float32)
    assert np.array_equal(inimtrace.simulate(big[:, ::2], display, eye), inimtrace.simulate(good, display, eye))
    with pytest.raises(ValueError, match=r"shape \(16, 16, 3\)"):
        a = np.zeros((16, 16, 3), np.float32)
        inimtrace.compare(a, np.zeros((16, 17, 3), np.float32))


def test_values_outside_closed_sets_are_value_errors():
    scene, display = inimtrace.Scene.paper(), inimtrace.Display.paper(set={"display.lcd.resolution": [54, 54]})
    with pytest.raises(ValueError, match="method"):
        inimtrace.render_display(scene, display, method="XY")
    with pytest.raises(ValueError, match="unknown backend"):
        inimtrace.render_display(scene, display, backend="optix")
    with pytest.raises(ValueError, match="threads"):
        inimtrace.render_display(scene, display, threads=0)
    with pytest.raises(ValueError, match="progress"):
        inimtrace.render_display(scene, display, progress=3)
    with pytest.raises(ValueError, match="exr_compression"):
        inimtrace.assess(inimtrace.Experiment.paper_grid(), exr_compression="lzma")
    with pytest.raises(ValueError):
        inimtrace.compare(np.zeros((16, 16, 3), np.float32), np.zeros((16, 16, 3), np.float32), ssim="other")
    with pytest.raises(ValueError, match="set"):
        inimtrace.Display.paper(set="display.lenslets.pitch=1")


@pytest.mark.parametrize("bad", [float("nan"), float("inf"), -0.5])
def test_array_inputs_get_the_clis_checks_nan_infinite_and_negative_are_refused(bad):
    display = inimtrace.Display.paper(set={"display.lcd.resolution": [54, 54]})
    img = np.full((54, 54, 3), 0.5, dtype=np.float32)
    img[3, 7, 1] = bad
    eye = inimtrace.Eye(focus_mm=400, retina=16, pupil_grid=2)
    with pytest.raises(ValueError) as e:
        inimtrace.simulate(img, display, eye)
    assert "display_image[3, 7, 1]" in str(e.value) and "finite and non-negative" in str(e.value)
    with pytest.raises(ValueError):
        inimtrace.compare(img, np.full((54, 54, 3), 0.5, dtype=np.float32))
