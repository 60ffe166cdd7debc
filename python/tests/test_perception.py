"""Perceptual scores from Python (docs/PERCEPTION.md): `compare(scores=...)` on plain images and
on replicate sets, and `Assessment.scores`. Values, not only presence: an image against itself
scores JOD 10 and FLIP 0 exactly; more noise, a lower JOD and a higher FLIP; the luminance PSNR
is the PSNR of the BT.709 luminance; compare() of an assessment's own images (or of its replicate
sets) gives the assessment's scores; `Assessment.scores` holds the numbers of `results.json`."""

import json
import math

import numpy as np
import pytest

import inimtrace
from conftest import ROOT, SMALL_DISPLAY, SMALL_DISPLAY_ARGS, load_json

SCORES = ["cvvdp", "flip", "psnr-luminance"]
# A 48-pixel retina over tangents -0.06..0.06: about 7 pixels per degree.
SMALL_RETINA = {"eye.retina_resolution": 48, "eye.retina_half_tangent": 0.06}
SMALL_RETINA_ARGS = ["--set", "eye.retina_resolution=48", "--set", "eye.retina_half_tangent=0.06"]


def ppd(resolution=48, half_tangent=0.06):
    """The retina image's pixels per degree at its centre (docs/PERCEPTION.md)."""
    return resolution / (2 * half_tangent) * math.pi / 180


