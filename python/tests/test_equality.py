"""Every function's output equals the CLI's for the same inputs, bit for bit: arrays against
the EXR files the CLI wrote (read by OpenEXR, not by inimtrace), scores against results.json."""

import json
import math

import numpy as np
import pytest

import inimtrace
from conftest import PUPIL_GRID, RETINA, SMALL_DISPLAY, SMALL_DISPLAY_ARGS, load_json, read_exr, same_bits

EYE_ARGS = ["--retina", RETINA, "--pupil-grid", PUPIL_GRID]


@pytest.fixture(scope="module")
def small():
    return inimtrace.Scene.paper(), inimtrace.Display.paper(set=SMALL_DISPLAY)


@pytest.mark.parametrize(
    "method,backend",
    [("LC", "auto"), ("PC", "auto"), ("LA", "auto"), ("LA3", "analytic"), ("LC", "bvh")]
    + ([("PC", "embree")] if inimtrace.has_embree else []),
)
def test_render_display_equals_cli(cli, tmp_path, small, method, backend):
    scene, display = small
    out = tmp_path / "display.exr"
    cli("render-display", "--method", method, "--backend", backend, *SMALL_DISPLAY_ARGS, "--out", out)
    img, z = inimtrace.render_display(scene, display, method=method, backend=backend, depth=True)
    rgb, cli_z = read_exr(out)
    assert img.shape == (540, 540, 3) and img.dtype == np.float32
    assert same_bits(img, rgb)
    assert z is not None and cli_z is not None and same_bits(z, cli_z)
    # Without depth=True: the same image alone.
    assert same_bits(inimtrace.render_display(scene, display, method=method, backend=backend), rgb)


def test_render_display_settings_equal_cli(cli, tmp_path, small):
    scene, display = small
    out = tmp_path / "display.exr"
    cli(
        "render-display", "--method", "PC", "--samples-per-pixel", 2, "--reference-plane", "-5",
        "--eye-position", "1,0.5,0", *SMALL_DISPLAY_ARGS, "--out", out,
    )
    img = inimtrace.render_display(
        scene, display, "PC", samples_per_pixel=2, reference_plane=-5.0, eye_position=(1.0, 0.5, 0.0)
    )
    assert same_bits(img, read_exr(out)[0])


@pytest.mark.parametrize(
    "flags,eye",
    [
        (["--pinhole"], dict(pinhole=True)),
        (["--focus-mm", 400, "--pupil", 3], dict(focus_mm=400, pupil=3)),
        (["--focus-diopters", 1.5, "--retina-samples", 2, "--half-tangent", 0.25], dict(focus_diopters=1.5, retina_samples=2, half_tangent=0.25)),
        # A schematic eye (docs/EYE.md), polychromatic by default, with Stiles-Crawford.
        (["--focus-diopters", 2.5, "--eye-model", "navarro", "--stiles-crawford-rho", 0.05],
         dict(focus_diopters=2.5, model="navarro", stiles_crawford_rho=0.05)),
    ],
)
def test_ground_truth_and_simulate_equal_cli(cli, tmp_path, small, flags, eye):
    scene, display = small
    eye = inimtrace.Eye(retina=RETINA, pupil_grid=PUPIL_GRID, **eye)
    gt_path = tmp_path / "gt.exr"
    cli("ground-truth", *flags, *EYE_ARGS, "--out", gt_path)
    assert same_bits(inimtrace.ground_truth(scene, eye), read_exr(gt_path)[0])

    disp_path, sim_path = tmp_path / "display.exr", tmp_path / "sim.exr"
    cli("render-display", "--method", "LA", *SMALL_DISPLAY_ARGS, "--out", disp_path)
    cli("simulate", disp_path, *flags, *EYE_ARGS, *SMALL_DISPLAY_ARGS, "--out", sim_path)
    cli_sim = read_exr(sim_path)[0]
    # The CLI's display image, read by OpenEXR (an array rendered elsewhere) ...
    from_file = inimtrace.simulate(read_exr(disp_path)[0], display, eye)
    assert from_file.shape == (RETINA, RETINA, 3)
    assert same_bits(from_file, cli_sim)
    # ... and the display image rendered here give the CLI's perceived image.
    here = inimtrace.render_display(scene, display, "LA")
    assert same_bits(inimtrace.simulate(here, display, eye), cli_sim)


