"""Single scattering, one fibre at a time: `marschner` against Mitsuba's hair BSDF.

Six separated, leaning, gently curved fibres 0.06 world units wide, path traced by Mitsuba 3
with `max_depth` 2 (direct light only, so no light passes between fibres and both sides
compute one scattering event), against `hj.Marschner` with Karis's closed forms and with
Chiang's far field (`azimuthal = "chiang"`, 64 nodes) on the same strands, camera and light
(docs/model.md §19). Printed per case: the mean RGB over the fibres' pixels (where the
model's coverage is over ½), model ÷ Mitsuba. The cases are lights from the front, the side
and behind (travelling towards the eye), hair colours from Mitsuba's examples, the scales'
tilt 3° (and the model's tilt of the wrong sign, which the front-lit ratio tells apart).

    python experiments/20_fibre_against_mitsuba.py            # 96², 256 spp: docs/model.md §19
    python experiments/20_fibre_against_mitsuba.py --quick    # 32², 16 spp, two cases
"""

from __future__ import annotations

import argparse
import sys
import time
from typing import NamedTuple

import numpy as np

import hairjax as hj

TILT = 3.0  # degrees, the scales' tilt of both sides


class Case(NamedTuple):
    light: str  # a key of LIGHTS
    colour: str  # a key of COLOURS
    beta: float  # longitudinal roughness β_m
    model_tilt: float = TILT  # the model's tilt (−TILT: the wrong sign)


# Directions the light travels in; the camera looks down −z from z = 3.5.
LIGHTS = {
    "front": (-0.3, -0.4, -1.0),
    "side": (1.0, -0.4, 0.0),
    "behind": (0.3, -0.4, 1.0),
    "behind, low": (0.1, -0.1, 1.0),
}
COLOURS = {"blonde": (0.3, 0.0), "brown": (1.3, 0.2), "black": (8.0, 0.0), "red": (0.1, 1.2)}
CASES = (
    Case("front", "blonde", 0.2),
    Case("front", "blonde", 0.2, -TILT),
    Case("front", "black", 0.3),
    Case("side", "blonde", 0.2),
    Case("side", "red", 0.2),
    Case("behind", "blonde", 0.2),
    Case("behind", "brown", 0.4),
    Case("behind, low", "blonde", 0.2),
)


def fibres() -> hj.Strands:
    """Six separated, leaning, gently curved fibres 0.06 world units wide."""
    t = np.linspace(-1.0, 1.0, 24)
    pieces = [
        np.stack([x + (i - 2.5) * 0.15 * t, t, 0.2 * np.sin(1.5 * t + i)], axis=1)
        for i, x in enumerate(np.linspace(-0.8, 0.8, 6))
    ]
    offsets = np.arange(7) * len(t)
    return hj.Strands(np.concatenate(pieces), offsets, alpha=1.0, width=0.06, width_units="world")


def scene(case: Case, size: int, azimuthal: str) -> hj.Scene:
    eu, pheo = COLOURS[case.colour]
    params = hj.MarschnerParams(
        eumelanin=eu, pheomelanin=pheo, longitudinal_roughness=case.beta, tilt=case.model_tilt, kappa=0.0
    )
    return hj.Scene(
        strands=fibres(),
        camera=hj.Camera(eye=(0.0, 0.0, 3.5), target=(0.0, 0.0, 0.0), fov=40.0, width=size, height=size),
        light=hj.Light(direction=LIGHTS[case.light]),
        shading=hj.Marschner(params, azimuthal=azimuthal),
        shadows=hj.Shadows("none"),
        reference=hj.ReferenceSettings(
            eumelanin=eu, pheomelanin=pheo, longitudinal_roughness=case.beta, scale_tilt=TILT, max_depth=2
        ),
    )


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--size", type=int, default=96)
    p.add_argument("--spp", type=int, default=256)
    p.add_argument("--quick", action="store_true", help="32², 16 spp, the first and the back-lit case")
    args = p.parse_args(argv)
    cases = CASES
    if args.quick:
        args.size, args.spp, cases = 32, 16, (CASES[0], CASES[5])
    print(f"fibres against Mitsuba: {args.size}², {args.spp} spp, max_depth 2; model ÷ Mitsuba, mean RGB")
    print("| light | hair, β_m | model tilt | Karis | Chiang (64 nodes) |")
    print("|---|---|---|---|---|")
    started = time.perf_counter()
    for case in cases:
        karis = scene(case, args.size, "karis")
        reference = hj.reference_image(karis, spp=args.spp, seed=0)
        image = np.asarray(hj.render(karis))
        covered = image[..., 3] > 0.5
        mean_ref = reference[covered, :3].mean(axis=0)
        chiang = np.asarray(hj.render(scene(case, args.size, "chiang")))
        ratios = [image[covered, :3].mean(axis=0) / mean_ref, chiang[covered, :3].mean(axis=0) / mean_ref]
        cells = [", ".join(f"{x:.2f}" for x in r) for r in ratios]
        print(
            f"| {case.light} | {case.colour}, {case.beta} | {case.model_tilt:g}° | {cells[0]} | {cells[1]} |",
            flush=True,
        )
    print(f"total {time.perf_counter() - started:.1f} s")
    return 0


if __name__ == "__main__":
    sys.exit(main())
