"""inimtrace: how a near-eye integral-imaging light-field display looks to a human eye.

The paper's pipeline (O. Doronin, E. Sahin, R. Bregovic and A. Gotchev, "A framework for
assessing rendering techniques for near-eye integral imaging displays", ICIP 2020) with NumPy
arrays in and out. Every function runs the same library code as the CLI command of the same name, so its outputs equal the CLI's bit for bit:

    import inimtrace
    scene, display = inimtrace.Scene.paper(), inimtrace.Display.paper()
    img = inimtrace.render_display(scene, display, method="LA")        # (2160, 2160, 3) float32
    eye = inimtrace.Eye(focus_mm=400, pupil=5)
    sim = inimtrace.simulate(img, display, eye)                        # (512, 512, 3) float32
    gt = inimtrace.ground_truth(scene, eye)
    inimtrace.compare(sim, gt)["psnr_db"]["mean"]

    exp = inimtrace.Experiment.load("experiments/paper.toml", set={"eye.pupil_diameter": 3})
    result = inimtrace.assess(exp)                 # scores, images, stage times
    pandas.DataFrame(result.scores)

Units are millimetres; images are (rows, columns, 3) float32 arrays of linear radiance, row 0 at
the top. Rendering releases the GIL; `threads=` sets the worker threads of one call (default:
all cores); `progress=` takes a callable `progress(stage, done, total)`; Ctrl-C stops a call
within a second (KeyboardInterrupt). Errors raise `inimtrace.Error` subclasses with the CLI's
messages (`OutOfMemoryError` is also a `MemoryError`). See docs/PYTHON.md.
"""

from dataclasses import dataclass, field
from os import PathLike
from typing import Any, Callable, Dict, List, Optional, Union

from ._inimtrace import (
    ConfigError,
    Display,
    Error,
    Experiment,
    Eye,
    ImageError,
    MeshError,
    OpticsError,
    OutOfMemoryError,
    Scene,
    __version__,
    _assess,
    _resolution,
    compare,
    git_revision,
    ground_truth,
    has_embree,
    read_exr,
    read_replicates,
    render_display,
    simulate,
)

__all__ = [
    "Assessment",
    "ConfigError",
    "Display",
    "Error",
    "Experiment",
    "Eye",
    "ImageError",
    "MeshError",
    "OpticsError",
    "OutOfMemoryError",
    "Scene",
    "__version__",
    "assess",
    "compare",
    "git_revision",
    "ground_truth",
    "has_embree",
    "read_exr",
    "read_replicates",
    "render_display",
    "Resolution",
    "resolution",
    "simulate",
]


@dataclass
class Assessment:
    """What `assess` computed.

    scores: one record per method and eye case (a list of dicts that `pandas.DataFrame` takes as
        it is): `experiment`, `method`, `eye_case`, `psnr_db`, `psnr_ci95_db`, `ssim`, `ssim_ci95`
        (the mean over R, G, B and the 95% half-width, None for the grid estimator), the same per
        channel (`psnr_db_R`, `ssim_ci95_G`, ...), and for the converged estimator
        `samples_per_pixel`, `replicates`, `target_met`; the scores `[measurement] scores` names
        beyond PSNR and SSIM as `cvvdp` (JOD), `flip`, `psnr_luminance_db`, each with `_ci95` and
        `_noise_bias` (docs/PERCEPTION.md). The numbers of `results.json`.
    images: the images by the stem of the file `inimtrace assess` writes: `display_LA`,
        `gt_Pin`, `sim_LA_Pin`, ... as (rows, columns, 3) float32 arrays.
    depths: the display images' `Z` channel by stem (`display_LA`), (rows, columns) float32,
        or None where the backend knows no depths.
    stages: the wall time of every stage: records with `stage`, `method`, `eye_case`, `seconds`.
    report: everything `results.json` holds (tool, settings, display, backend, threads, ...).
    out: the folder the files were written to, or None.
    optimization: when the methods list OPT, its convergence record (`optimization` of
        `results.json`): `solver`, `initial`, the training `states` (name, weight), each state's
        training `initial_mse` and `final_mse`, `stop`, and `iterations` (records of `iteration`,
        `objective`, `projected_gradient`, `step`, `seconds`; iteration 0 is the start); else None.
    provenance: where the scores come from, as `results.json`'s `provenance`: `scene_name`,
        `scene_path` (as the experiment gives it), `experiment_path` and `display_path` (as
        given), `files` (every file read to set the run up: `path`, `sha256`, `bytes`), `set`
        (the `set=` overrides as `KEY=VALUE`), `budgets` (estimator, targets, sample and time
        budgets, memory), `seed` (an int) and `working_directory`.
    """

    scores: List[Dict[str, Any]]
    images: Dict[str, Any]
    depths: Dict[str, Any]
    stages: List[Dict[str, Any]]
    report: Dict[str, Any] = field(repr=False)
    out: Optional[str] = None
    optimization: Optional[Dict[str, Any]] = field(default=None, repr=False)
    provenance: Dict[str, Any] = field(default_factory=dict, repr=False)

    def score(self, method: str, eye_case: str) -> Dict[str, Any]:
        """The score record of one method under one eye case."""
        for s in self.scores:
            if s["method"] == method and s["eye_case"] == eye_case:
                return s
        raise KeyError(f"no score for method {method!r} and eye case {eye_case!r}")


