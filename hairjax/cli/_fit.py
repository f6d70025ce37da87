"""`hairjax fit`: fit the shading model's parameters to target images (docs/fitting.md).

Exit code 0 when the fit converged, 3 when it stopped without converging (the step
limit, a diverging loss, a solver's failure), so a script can tell them apart.
"""

from __future__ import annotations

import argparse
import sys

from ._main import EXIT_NOT_CONVERGED
from ._outputs import (
    FILE_OVERHEAD,
    IMAGE_SUFFIXES,
    Output,
    check_free_space,
    check_outputs,
    image_bytes,
    written_together,
)

__all__ = ["run"]


def _outputs(args: argparse.Namespace) -> list[Output]:
    outputs = []
    if args.json is not None:
        outputs.append(Output(args.json, (".json",), "--json"))
    if args.out is not None:
        outputs.append(Output(args.out, IMAGE_SUFFIXES, "--out"))
    if args.plot is not None:
        outputs.append(Output(args.plot, (".png",), "--plot"))
    if args.save_scene is not None:
        outputs.append(Output(args.save_scene, (".toml",), "--save-scene"))
    return outputs


def _sizes(outputs: list[Output], scene) -> list[tuple[Output, int]]:
    """Each output's expected bytes: an image of the scene's size (the plot: three side
    by side), a small text file otherwise."""
    width, height = scene.camera.width, scene.camera.height
    sizes = {"--out": image_bytes, "--plot": lambda p, w, h: image_bytes(p, 3 * w, h)}
    return [
        (o, sizes[o.option](o.path, width, height) if o.option in sizes else FILE_OVERHEAD) for o in outputs
    ]


def fitted_scene(scene, result):
    """`scene` with `result`'s fitted parameters: the model's, and the light's direction
    and colour or the strands' opacity where the fit fitted them (a saved scene's shadows
    then follow the fitted light, where the fit held them at the scene's)."""
    import dataclasses

    import numpy as np

    scene = scene.replace(params=result.params)
    if result.light is not None and scene.light.kind == "directional":
        light = {
            # str of a NumPy scalar: the shortest decimal of the fitted float32 (or float64).
            k: tuple(float(str(x)) for x in np.asarray(v))
            for k, v in (("direction", result.light.direction), ("color", result.light.color))
            if v is not None
        }
        scene = scene.replace(light=dataclasses.replace(scene.light, **light))
    if result.alpha is not None:
        alpha = float(result.alpha)
        tables = dict(scene.file_tables or {})
        if "hair" in tables:
            tables["hair"] = {**tables["hair"], "alpha": alpha}
        scene = scene.replace(strands=scene.strands.replace(alpha=alpha), file_tables=tables)
    return scene


def _table(result, names, fittable) -> str:
    """The model's parameters, then the light's where fitted (light_direction's error is an
    angle in radians, docs/fitting.md)."""
    import numpy as np

    def fmt(v):
        return " ".join(f"{x:.6g}" for x in np.atleast_1d(np.asarray(v, float)))

    header = ("parameter", "initial", "fitted", "std. error")
    rows = []
    for name in (*fittable, *(n for n in names if n not in fittable)):
        se = result.std_error.get(name)
        se_text = "undetermined" if name in result.undetermined else "fixed" if name not in names else fmt(se)
        rows.append((name, fmt(result.get(name, initial=True)), fmt(result.get(name)), se_text))
    widths = [max(len(r[i]) for r in [header, *rows]) for i in range(4)]
    return "\n".join("  ".join(c.ljust(w) for c, w in zip(row, widths)) for row in [header, *rows])


def _mask_weights(masks, target_paths, targets) -> list | None:
    """Each --mask's weights (`read_mask`), paired with the --target at its position;
    None for targets without one. ImageError naming both files when their sizes differ."""
    from .._io._image import ImageError
    from .._io._mask import read_mask

    if not masks:
        return None
    weights: list = [None] * len(targets)
    for k, (mask, target_path, target) in enumerate(zip(masks, target_paths, targets)):
        weights[k] = read_mask(mask)
        (mh, mw), (th, tw) = weights[k].shape, target.shape[:2]
        if (mh, mw) != (th, tw):
            raise ImageError(f"{mask}: the mask is {mw}x{mh} but its target {target_path} is {tw}x{th}")
    return weights


def _check_counts(args: argparse.Namespace) -> None:
    """Each extra --scene, --holdout-scene and --mask has its target: FitError otherwise."""
    from .._fit import FitError

    if len(args.scenes) >= len(args.target):
        raise FitError(
            f"{1 + len(args.scenes)} scenes for {len(args.target)} targets: "
            "each extra --scene goes with one extra --target"
        )
    if len(args.holdout_scenes) > len(args.holdout):
        raise FitError(
            f"{len(args.holdout_scenes)} --holdout-scene for {len(args.holdout)} --holdout targets: "
            "each --holdout-scene goes with one --holdout"
        )
    if len(args.masks) > len(args.target):
        raise FitError(
            f"{len(args.masks)} --mask for {len(args.target)} --target: "
            "each --mask goes with the --target at the same position"
        )


