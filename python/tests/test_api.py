"""The objects' attributes, `set=` in both forms, thread counts and progress callbacks."""

import json

import numpy as np
import pytest

import inimtrace
from conftest import ROOT, SMALL_DISPLAY, same_bits


def test_display_fields_are_the_clis(cli):
    d = inimtrace.Display.paper()
    assert (d.eye_to_lenslets_mm, d.lenslets_to_lcd_mm, d.focal_length_mm) == (20.0, 6.316, 6.427)
    assert d.lenslet_pitch_matrix_mm == [1.2, 0.0, 0.0, 1.2]
    assert d.elemental_image_pitch_matrix_mm == [1.58, 0.0, 0.0, 1.58]
    assert d.lcd_size_mm == [21.6, 21.6] and d.lcd_resolution == [2160, 2160]
    assert d.image_shape == (2160, 2160, 3)
    design = json.loads(cli("info", "--json").stdout)
    assert d.design() == design
    assert d.central_depth_plane_mm == pytest.approx(385.7, abs=0.05)
    loaded = inimtrace.Display.load(ROOT / "displays" / "paper.toml")
    assert loaded.to_dict() == d.to_dict()
    yaml = inimtrace.Display.load(ROOT / "data" / "lensletdisplay.yaml")
    assert yaml.lcd_resolution == [2160, 2160]


def test_eye_fields():
    e = inimtrace.Eye(focus_diopters=2.5, pupil=3, retina=128, position=(1.0, 0.0, 0.0))
    assert (e.focus_mm, e.focus_diopters, e.pupil, e.pinhole) == (400.0, 2.5, 3.0, False)
    assert (e.retina, e.half_tangent, e.retina_distance, e.position) == (128, 0.3, 17.0, (1.0, 0.0, 0.0))
    assert inimtrace.Eye(focus_mm=400).pupil_samples == 52  # 8 x 8 grid kept inside the circle
    p = inimtrace.Eye(pinhole=True)
    assert p.pinhole and p.focus_mm is None and p.pupil is None
    # The model is named, and so is it in the repr.
    assert e.model == "thin-lens" and "thin-lens" in repr(e)
    n = inimtrace.Eye(focus_diopters=2.5, retina=16, model="navarro")
    assert n.model == "navarro-1985" and "navarro-1985" in repr(n), repr(n)


def test_experiment_fields_and_set_forms():
    path = ROOT / "experiments" / "paper.toml"
    exp = inimtrace.Experiment.load(path)
    assert exp.name == "paper" and exp.methods == ["LC", "PC", "LA"] and exp.estimator == "grid"
    assert [name for name, _ in exp.eye_cases] == ["Pin", "Near", "Cen", "Far"]
    assert exp.eye_cases[2][1].focus_mm == 400.0 and exp.eye_cases[0][1].pinhole
    as_dict = inimtrace.Experiment.load(path, set={"eye.pupil_diameter": 3, "methods": ["LC", "LA3"]})
    as_list = inimtrace.Experiment.load(path, set=["eye.pupil_diameter=3", 'methods=["LC", "LA3"]'])
    assert as_dict.settings() == as_list.settings()
    assert as_dict.eye_cases[1][1].pupil == 3.0 and as_dict.methods == ["LC", "LA3"]
    assert as_dict.settings()["eye"]["pupil_diameter"] == 3
    assert inimtrace.Experiment.paper().estimator == "converged"
    assert "[[eye_cases]]" in exp.to_toml()
    assert exp.scene.name == "paper" and exp.display.lcd_resolution == [2160, 2160]


def test_auto_pupil_follows_the_display_luminance():
    path = ROOT / "experiments" / "paper.toml"
    dim = inimtrace.Experiment.load(path, set={"eye.pupil_diameter": "auto"})
    bright = inimtrace.Experiment.load(
        path, set={"eye.pupil_diameter": "auto", "display.photometry.peak_luminance": 1000}
    )
    assert dim.settings()["eye"]["pupil_diameter"] == "auto"
    # Watson & Yellott (2012): a brighter display, a smaller pupil, within the formula's range.
    assert 2.0 < bright.eye_cases[1][1].pupil < dim.eye_cases[1][1].pupil < 8.0


