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
