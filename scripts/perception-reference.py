#!/usr/bin/env python3
"""Scores image pairs with the perceptual metrics' reference implementations, for
tests/perception_reference.rs: NVIDIA's FLIP (`pip install flip-evaluator`) and the authors'
ColorVideoVDP (`pip install cvvdp`, PyTorch on the CPU).

    perception-reference.py MANIFEST.json [flip] [cvvdp]

MANIFEST lists pairs: {"name", "width", "height", "ppd", "peak", "contrast", "ambient_lux",
"reflectance", "flip_test", "flip_reference", "cvvdp_test", "cvvdp_reference"}, each image a file
of little-endian float32, height x width x 3 (row 0 at the top): exactly what inimtrace hands
each metric (FLIP: absolute linear RGB in cd/m^2; ColorVideoVDP: the panel's BT.709 linear RGB
in cd/m^2, its black included; the display model adds the reflected ambient light). Prints one
JSON object per pair: {"name", "flip": mean HDR-FLIP, "cvvdp": JOD}.
"""
import json
import sys

import numpy as np


def image(path, pair):
    return np.fromfile(path, dtype="<f4").reshape(pair["height"], pair["width"], 3)


def main():
    manifest = json.load(open(sys.argv[1]))
    which = set(sys.argv[2:]) or {"flip", "cvvdp"}
    if "flip" in which:
        import flip_evaluator as flip
    if "cvvdp" in which:
        import pycvvdp
        import torch

        torch.set_num_threads(2)
    for pair in manifest:
        out = {"name": pair["name"]}
        if "flip" in which:
            ref, test = image(pair["flip_reference"], pair), image(pair["flip_test"], pair)
            _, mean, _ = flip.evaluate(ref, test, "HDR", applyMagma=False, parameters={"ppd": pair["ppd"]})
            out["flip"] = float(mean)
        if "cvvdp" in which:
            ref, test = image(pair["cvvdp_reference"], pair), image(pair["cvvdp_test"], pair)
            photometry = pycvvdp.vvdp_display_photo_eotf(
                pair["peak"],
                contrast=pair["contrast"],
                source_colorspace="BT.709-linear",
                E_ambient=pair["ambient_lux"],
                k_refl=pair["reflectance"],
            )
            geometry = pycvvdp.vvdp_display_geometry([pair["width"], pair["height"]], ppd=pair["ppd"])
            metric = pycvvdp.cvvdp(
                display_name="standard_4k",
                display_photometry=photometry,
                display_geometry=geometry,
                quiet=True,
                device=torch.device("cpu"),
            )
            with torch.no_grad():
                jod, _ = metric.predict(torch.from_numpy(test), torch.from_numpy(ref), dim_order="HWC")
            out["cvvdp"] = float(jod)
        print(json.dumps(out), flush=True)


if __name__ == "__main__":
    main()