def _fit_targets(args: argparse.Namespace, first, targets, weights):
    """The scenes and the `FitTargets`: the --target images with their --mask weights, the
    --holdout images with their scenes (the first scene for those without)."""
    from .._fit import FitTargets
    from .._io._image import read_image
    from ._scenes import load_cli_scene

    extra = [load_cli_scene(args, s) for s in args.scenes]
    scenes = [first, *extra, *[first] * (len(targets) - 1 - len(extra))]
    holdout = None
    if args.holdout:
        held = [read_image(t) for t in args.holdout]
        held_scenes = [load_cli_scene(args, s) for s in args.holdout_scenes]
        holdout = ([*held_scenes, *[first] * (len(held) - len(held_scenes))], held)
    return scenes, FitTargets(targets, weights=weights, holdout=holdout)


def _names(args: argparse.Namespace, fittable: tuple[str, ...]) -> tuple[str, ...]:
    """--fit's names (default the model's `fittable`); FitError for an unknown one. Each
    shading model has its parameters (docs/model.md §17 for Scheuermann's); any model also
    fits the light's (docs/fitting.md, "Fitting the light") and the strands' opacity, when
    named."""
    from .._fit import ALPHA, LIGHT_NAMES, FitError

    also = (*(("ambient",) if "ambient" not in fittable else ()), *LIGHT_NAMES, ALPHA)  # where named
    names = fittable if args.fit is None else tuple(n.strip() for n in args.fit.split(",") if n.strip())
    unknown = [n for n in names if n not in fittable + also]
    if unknown or not names:
        what = f"unknown parameter {unknown[0]!r}" if unknown else "no parameter"
        raise FitError(f"{what} in --fit; fittable: {', '.join(fittable + also)}")
    return names


def _summary(args: argparse.Namespace, result, names, fittable) -> None:
    """The parameters' table, how the fit stopped and its RMSE (held out too), on stdout."""
    print(_table(result, names, fittable))
    restarted = f" ({result.restarts} restarts)" if result.restarts else ""
    print(
        f"{result.termination} after {result.steps} steps{restarted}, {result.time_s:.2f} s "
        f"(+ {result.geometry_s:.2f} s geometry); RMSE {result.rmse:.4g}"
    )
    if result.holdout_rmse is not None:
        print(f"held-out RMSE {result.holdout_rmse:.4g} ({len(args.holdout)} target(s) the fit did not see)")


def _write(outputs: list[Output], first, result, target) -> None:
    """Every requested output, written together (none where one fails)."""
    import numpy as np

    image = None
    if any(o.option in ("--out", "--plot") for o in outputs):
        from .._fit import fitted_image

        image = np.asarray(fitted_image(first, result))
    with written_together([o.path for o in outputs]) as temps:
        for out, tmp in zip(outputs, temps):
            if out.option == "--json":
                from .._io._files import write_json

                write_json(tmp, result.to_json())
            elif out.option == "--save-scene":
                from .._scene._save import save_scene

                save_scene(fitted_scene(first, result), tmp)
            elif out.option == "--out":
                from .._io._image import write_image

                write_image(tmp, image)
            else:
                from .._io._view import side_by_side

                side_by_side(target, image, tmp, title=f"{first.name}: {result.termination}")


def run(args: argparse.Namespace) -> int:
    from .._fit import FitStop, FitVariables, fit, solver_named
    from .._io._image import read_image
    from .._progress import reporter
    from ._scenes import load_cli_scene

    _check_counts(args)
    outputs = _outputs(args)
    check_outputs(outputs)
    # Everything is read and checked before any rendering starts.
    images = [read_image(t) for t in args.target]
    weights = _mask_weights(args.masks, args.target, images)
    first = load_cli_scene(args, args.scene)
    check_free_space(_sizes(outputs, first))
    if args.save_scene is not None:  # a scene a file cannot describe is refused before the fit
        from .._scene._save import scene_data

        scene_data(first)
    scenes, targets = _fit_targets(args, first, images, weights)
    fittable = first.shading.fittable
    names = _names(args, fittable)

    if not args.quiet:
        print(f"fitting {', '.join(names)} with {args.solver} to {len(scenes)} target(s)", file=sys.stderr)
    with reporter("fit", quiet=args.quiet) as progress:

        def on_step(step, loss, elapsed):
            progress(step, args.max_steps, f"loss {loss:.6e}")

        result = fit(
            scenes,
            targets,
            solver_named(args.solver),
            variables=FitVariables(names),
            stop=FitStop(max_steps=args.max_steps),
            progress=on_step,
        )
    _summary(args, result, names, fittable)
    _write(outputs, first, result, images[0])
    if not args.quiet:
        for out in outputs:
            print(f"wrote {out.path}")
    return 0 if result.termination == "converged" else EXIT_NOT_CONVERGED