def test_compare_equals_cli(cli, tmp_path, small):
    scene, _ = small
    a_path, b_path = tmp_path / "a.exr", tmp_path / "b.exr"
    cli("ground-truth", "--pinhole", *EYE_ARGS, "--out", a_path)
    cli("ground-truth", "--focus-mm", 300, *EYE_ARGS, "--out", b_path)
    a, b = read_exr(a_path)[0], read_exr(b_path)[0]
    for constants in ["wang2004", "framework-8bit"]:
        ours = inimtrace.compare(a, b, ssim=constants)
        theirs = json.loads(cli("compare", a_path, b_path, "--ssim", constants, "--json").stdout)
        for metric in ["psnr_db", "ssim"]:
            for k in ["R", "G", "B", "mean"]:
                assert ours[metric][k] == theirs[metric][k], (metric, k)
        assert ours["ssim_constants"] == theirs["ssim_constants"]
    # Identical images: infinite PSNR (the CLI's JSON says null).
    same = inimtrace.compare(a, a)
    assert same["psnr_db"]["mean"] == math.inf and same["ssim"]["mean"] == 1.0
    assert json.loads(cli("compare", a_path, a_path, "--json").stdout)["psnr_db"]["mean"] is None


GRID_EXPERIMENT = """
name = "py-grid"
scene = "builtin:paper"
display = "builtin:paper"
methods = ["LC", "PC", "LA"]
[eye]
retina_resolution = 48
pupil_grid = 4
[[eye_cases]]
name = "Pin"
pinhole = true
[[eye_cases]]
name = "Near"
focus_mm = 300.0
"""

CONVERGED_EXPERIMENT = """
name = "py-converged"
methods = ["LC", "LA3"]
[measurement]
estimator = "converged"
psnr_ci95_db = 0.5
ssim_ci95 = 0.05
max_samples_per_pixel = 64
max_seconds = 600.0
seed = 7
replicates = 4
[eye]
retina_resolution = 32
[[eye_cases]]
name = "Cen"
focus_mm = 400.0
"""


def check_assessment(result, out_dir, experiment_name):
    report = load_json(out_dir / "results.json")
    assert report["experiment"] == experiment_name
    # Scores: every number of results.json, exactly.
    assert len(result.scores) == len(report["scores"])
    for ours, theirs in zip(result.scores, report["scores"]):
        assert (ours["method"], ours["eye_case"]) == (theirs["method"], theirs["eye_case"])
        for metric, key in [("psnr", "psnr_db"), ("ssim", "ssim")]:
            want = theirs[metric]
            assert ours[key] == (math.inf if want["mean"] == "inf" else want["mean"])
            for c, name in enumerate("RGB"):
                assert ours[f"{key}_{name}"] == want["channels"][c]
            if "ci95" in want:
                assert ours[key.replace("_db", "") + "_ci95" + ("_db" if metric == "psnr" else "")] == want["ci95"]
                for c, name in enumerate("RGB"):
                    ci_key = ("psnr_ci95_db_" if metric == "psnr" else "ssim_ci95_") + name
                    assert ours[ci_key] == want["channels_ci95"][c]
            else:
                assert ours["psnr_ci95_db"] is None and ours["ssim_ci95"] is None
        for k in ["samples_per_pixel", "replicates", "target_met"]:
            assert ours[k] == theirs.get(k)
    # Images: every EXR the CLI wrote, bit for bit (display images with their Z channel).
    exrs = sorted(p.stem for p in out_dir.glob("*.exr"))
    assert exrs == sorted(result.images)
    for stem, img in result.images.items():
        rgb, z = read_exr(out_dir / f"{stem}.exr")
        assert same_bits(img, rgb), stem
        if stem.startswith("display_"):
            assert same_bits(result.depths[stem], z), stem
    stages = {s["stage"] for s in result.stages}
    assert {"render_display", "write_display_image"} <= stages
    return report