def scene(n=48, seed=3):
    """A textured image: smooth gradients and a few bars, values within 0.05..0.95."""
    rng = np.random.default_rng(seed)
    y, x = np.mgrid[0:n, 0:n] / n
    base = 0.5 + 0.3 * np.sin(6 * x + 2 * y)[..., None] * np.array([1.0, 0.8, 0.6])
    base[:, n // 3 : n // 3 + 3] = 0.9
    return np.clip(base + 0.02 * rng.standard_normal((n, n, 3)), 0.05, 0.95).astype(np.float32)


def test_an_image_against_itself_scores_jod_10_and_flip_0_exactly():
    a = scene()
    r = inimtrace.compare(a, a, scores=SCORES, ppd=ppd())
    assert r["cvvdp"] == 10.0 and r["flip"] == 0.0 and r["psnr_luminance_db"] == math.inf, r
    for k in ["cvvdp", "flip", "psnr_luminance_db"]:
        assert r[f"{k}_ci95"] is None and r[f"{k}_noise_bias"] is None, r


def test_more_noise_a_lower_jod_and_a_higher_flip():
    a = scene()
    noise = np.random.default_rng(7).standard_normal(a.shape).astype(np.float32)
    jods, flips = [], []
    for amplitude in [0.01, 0.03, 0.1]:
        b = np.clip(a + amplitude * noise, 0, None).astype(np.float32)
        r = inimtrace.compare(a, b, scores=["cvvdp", "flip"], ppd=ppd())
        jods.append(r["cvvdp"])
        flips.append(r["flip"])
    assert 10 > jods[0] > jods[1] > jods[2], jods
    assert 0 < flips[0] < flips[1] < flips[2] <= 1, flips


def test_luminance_psnr_is_the_psnr_of_the_bt709_luminance():
    a = scene()
    b = np.clip(a * np.array([1.05, 0.97, 1.1], dtype=np.float32), 0, None).astype(np.float32)
    r = inimtrace.compare(a, b, scores=["psnr-luminance"])
    w = np.array([0.2126, 0.7152, 0.0722])
    ya, yb = a.astype(np.float64) @ w, b.astype(np.float64) @ w
    expected = 10 * math.log10(1.0 / np.mean((ya - yb) ** 2))
    assert r["psnr_luminance_db"] == pytest.approx(expected, abs=1e-9)
    assert "cvvdp" not in r and "flip" not in r


def test_compare_of_an_assessments_images_gives_its_scores(cli, tmp_path):
    # The paper's experiment (thin-lens eye, grid estimator: its scores are of the images as they
    # are), small, at 200 cd/m^2, black 0.4 cd/m^2: compare() sees them on that display.
    exp = inimtrace.Experiment.load(
        ROOT / "experiments" / "paper.toml",
        set={
            **SMALL_DISPLAY,
            **SMALL_RETINA,
            "methods": ["LC", "LA"],
            "measurement.scores": ["psnr", "ssim", *SCORES],
            "display.photometry.peak_luminance": 200.0,
            "display.photometry.black_level": 0.4,
        },
    )
    result = inimtrace.assess(exp, tmp_path / "run")
    assert len(result.scores) == 8
    for s in result.scores:
        gt, sim = result.images[f"gt_{s['eye_case']}"], result.images[f"sim_{s['method']}_{s['eye_case']}"]
        r = inimtrace.compare(gt, sim, scores=["cvvdp", "flip"], peak_white=200.0, black=0.4, ppd=ppd())
        assert 0 < s["cvvdp"] < 10 and 0 < s["flip"] < 1, s
        assert r["cvvdp"] == pytest.approx(s["cvvdp"], abs=1e-5), (r, s)
        assert r["flip"] == pytest.approx(s["flip"], abs=1e-6), (r, s)
        assert r["psnr_db"]["mean"] == s["psnr_db"]
        # And the CLI's compare of the files written, which reads the pixels per degree from them.
        out = tmp_path / "run"
        files = [out / f"gt_{s['eye_case']}.exr", out / f"sim_{s['method']}_{s['eye_case']}.exr"]
        flags = ["--scores", "cvvdp,flip", "--peak-white", "200", "--black", "0.4", "--json"]
        cli_r = json.loads(cli("compare", *files, *flags).stdout)
        assert cli_r["perceptual"]["cvvdp"]["value"] == s["cvvdp"], (cli_r, s)
        assert cli_r["perceptual"]["flip"]["value"] == s["flip"], (cli_r, s)


def test_assessment_scores_are_results_json_and_replicate_sets_give_them(cli, tmp_path):
    # The converged estimator, small: one round of four replicates, LC and LA, one eye case.
    settings = {
        **SMALL_DISPLAY,
        **SMALL_RETINA,
        "methods": ["LC", "LA"],
        "eye_cases": [{"name": "Near", "focus_mm": 300.0}],
        "measurement.psnr_ci95_db": 5.0,
        "measurement.ssim_ci95": 0.5,
        "measurement.replicates": 4,
        "measurement.scores": ["psnr", "ssim", *SCORES],
    }
    path = ROOT / "experiments" / "paper-converged.toml"
    result = inimtrace.assess(inimtrace.Experiment.load(path, set=settings), tmp_path / "py")
    report = load_json(tmp_path / "py" / "results.json")
    assert len(result.scores) == len(report["scores"]) == 2
    for s, j in zip(result.scores, report["scores"]):
        assert (s["method"], s["eye_case"]) == (j["method"], j["eye_case"])
        for name, key in [("cvvdp", "cvvdp"), ("flip", "flip"), ("psnr-luminance", "psnr_luminance_db")]:
            e = j["perceptual"][name]
            assert s[key] == e["value"] and s[f"{key}_ci95"] == e["ci95"], (name, s, e)
            assert s[f"{key}_ci95"] > 0, (name, s)
            # The luminance PSNR is freed of noise bias as PSNR is: no removed bias to report.
            assert s[f"{key}_noise_bias"] == e.get("noise_bias"), (name, s, e)
        assert s["cvvdp_noise_bias"] is not None and s["flip_noise_bias"] is not None, s

    # The same cell from the CLI's replicate sets: compare() gives the table's de-biased scores
    # with their intervals, bit for bit.
    args = [f"{k}={v}" for k, v in settings.items() if not isinstance(v, (list, dict))]
    lists = ['methods=["LC", "LA"]', 'eye_cases=[{ name = "Near", focus_mm = 300.0 }]',
             'measurement.scores=["psnr", "ssim", "cvvdp", "flip", "psnr-luminance"]']
    sets = [x for a in args + lists if not a.startswith("display.lcd") for x in ("--set", a)]
    out = tmp_path / "cli"
    cli("assess", path, "--out", out, "--keep-replicates", *SMALL_DISPLAY_ARGS, *sets)
    table = load_json(out / "results.json")["scores"]
    gt = inimtrace.read_replicates(out / "gt_Near.replicates.exr")
    for cell in table:
        sim = inimtrace.read_replicates(out / f"sim_{cell['method']}_Near.replicates.exr")
        r = inimtrace.compare(gt, sim, scores=["cvvdp", "flip"], peak_white=100.0, black=0.1, ppd=ppd())
        for name in ["cvvdp", "flip"]:
            e = cell["perceptual"][name]
            assert (r[name], r[f"{name}_ci95"], r[f"{name}_noise_bias"]) == (e["value"], e["ci95"], e["noise_bias"])

