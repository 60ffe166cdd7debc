"""What a Python result says about where it comes from and how precise it is: `assess`'s
provenance is results.json's (the CLI's, for the same experiment and overrides), its seed a
number; every score carries its interval, samples per pixel and whether its target was met; and
the CLI's unit-mistake warnings reach Python as `UserWarning`s naming the field and the unit."""

import json
import warnings

import inimtrace
import pytest

from conftest import ROOT

EXPERIMENT = str(ROOT / "experiments" / "paper-converged.toml")
TINY = {
    "display.lcd.resolution": [108, 108],
    "eye.retina_resolution": 16,
    "measurement.max_samples_per_pixel": 64,
    "methods": ["LC"],
}
TINY_ARGS = [
    "--set", "display.lcd.resolution=[108, 108]",
    "--set", "eye.retina_resolution=16",
    "--set", "measurement.max_samples_per_pixel=64",
    "--set", 'methods=["LC"]',
]


def without_machine(p):
    """A provenance less what depends on the machine and the moment: the memory budget (read from
    the free memory) and the working directory."""
    p = json.loads(json.dumps(p))
    p["budgets"].pop("memory_bytes")
    p.pop("working_directory")
    return p


def test_assess_carries_the_clis_provenance(cli, tmp_path):
    exp = inimtrace.Experiment.load(EXPERIMENT, set=TINY)
    result = inimtrace.assess(exp, tmp_path / "py")
    p = result.provenance
    # The same record as the results.json this very call wrote ...
    with open(tmp_path / "py" / "results.json") as f:
        assert json.load(f)["provenance"] == p
    # ... and as the CLI's for the same experiment and overrides.
    cli("assess", EXPERIMENT, *TINY_ARGS, "--out", tmp_path / "cli")
    with open(tmp_path / "cli" / "results.json") as f:
        theirs = json.load(f)["provenance"]
    assert without_machine(p) == without_machine(theirs)
    assert p["experiment_path"] == EXPERIMENT and p["scene_path"] == "../scenes/paper.toml"
    assert p["scene_name"] == exp.scene.name
    assert isinstance(p["seed"], int) and not isinstance(p["seed"], bool)
    assert p["set"] == ["display.lcd.resolution=[108, 108]", "eye.retina_resolution=16",
                        "measurement.max_samples_per_pixel=64", 'methods=["LC"]']
    assert p["budgets"]["estimator"] == "converged" and p["budgets"]["max_samples_per_pixel"] == 64
    hashed = {f["path"]: f["sha256"] for f in p["files"]}
    assert EXPERIMENT in hashed and all(len(h) == 64 for h in hashed.values())
    assert any(path.endswith("scenes/paper.toml") for path in hashed)
    # Every score: its interval, samples per pixel, replicates and whether the target was met.
    for s in result.scores:
        assert s["psnr_ci95_db"] > 0 and s["ssim_ci95"] > 0, s
        assert isinstance(s["samples_per_pixel"], int) and 0 < s["samples_per_pixel"] <= 64, s
        assert isinstance(s["replicates"], int) and s["replicates"] >= 2, s
        assert isinstance(s["target_met"], bool), s


def test_a_built_in_experiment_has_a_provenance_too():
    exp = inimtrace.Experiment.paper_grid(set={"display.lcd.resolution": [108, 108], "eye.retina_resolution": 16,
                                               "eye.pupil_grid": 2, "methods": ["LC"]})
    p = inimtrace.assess(exp).provenance
    assert p["experiment_path"] is None and p["scene_path"] == "builtin:paper"
    assert p["budgets"]["estimator"] == "grid" and isinstance(p["seed"], int)


@pytest.mark.parametrize(
    "key, value, field, unit",
    [
        ("display.lenslets.pitch", 1200, "lenslets.pitch", "micrometres? 1200 µm = 1.2 mm"),
        ("display.lenslets.focal_length", 0.006427, "lenslets.focal_length", "metres? 0.006427 m = 6.427 mm"),
        ("display.lcd.size", [2.16, 2.16], "lcd.size", "centimetres? 2.16 cm = 21.6 mm"),
        ("eye_cases[1].focus_mm", 1.5, "eye_cases[1].focus_mm", "metres? 1.5 m = 1500 mm"),
    ],
)
def test_unit_mistakes_warn_as_the_cli_does(key, value, field, unit):
    with pytest.warns(UserWarning) as caught:
        inimtrace.Experiment.load(str(ROOT / "experiments" / "paper.toml"), set={key: value})
    lines = [str(w.message) for w in caught if field in str(w.message)]
    assert len(lines) == 1 and unit in lines[0], [str(w.message) for w in caught]


def test_display_eye_and_resolution_warn_too(tmp_path):
    with pytest.warns(UserWarning, match=r"lenslets\.pitch = 1200 mm .* micrometres"):
        inimtrace.Display.paper(set={"display.lenslets.pitch": 1200})
    with pytest.warns(UserWarning, match=r"focus_mm = 1\.5 mm .* metres\? 1\.5 m = 1500 mm"):
        inimtrace.Eye(focus_mm=1.5)
    with pytest.warns(UserWarning, match=r"pupil_diameter_mm = 0\.9 mm .* centimetres"):
        inimtrace.resolution(ROOT / "studies" / "tiny.toml", tmp_path / "r", set={"pupil_diameter_mm": 0.9})
    # The paper's own files: no warning.
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        inimtrace.Experiment.load(str(ROOT / "experiments" / "paper.toml"))
        inimtrace.Display.paper()
        inimtrace.Eye(focus_mm=400)
        inimtrace.Eye(pinhole=True)