def assess(
    experiment: Experiment,
    out: Union[str, "PathLike[str]", None] = None,
    backend: str = "auto",
    *,
    exr_compression: str = "zip",
    threads: Optional[int] = None,
    progress: Optional[Callable[[str, int, int], Any]] = None,
) -> Assessment:
    """Runs `experiment` as `inimtrace assess` does, returning its scores, images and stage times.

    With `out`, also writes every file the CLI writes there (EXR + PNG previews, table.md,
    results.csv, results.json, figure.png); the arrays and scores are the same either way.
    `backend` is auto, analytic, embree, bvh or brute.
    """
    r = _assess(experiment, out, backend, exr_compression=exr_compression, threads=threads, progress=progress)
    return Assessment(
        scores=r["scores"],
        images=r["images"],
        depths=r["depths"],
        stages=r["stages"],
        report=r["report"],
        out=r["out"],
        optimization=r["report"].get("optimization"),
        provenance=r["report"]["provenance"],
    )


@dataclass
class Resolution:
    """What `resolution` wrote: the output folder and the study's tables as records (lists of
    dicts that `pandas.DataFrame` accepts as they are; numbers as floats)."""

    out: str
    mtf: List[Dict[str, Any]]
    mtf50: List[Dict[str, Any]]
    accommodation: List[Dict[str, Any]]
    display: Dict[str, Any]
    timings: List[Dict[str, Any]] = field(default_factory=list)


# Columns of the study's CSV files that are counts: ints, as the assessment's records give them.
_COUNT_COLUMNS = frozenset({"samples_per_pixel", "replicates"})


def _records(path: str) -> List[Dict[str, Any]]:
    import csv

    def value(k: str, v: str) -> Any:
        try:
            return int(v) if k in _COUNT_COLUMNS else float(v)
        except ValueError:
            return v

    with open(path, newline="") as f:
        return [{k: value(k, v) for k, v in row.items()} for row in csv.DictReader(f)]


def resolution(
    study: Optional[Union[str, "PathLike[str]"]] = None,
    out: Optional[Union[str, "PathLike[str]"]] = None,
    set: Optional[Any] = None,
    *,
    threads: Optional[int] = None,
    progress: Optional[Callable[[str, int, int], None]] = None,
) -> Resolution:
    """Runs a resolution study exactly as `inimtrace resolution [STUDY] --out OUT` (the same code
    path and files): MTF in cycles per degree, through-focus contrast, predicted accommodation
    and the display's limits. `study=None` is the built-in `studies/paper.toml`; `set` takes the
    same overrides as `--set`. The GIL is released while it runs."""
    import json
    import os

    r = _resolution(study, out, set, threads=threads, progress=progress)
    d = r["out"]
    with open(os.path.join(d, "display.json")) as f:
        display = json.load(f)
    return Resolution(
        out=d,
        mtf=_records(os.path.join(d, "mtf.csv")),
        mtf50=_records(os.path.join(d, "mtf50.csv")),
        accommodation=_records(os.path.join(d, "accommodation.csv")),
        display=display,
        timings=r["timings"],
    )