def test_assess_grid_with_set_equals_cli(cli, tmp_path):
    path = tmp_path / "exp.toml"
    path.write_text(GRID_EXPERIMENT)
    cli_out = tmp_path / "cli"
    cli("assess", path, "--out", cli_out, *SMALL_DISPLAY_ARGS, "--set", "eye.pupil_diameter=3")
    exp = inimtrace.Experiment.load(path, set={**SMALL_DISPLAY, "eye.pupil_diameter": 3})
    assert exp.display.lcd_resolution == [540, 540]
    result = inimtrace.assess(exp)
    assert result.out is None
    report = check_assessment(result, cli_out, "py-grid")
    assert report["settings"] == result.report["settings"]
    assert len(result.scores) == 6 and result.score("LA", "Near")["psnr_db"] > 0
    # With out=, the package writes the same files, and the same numbers.
    py_out = tmp_path / "py"
    written = inimtrace.assess(exp, out=py_out)
    assert written.out == str(py_out)
    check_assessment(written, cli_out, "py-grid")
    assert load_json(py_out / "results.json")["scores"] == report["scores"]
    assert "write_images" in {s["stage"] for s in written.stages}


def test_assess_converged_scores_and_intervals_equal_cli(cli, tmp_path):
    path = tmp_path / "exp.toml"
    path.write_text(CONVERGED_EXPERIMENT)
    cli_out = tmp_path / "cli"
    cli("assess", path, "--out", cli_out, *SMALL_DISPLAY_ARGS)
    exp = inimtrace.Experiment.load(path, set=SMALL_DISPLAY)
    assert exp.estimator == "converged"
    assert exp.methods == ["LC", "LA3"]
    result = inimtrace.assess(exp, threads=1)
    check_assessment(result, cli_out, "py-converged")
    # LA3 keeps its name: in the scores, the images and the CLI's file names.
    assert [s["method"] for s in result.scores] == ["LC", "LA3"]
    assert {"display_LA3", "sim_LA3_Cen"} <= set(result.images)
    assert all(s["psnr_ci95_db"] > 0 and s["replicates"] == 4 for s in result.scores)


def test_compare_of_replicate_sets_gives_the_tables_scores(cli, tmp_path):
    """`assess --keep-replicates` writes each converged image's replicates; `compare()` on the
    ground truth's and a method's sets (read by `read_replicates`) gives that cell of
    results.json, intervals included, exactly; on single images it warns once about noise."""
    path = tmp_path / "exp.toml"
    path.write_text(CONVERGED_EXPERIMENT)
    out = tmp_path / "cli"
    cli("assess", path, "--out", out, "--keep-replicates", *SMALL_DISPLAY_ARGS)
    report = load_json(out / "results.json")
    for cell in report["scores"]:
        gt = inimtrace.read_replicates(out / f"gt_{cell['eye_case']}.replicates.exr")
        sim = inimtrace.read_replicates(out / f"sim_{cell['method']}_{cell['eye_case']}.replicates.exr")
        assert gt.shape == (4, 32, 32, 3) and gt.dtype == np.float32
        # The replicates' mean is the image the run wrote (to f32 rounding of the mean).
        mean = read_exr(out / f"gt_{cell['eye_case']}.exr")[0]
        assert np.allclose(gt.astype(np.float64).mean(axis=0), mean, rtol=1e-6, atol=1e-7)
        ours = inimtrace.compare(gt, sim)
        assert ours["replicate_sets"] is True and ours["replicates"] == 4
        for metric, key in [("psnr_db", "psnr"), ("ssim", "ssim")]:
            assert ours[metric]["mean"] == cell[key]["mean"]
            assert ours[metric]["ci95"] == cell[key]["ci95"]
            assert [ours[metric][c] for c in "RGB"] == cell[key]["channels"]
            assert [ours[metric]["channels_ci95"][c] for c in "RGB"] == cell[key]["channels_ci95"]
    with pytest.raises(ValueError, match="replicate set"):
        inimtrace.compare(gt, sim[0])


def test_compare_of_single_images_warns_once_that_noise_biases_the_score():
    import subprocess
    import sys

    code = (
        "import warnings, numpy as np, inimtrace\n"
        "a = np.full((16, 16, 3), 0.25, np.float32)\n"
        "warnings.simplefilter('always')\n"
        "with warnings.catch_warnings(record=True) as w:\n"
        "    warnings.simplefilter('always')\n"
        "    inimtrace.compare(a, a + 0.1); inimtrace.compare(a, a + 0.2)\n"
        "print(len(w), 'biases PSNR and SSIM' in str(w[0].message), w[0].category.__name__)\n"
    )
    r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert r.stdout.split() == ["1", "True", "UserWarning"], r.stdout + r.stderr
