"""A turned eye built in Python (`Eye(..., gaze=(h, v), centre_of_rotation=...)`) is the eye of the
CLI's `--set eye.gaze_deg=...`: the same ground truth, perceived images, PupilCenter image for the
turned pupil and scores, bit for bit; a bad gaze or centre raises the CLI's message."""

import math
import warnings

import pytest

import inimtrace
from conftest import SMALL_DISPLAY, SMALL_DISPLAY_ARGS, load_json, read_exr, same_bits

EXPERIMENT = """
name = "py-gaze"
scene = "builtin:paper"
display = "builtin:paper"
methods = ["PC", "LA"]
[eye]
retina_resolution = 40
pupil_grid = 4
[[eye_cases]]
name = "Near"
focus_mm = 300.0
"""

GAZE = (6.0, -3.0)
CENTRE = 12.0


def test_a_python_turned_eye_gives_the_clis_assessment(cli, tmp_path):
    path = tmp_path / "exp.toml"
    path.write_text(EXPERIMENT)
    out = tmp_path / "cli"
    cli(
        "assess", path, "--out", out, *SMALL_DISPLAY_ARGS,
        "--set", f"eye.gaze_deg=[{GAZE[0]}, {GAZE[1]}]", "--set", f"eye.centre_of_rotation_mm={CENTRE}",
    )
    report = load_json(out / "results.json")
    scene, display = inimtrace.Scene.paper(), inimtrace.Display.paper(set=SMALL_DISPLAY)
    eye = inimtrace.Eye(focus_mm=300, retina=40, pupil_grid=4, gaze=GAZE, centre_of_rotation=CENTRE)
    assert eye.gaze == GAZE and eye.centre_of_rotation == CENTRE
    # The pupil has turned about the centre: about 9 mm x sin(6.7 degrees) off the axis, behind z = 0.
    x, y, z = eye.pupil_centre
    assert 0.8 < x < 1.2 and -0.6 < y < -0.3 and z < 0

    gt = inimtrace.ground_truth(scene, eye)
    assert same_bits(gt, read_exr(out / "gt_Near.exr")[0])
    # PupilCenter with ideal tracking renders for the turned pupil.
    pc = inimtrace.render_display(scene, display, "PC", eye_position=eye.pupil_centre)
    assert same_bits(pc, read_exr(out / "display_PC.exr")[0])
    for method, image in [("PC", pc), ("LA", inimtrace.render_display(scene, display, "LA"))]:
        sim = inimtrace.simulate(image, display, eye)
        assert same_bits(sim, read_exr(out / f"sim_{method}_Near.exr")[0]), method
        score = next(s for s in report["scores"] if s["method"] == method)
        with warnings.catch_warnings():  # the grid estimator's images have no sampling noise
            warnings.simplefilter("ignore")
            assert inimtrace.compare(sim, gt)["psnr_db"]["mean"] == score["psnr"]["mean"], method

    # The experiment's own eye, seen from Python, is the same turned eye.
    exp = inimtrace.Experiment.load(path, set={**SMALL_DISPLAY, "eye.gaze_deg": list(GAZE),
                                               "eye.centre_of_rotation_mm": CENTRE})
    (_, case_eye), = exp.eye_cases
    assert case_eye.gaze == GAZE and case_eye.centre_of_rotation == CENTRE
    assert case_eye.pupil_centre == eye.pupil_centre
    # Straight ahead: the eye at rest, its pupil where it is.
    ahead = inimtrace.Eye(focus_mm=300, position=(0.5, 0.0, 0.0))
    assert ahead.gaze == (0.0, 0.0) and ahead.pupil_centre == (0.5, 0.0, 0.0)
    assert ahead.centre_of_rotation == 13.3


def cli_message(cli, *args):
    r = cli(*args, check=False)
    assert r.returncode == 1, r.stderr
    line = [l for l in r.stderr.splitlines() if l.startswith("error: ")][-1]
    return line[len("error: "):]


@pytest.mark.parametrize(
    "key,value,kwargs",
    [
        ("eye.gaze_deg", "[61.0, 0.0]", dict(gaze=(61.0, 0.0))),
        ("eye.gaze_deg", "[nan, 0.0]", dict(gaze=(math.nan, 0.0))),
        ("eye.centre_of_rotation_mm", "-1.0", dict(centre_of_rotation=-1.0)),
    ],
)
def test_a_bad_gaze_or_centre_raises_the_clis_message(cli, tmp_path, key, value, kwargs):
    path = tmp_path / "exp.toml"
    path.write_text(EXPERIMENT)
    want = cli_message(cli, "assess", path, "--set", f"{key}={value}")
    with pytest.raises(inimtrace.ConfigError) as e:
        inimtrace.Eye(focus_mm=300, **kwargs)
    field = "gaze" if "gaze" in key else "centre_of_rotation"
    assert e.value.source == "Eye()" and e.value.field == field
    # The CLI names the file and its --set; Eye() names itself: the same message follows.
    assert str(e.value) == f"Eye(): field `{field}`: " + want.split(f"field `{key}`: ", 1)[1]


def test_a_gaze_past_the_display_raises_the_clis_message_when_the_display_is_known(cli, tmp_path):
    path = tmp_path / "exp.toml"
    path.write_text(EXPERIMENT)
    want = cli_message(cli, "assess", path, "--set", "eye.gaze_deg=[25.0, 0.0]")
    assert "look past the display" in want
    display = inimtrace.Display.paper()
    eye = inimtrace.Eye(focus_mm=300, retina=8, gaze=(25.0, 0.0))
    with pytest.raises(inimtrace.ConfigError) as e:
        inimtrace.simulate(inimtrace.render_display(inimtrace.Scene.paper(), display, "LC"), display, eye)
    assert str(e.value) == "Eye(): field `gaze`: " + want.split("field `eye.gaze_deg`: ", 1)[1]
