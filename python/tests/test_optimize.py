"""OPT from Python (docs/OPTIMAL.md): an experiment that names OPT with an [optimize] table runs
through `assess`, its convergence record is the Assessment's `optimization`, and it is what the
solver promises: the objective never increases, the display image lies in [0, 1], and on its
training state OPT's grid PSNR is at least LA's (LA's image is where it starts)."""

import numpy as np
import pytest

import inimtrace

# A tiny problem: a 60 x 60 LCD, a 16 x 16 retina, a 2 x 2 pupil grid, two eye cases (one
# trained on, one held out) and the grid estimator (its samples are OPT's when the retina and
# pupil grid agree).
TINY = {
    "display.lcd.resolution": [60, 60],
    "eye.retina_resolution": 16,
    "eye.pupil_grid": 2,
    "methods": ["LA", "OPT"],
    "optimize.train_cases": ["Cen"],
    "optimize.iterations": 8,
    "optimize.tolerance": 0.0,
    "optimize.solver": "fista",
}


def tiny_experiment():
    exp = inimtrace.Experiment.paper_grid(set=TINY)
    assert exp.methods == ["LA", "OPT"]
    return exp


def test_opt_runs_from_python_with_its_convergence_record(tmp_path):
    exp = tiny_experiment()
    assert exp.settings()["optimize"]["train_cases"] == ["Cen"]
    result = inimtrace.assess(exp, out=tmp_path)
    rec = result.optimization
    assert rec is not None and rec == result.report["optimization"]
    assert rec["method"] == "OPT" and rec["solver"] == "fista" and rec["initial"].startswith("LA")
    assert [name for name, _ in rec["states"]] == ["Cen"]
    its = rec["iterations"]
    assert its[0]["iteration"] == 0 and 1 < len(its) <= 9
    objective = [i["objective"] for i in its]
    assert all(b <= a for a, b in zip(objective, objective[1:])), objective
    assert objective[-1] < objective[0]
    assert sum(rec["final_mse"]) <= sum(rec["initial_mse"])
    image = result.images["display_OPT"]
    assert image.shape == (60, 60, 3) and image.min() >= 0.0 and image.max() <= 1.0
    assert result.score("OPT", "Cen")["psnr_db"] >= result.score("LA", "Cen")["psnr_db"] - 1e-9
    # The CLI's convergence files are written beside the images.
    assert (tmp_path / "optimize_OPT.csv").is_file() and (tmp_path / "optimize_OPT.png").is_file()


def test_without_opt_there_is_no_record_and_a_stray_optimize_table_is_refused():
    plain = inimtrace.Experiment.paper_grid(
        set={**{k: v for k, v in TINY.items() if not k.startswith("optimize")}, "methods": ["LA"]}
    )
    assert inimtrace.assess(plain).optimization is None
    with pytest.raises(inimtrace.ConfigError, match="optimize"):
        inimtrace.Experiment.paper_grid(set={**TINY, "methods": ["LA"]})


def small_opt_experiment(tmp_path, display, extra=""):
    """LC, LA 3 x 3 and OPT on the repository's `display` with a 108 x 108 LCD, a 20 x 20 retina,
    trained on Pin and Cen with a 3 x 3 pupil grid (one sample per retina pixel, as the grid
    estimator's), Far held out; `extra` is added to the experiment file."""
    from conftest import ROOT

    path = tmp_path / "opt.toml"
    path.write_text(
        f'name = "opt"\nscene = "{ROOT / "scenes/paper.toml"}"\ndisplay = "{ROOT / "displays" / display}"\n'
        f'methods = ["LC", "LA3", "OPT"]\n{extra}\n'
        "[eye]\nretina_resolution = 20\n\n"
        '[[eye_cases]]\nname = "Pin"\npinhole = true\n\n[[eye_cases]]\nname = "Cen"\nfocus_mm = 400.0\n\n'
        '[[eye_cases]]\nname = "Far"\nfocus_mm = 600.0\n\n'
        '[optimize]\ntrain_cases = ["Pin", "Cen"]\niterations = 12\ntolerance = 0.0\npupil_grid = 3\n'
        "pinhole_retina_samples = 1\n"
    )
    return inimtrace.Experiment.load(path, set={"display.lcd.resolution": [108, 108]})


def check_opt_is_its_own_image_and_gains_on_its_training_states(result):
    lc, la, opt = (result.images[f"display_{m}"] for m in ("LC", "LA3", "OPT"))
    assert np.count_nonzero(np.any(opt != lc, axis=2)) > lc.shape[0] * lc.shape[1] // 10, "OPT is LC's image"
    assert np.any(opt != la), "OPT never left LA's image"
    assert opt.min() >= 0.0 and opt.max() <= 1.0
    rec = result.optimization
    assert [name for name, _ in rec["states"]] == ["Pin", "Cen"]
    assert all(a <= b for a, b in zip(rec["final_mse"], rec["initial_mse"])), rec


def test_opt_through_real_lenslets_beats_la_on_its_training_cases(tmp_path):
    result = inimtrace.assess(small_opt_experiment(tmp_path, "paper-pmma.toml"), threads=2)
    check_opt_is_its_own_image_and_gains_on_its_training_states(result)
    # The grid estimator sees OPT's own samples there: Table 1 is the training objective.
    for case in ("Pin", "Cen"):
        assert result.score("OPT", case)["psnr_db"] >= result.score("LA3", case)["psnr_db"] - 1e-6


def test_opt_with_diffraction_at_the_apertures_through_real_lenslets(tmp_path):
    extra = (
        '[optics]\ndiffraction = "apertures"\n\n[measurement]\nestimator = "converged"\npsnr_ci95_db = 5.0\n'
        "ssim_ci95 = 0.5\nmax_samples_per_pixel = 12\nreplicates = 3\nmax_seconds = 60.0\n"
    )
    exp = small_opt_experiment(tmp_path, "paper-pmma.toml", extra)
    assert exp.settings()["optics"]["diffraction"] == "apertures"
    check_opt_is_its_own_image_and_gains_on_its_training_states(inimtrace.assess(exp, threads=2))