def test_scene_fields():
    s = inimtrace.Scene.paper()
    assert s.name == "paper" and s.object_count == 4 and s.triangle_count == 8 and s.warnings == []
    assert s.summary()["objects"][0]["name"]
    moved = inimtrace.Scene.paper(set={"scene.objects[0].center": [0.0, 0.0, 350.0]})
    assert moved.summary() != s.summary()


def test_thread_counts_give_the_same_images():
    scene, display = inimtrace.Scene.paper(), inimtrace.Display.paper(set=SMALL_DISPLAY)
    one = inimtrace.render_display(scene, display, "LA", threads=1)
    for threads in [2, 3, None]:
        assert same_bits(inimtrace.render_display(scene, display, "LA", threads=threads), one)


def test_progress_reports_reach_the_end():
    scene, display = inimtrace.Scene.paper(), inimtrace.Display.paper(set=SMALL_DISPLAY)
    reports = []
    inimtrace.render_display(scene, display, "PC", progress=lambda *r: reports.append(r))
    assert reports[-1] == ("display image PC", 540, 540)
    reports.clear()
    exp = inimtrace.Experiment.paper_grid(set={**SMALL_DISPLAY, "eye.retina_resolution": 16, "eye.pupil_grid": 2})
    inimtrace.assess(exp, progress=lambda *r: reports.append(r))
    finals = {stage for stage, done, total in reports if done == total}
    assert {"display image LC", "display image PC", "display image LA", "ground truth Pin", "simulate Far"} <= finals


def test_a_progress_callback_that_raises_stops_with_its_exception():
    scene, display = inimtrace.Scene.paper(), inimtrace.Display.paper(set=SMALL_DISPLAY)

    def fail(stage, done, total):
        raise KeyboardInterrupt("stop")

    with pytest.raises(KeyboardInterrupt, match="stop"):
        inimtrace.render_display(scene, display, "LC", progress=fail)


def test_read_exr_reads_what_the_cli_wrote(cli, tmp_path):
    out = tmp_path / "d.exr"
    cli("render-display", "--set", "display.lcd.resolution=[54, 54]", "--out", out)
    img, z = inimtrace.read_exr(out)
    assert img.shape == (54, 54, 3) and z.shape == (54, 54)
    scene, display = inimtrace.Scene.paper(), inimtrace.Display.paper(set={"display.lcd.resolution": [54, 54]})
    mine, my_z = inimtrace.render_display(scene, display, "LC", depth=True)
    assert same_bits(img, mine) and same_bits(z, my_z)


def test_assessment_records_make_a_table():
    exp = inimtrace.Experiment.paper_grid(set={**SMALL_DISPLAY, "eye.retina_resolution": 16, "eye.pupil_grid": 2})
    result = inimtrace.assess(exp)
    keys = set(result.scores[0])
    assert all(set(s) == keys for s in result.scores)
    assert {"method", "eye_case", "psnr_db", "psnr_ci95_db", "ssim", "ssim_ci95", "psnr_db_R", "target_met"} <= keys
    assert sorted(result.images) == sorted(
        [f"display_{m}" for m in exp.methods] + [f"gt_{c}" for c, _ in exp.eye_cases]
        + [f"sim_{m}_{c}" for m in exp.methods for c, _ in exp.eye_cases]
    )
    assert result.images["gt_Pin"].shape == (16, 16, 3)
    assert result.report["threads"] >= 1 and result.report["experiment"] == "paper"
    with pytest.raises(KeyError):
        result.score("LC", "Nowhere")
    assert np.isfinite(result.score("LA", "Cen")["psnr_db"])
