"""The paper's experiment at several pupil diameters: PSNR of each method against the pupil.

    pip install . matplotlib pandas            # at the repository root
    python python/examples/pupil_psnr.py       # writes pupil_psnr.png; --quick: small images

Loads experiments/paper.toml (the paper's settings, grid estimator), changes the pupil with
`set=` (the CLI's --set eye.pupil_diameter=...), runs each assessment in memory and plots the
mean PSNR of LC, PC and LA over the focused eye cases against the pupil diameter.
"""

import argparse
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import pandas as pd

import inimtrace

ROOT = Path(__file__).resolve().parents[2]

parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
parser.add_argument("--quick", action="store_true", help="540 x 540 LCD, 128 x 128 retina")
parser.add_argument("--out", default="pupil_psnr.png")
args = parser.parse_args()

small = {"display.lcd.resolution": [540, 540], "eye.retina_resolution": 128} if args.quick else {}
rows = []
for pupil in [2.0, 3.0, 4.0, 5.0, 6.0]:
    exp = inimtrace.Experiment.load(ROOT / "experiments" / "paper.toml", set={**small, "eye.pupil_diameter": pupil})
    result = inimtrace.assess(exp, progress=None)
    rows += [{**score, "pupil_mm": pupil} for score in result.scores]
    print(f"pupil {pupil} mm: {len(result.scores)} scores")

df = pd.DataFrame(rows)
focused = df[df.eye_case != "Pin"].groupby(["method", "pupil_mm"]).psnr_db.mean().unstack("method")
print(focused.round(2))
ax = focused[["LC", "PC", "LA"]].plot(marker="o")
ax.set_xlabel("pupil diameter (mm)")
ax.set_ylabel("PSNR (dB), mean of Near, Cen, Far")
ax.set_title("The paper's experiment: PSNR against the pupil")
plt.savefig(args.out, dpi=120, bbox_inches="tight")
print(f"wrote {args.out}")
