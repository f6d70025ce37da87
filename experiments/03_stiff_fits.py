"""Stiff fits: each solver on needle-thin highlights, saturated shadows, Ks ≈ 0 and far starts.

The table of docs/results.md §5 (the solvers: docs/fitting.md). For every case a
noise-free target is rendered with the JAX renderer (`hj.render(scene, truth)`) and each
solver fits all four parameters (Kd RGB, Ks, shininess, κ; `ks-zero-held` holds Ks) from
the case's start with `hj.fit`. Cases:

- `reference`: moderate truth and start (a control: every solver should converge here);
- `shininess-1000`: p = 1500 (needle-thin highlights) from p = 40;
- `kappa-50`: κ = 75 (saturated shadows: only the outer layer is lit) from κ = 2;
- `ks-zero`: Ks = 0, so the shininess has no effect and should come back undetermined; Ks
  is judged by its absolute error (its relative error is undefined). Ks is fitted: solved
  for (the default) it can be exactly 0; searched (`--no-separable`) it only approaches 0
  (softplus(z) → 0 as z → −∞);
- `ks-zero-held`: the same target, Ks held at 0 and Kd, p, κ fitted: here the image does
  not depend on p at all, and `hj.fit` reports it undetermined (tests/fit/test_fit.py);
- `start-x100`, `start-x0.01`: the reference truth, every parameter starting 100 times and
  0.01 times its true value;
- `combined`: p = 1200 and κ = 60 together, from a start 10 times too low.

A fit's status is `converged` (the solver reports convergence and every determined
parameter is within `--tol` relative error of the truth), `stopped: <reason>` (the solver
stopped and said why: max_steps, a non-finite loss, an optimistix failure), or a failure:
`wrong: …` (reported convergence at a point off the truth, or with a parameter that should
be determined left undetermined) or `error: …` (an exception; it is caught and recorded).
Only fitted parameters are judged, and not those a case expects to be undetermined (the
shininess of `ks-zero`; when the fit does not flag it, the status says so). The worst error
is over the rest that are not in `FitResult.undetermined`; an undetermined parameter counts
as wrong only when it is off the truth as well (a Ks pushed into the softplus's flat tail
is undetermined, and right where the truth is 0).

The RMSE reported is that of the returned parameters, rendered afresh against the target
(`fit_rmse` is `FitResult.rmse`, which is NaN after a diverged step although the point
kept is finite; the status then says so).

    python experiments/03_stiff_fits.py                    # 2000 strands at 128², float32
    python experiments/03_stiff_fits.py --x64              # the same in float64
    python experiments/03_stiff_fits.py --no-separable     # the solver searches Kd, Ks too
    python experiments/03_stiff_fits.py --quick            # tiny, for the test suite

Writes DIR/stiff_fits.csv (one row per fit) and DIR/stiff_fits.md (the table), and prints
the table.
"""

from __future__ import annotations

import argparse
import statistics
import sys
import time
from pathlib import Path
from typing import NamedTuple

import numpy as np

PARAMS = ("kd", "ks", "shininess", "kappa")
SOLVERS = ("levenberg-marquardt", "gauss-newton", "dogleg", "bfgs")
SHORT = {"levenberg-marquardt": "LM", "gauss-newton": "GN", "dogleg": "dogleg", "bfgs": "BFGS"}
CSV_COLUMNS = (
    "case",
    "solver",
    "dtype",
    "fitted",
    "steps",
    "time_s",
    "step_ms",
    "wall_s",
    "termination",
    "status",
    "failure",
    "rmse",
    "fit_rmse",
    "worst_error",
    *(f"err_{n}" for n in PARAMS),
    "undetermined",
    "expected_undetermined",
    *(f"true_{n}" for n in PARAMS),
    *(f"start_{n}" for n in PARAMS),
    *(f"fit_{n}" for n in PARAMS),
)


class Case(NamedTuple):
    name: str
    truth: dict
    start: dict
    expect_undetermined: tuple[str, ...] = ()
    fit: tuple[str, ...] = PARAMS


REFERENCE = dict(kd=(0.5, 0.35, 0.2), ks=0.4, shininess=60.0, kappa=2.0)
START = dict(kd=0.5, ks=0.3, shininess=40.0, kappa=2.0)


def _scaled(values: dict, factor: float) -> dict:
    return {
        k: tuple(factor * x for x in v) if isinstance(v, tuple) else factor * v for k, v in values.items()
    }


CASES = (
    Case("reference", REFERENCE, START),
    Case("shininess-1000", {**REFERENCE, "shininess": 1500.0}, START),
    Case("kappa-50", {**REFERENCE, "kappa": 75.0}, START),
    Case("ks-zero", {**REFERENCE, "ks": 0.0}, START, expect_undetermined=("shininess",)),
    Case(
        "ks-zero-held",
        {**REFERENCE, "ks": 0.0},
        {**START, "ks": 0.0},
        expect_undetermined=("shininess",),
        fit=("kd", "shininess", "kappa"),
    ),
    Case("start-x100", REFERENCE, _scaled(REFERENCE, 100.0)),
    Case("start-x0.01", REFERENCE, _scaled(REFERENCE, 0.01)),
    Case(
        "combined",
        {**REFERENCE, "shininess": 1200.0, "kappa": 60.0},
        _scaled({**REFERENCE, "shininess": 1200.0, "kappa": 60.0}, 0.1),
    ),
)
QUICK_CASES = ("ks-zero-held", "start-x100")


def _params(values: dict, ambient: float):
    import hairjax as hj

    return hj.ShadingParams(**values, ambient=ambient)


def make_scene(strands: int, points: int, size: int, maps: int, resolution: int, seed: int):
    """A fur ball under the default scene's camera and light (hairjax/scenes/default.toml)."""
    import hairjax as hj

    return hj.Scene(
        hj.furball(strands, points, seed=seed),
        camera=hj.Camera(eye=(0.0, 0.3, 4.2), target=(0.0, -0.1, 0.0), fov=40.0, width=size, height=size),
        light=hj.Light(direction=(-0.6, -0.8, -0.5)),
        shadows=hj.Shadows("opacity-maps", maps, resolution),
        background=(0.02, 0.02, 0.03),
        name=f"furball-{strands}",
    )


def parameter_errors(fitted, truth) -> dict:
    """Per parameter, the worst over RGB of |fit − truth|/|truth|; the absolute error where
    the truth is 0 (Ks in `ks-zero`: a relative error is undefined there)."""
    out = {}
    for name in PARAMS:
        a = np.atleast_1d(np.asarray(getattr(fitted, name), float))
        b = np.atleast_1d(np.asarray(getattr(truth, name), float))
        err = np.where(b != 0, np.abs(a - b) / np.where(b != 0, np.abs(b), 1.0), np.abs(a))
        out[name] = float(np.max(err)) if np.all(np.isfinite(a)) else float("inf")
    return out


def _mean(p, name) -> float:
    return float(np.mean(np.asarray(getattr(p, name), float)))


def judge(termination: str, errors: dict, fitted, undetermined, expected, tol: float):
    """(status, failure, worst error over the determined fitted parameters)."""
    judged = [n for n in fitted if n not in undetermined and n not in expected]
    worst = max((errors[n] for n in judged), default=0.0)
    off = [n for n in judged if not errors[n] <= tol]
    # An undetermined parameter is wrong only off the truth: Ks in the softplus's flat tail
    # is undetermined, and right when the truth is 0.
    lost = [n for n in undetermined if n in fitted and n not in expected and not errors[n] <= tol]
    # An expected-undetermined parameter the fit did not flag is noted, not a failure.
    note = "".join(
        f" ({n} not reported undetermined)" for n in expected if n in fitted and n not in undetermined
    )
    if termination == "converged":
        if not off and not lost:
            return "converged" + note, False, worst
        what = [f"{n} off by {errors[n]:.2g}" for n in off] + [f"{n} undetermined" for n in lost]
        return "wrong: converged with " + ", ".join(what), True, worst
    if termination.startswith("stopped:"):
        return termination + note, False, worst
    # Fires only if hairjax.fit ever returns a termination string of another form.
    return f"wrong: unclear termination {termination!r}", True, worst


def run_fit(
    scene, target, case: Case, solver: str, max_steps: int, tol: float, ambient: float, separable: bool = True
):
    import hairjax as hj

    truth, start = _params(case.truth, ambient), _params(case.start, ambient)
    row = dict(
        case=case.name,
        solver=solver,
        fitted=" ".join(case.fit),
        expected_undetermined=" ".join(case.expect_undetermined),
        **{f"true_{n}": _mean(truth, n) for n in PARAMS},
        **{f"start_{n}": _mean(start, n) for n in PARAMS},
    )
    elapsed = []  # after each step; a first fit's first step includes compiling it
    t0 = time.perf_counter()
    try:
        r = hj.fit(
            scene,
            target,
            solver=hj.fit_solvers()[solver],
            init=start,
            variables=hj.FitVariables(case.fit, separable=separable),
            stop=hj.FitStop(max_steps=max_steps),
            progress=lambda step, loss, t: elapsed.append(t),
        )
    except Exception as err:  # noqa: BLE001 — a stiff case must never stop the sweep
        message = f"{type(err).__name__}: {err}".splitlines()[0][:200]
        row.update(
            steps=0,
            time_s=float("nan"),
            step_ms=float("nan"),
            wall_s=time.perf_counter() - t0,
            termination=f"error: {message}",
            status=f"error: {message}",
            failure=True,
            rmse=float("nan"),
            fit_rmse=float("nan"),
            worst_error=float("nan"),
            undetermined="",
            **{f"err_{n}": float("nan") for n in PARAMS},
            **{f"fit_{n}": float("nan") for n in PARAMS},
        )
        return row
    wall = time.perf_counter() - t0
    errors = parameter_errors(r.params, truth)
    # The RMSE of the parameters returned, rendered afresh (FitResult.rmse is that of the
    # last loss evaluated, which is NaN after a diverged step although the point is kept).
    try:
        image = np.asarray(hj.render(scene, r.params))[..., :3]
        rmse = float(np.sqrt(np.mean((image - target[..., :3]) ** 2)))
    except Exception:  # noqa: BLE001 — e.g. parameters a ShadingParams refuses
        rmse = float("nan")
    status, failure, worst = judge(
        r.termination, errors, case.fit, r.undetermined, case.expect_undetermined, tol
    )
    if not np.isfinite(rmse):  # fires if the returned parameters render non-finite pixels
        status, failure = f"wrong: non-finite image ({status})", True
    elif not np.isfinite(r.rmse):
        status += " (FitResult.rmse is NaN)"
    per_step = np.diff(elapsed)
    step_ms = float(1e3 * np.median(per_step)) if per_step.size else float("nan")
    row.update(
        steps=r.steps,
        time_s=r.time_s,
        step_ms=step_ms,
        wall_s=wall,
        termination=r.termination,
        status=status,
        failure=failure,
        rmse=rmse,
        fit_rmse=r.rmse,
        worst_error=worst,
        undetermined=" ".join(r.undetermined),
        **{f"err_{n}": errors[n] for n in PARAMS},
        **{f"fit_{n}": _mean(r.params, n) for n in PARAMS},
    )
    return row


def _short_status(status: str) -> str:
    for long, short in (
        ("stopped: reached max_steps = ", "max_steps "),
        (
            "stopped: diverged (the loss became non-finite); kept the last finite point",
            "stopped: non-finite loss",
        ),
    ):
        status = status.replace(long, short)
    return status


def _cell(row) -> str:
    worst = row["worst_error"]
    worst_text = "–" if not np.isfinite(worst) else f"{worst:.1e}"
    time_text = "–" if not np.isfinite(row["time_s"]) else f"{row['time_s']:.1f} s"
    return f"{row['steps']} / {time_text} / {worst_text} / {_short_status(row['status'])}"


def table(rows, cases, solvers, header: str) -> str:
    lines = [
        header,
        "",
        "| case | " + " | ".join(SHORT.get(s, s) for s in solvers) + " |",
        "|---" * (len(solvers) + 1) + "|",
    ]
    for case in cases:
        cells = []
        for s in solvers:
            sel = [r for r in rows if r["case"] == case and r["solver"] == s]
            cells.append(_cell(sel[0]) if sel else "")
        lines.append(f"| {case} | " + " | ".join(cells) + " |")
    summary = []
    for s in solvers:
        sel = [r for r in rows if r["solver"] == s]
        times = [r["time_s"] for r in sel if np.isfinite(r["time_s"])]
        median = statistics.median(times) if times else float("nan")
        per_step = [r["step_ms"] for r in sel if np.isfinite(r["step_ms"])]
        step_text = f", {statistics.median(per_step):.0f} ms per step" if per_step else ""
        summary.append(
            f"{SHORT.get(s, s)}: {sum(r['failure'] for r in sel)} failure(s) of "
            f"{len(sel)}, median time {median:.1f} s{step_text}"
        )
    lines += [
        "",
        "Cells: steps / time (`FitResult.time_s`: after the geometry stage; the first "
        "fit of a solver and set of fitted names includes compiling its step, later ones "
        "reuse it) / worst relative error over the determined fitted parameters / "
        "status. A failure is a reported convergence off the truth (`wrong`) or an "
        "exception (`error`); a stop with a stated reason is not one.",
        "",
        "Per solver: " + "; ".join(summary) + " (median of the steps after the first).",
    ]
    return "\n".join(lines) + "\n"


def _parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument(
        "--cases", default=",".join(c.name for c in CASES), help="comma-separated case names (default: all)"
    )
    p.add_argument("--solvers", default=",".join(SOLVERS))
    p.add_argument("--strands", type=int, default=2000)
    p.add_argument("--points", type=int, default=16)
    p.add_argument("--size", type=int, default=128, help="image SIZE × SIZE (default 128)")
    p.add_argument("--maps", type=int, default=32, help="opacity maps (default 32)")
    p.add_argument("--resolution", type=int, default=128, help="opacity-map size (default 128)")
    p.add_argument("--seed", type=int, default=1)
    p.add_argument("--max-steps", type=int, default=200)
    p.add_argument("--tol", type=float, default=1e-2, help="relative error bound (default 1e-2)")
    p.add_argument("--x64", action="store_true", help="fit in float64 (default: float32)")
    p.add_argument(
        "--no-separable",
        dest="separable",
        action="store_false",
        help="let the solver search Kd and Ks too (hj.FitVariables(separable=False)) instead of "
        "solving for them at every step (the default)",
    )
    p.add_argument("--out", type=Path, default=Path("out/stiff_fits"))
    p.add_argument(
        "--quick",
        action="store_true",
        help=f"300 strands at 32², cases {', '.join(QUICK_CASES)}, LM only, ≤ 20 steps",
    )
    return p


def main(argv=None) -> int:
    args = _parser().parse_args(argv)
    import jax

    if args.x64:
        jax.config.update("jax_enable_x64", True)
    import hairjax as hj

    if args.quick:
        args.strands, args.points, args.size, args.maps, args.resolution = 300, 8, 32, 8, 32
        args.cases, args.solvers = ",".join(QUICK_CASES), "levenberg-marquardt"
        args.max_steps = min(args.max_steps, 20)
    by_name = {c.name: c for c in CASES}
    unknown = [c for c in args.cases.split(",") if c not in by_name]
    if unknown:
        raise SystemExit(f"unknown case(s) {', '.join(unknown)}; choose from {', '.join(by_name)}")
    cases = [by_name[c] for c in args.cases.split(",")]
    solvers = args.solvers.split(",")

    scene = make_scene(args.strands, args.points, args.size, args.maps, args.resolution, args.seed)
    ambient = 0.05
    dtype = str(jax.numpy.result_type(float))
    header = (
        f"Stiff fits: fur ball of {args.strands} strands × {args.points} points at "
        f"{args.size}², {args.maps} opacity maps of {args.resolution}², {dtype}, "
        f"max_steps {args.max_steps}, bound {args.tol:g}, "
        + (
            "Kd and Ks solved for at every step (separable, the default)"
            if args.separable
            else "all four parameters searched by the solver (separable=False)"
        )
    )
    print(header, flush=True)
    rows = []
    started = time.perf_counter()
    for case in cases:
        target = np.asarray(hj.render(scene, _params(case.truth, ambient)))
        for solver in solvers:
            row = run_fit(scene, target, case, solver, args.max_steps, args.tol, ambient, args.separable)
            row["dtype"] = dtype
            rows.append(row)
            print(
                f"  {case.name:<15} {solver:<20} {row['steps']:4d} steps {row['wall_s']:6.1f} s  "
                f"rmse {row['rmse']:.2e}  worst {row['worst_error']:.2e}  {row['status']}"
                + (f"  [undetermined: {row['undetermined']}]" if row["undetermined"] else ""),
                flush=True,
            )

    text = table(rows, [c.name for c in cases], solvers, header)
    csv_path, md_path = args.out / "stiff_fits.csv", args.out / "stiff_fits.md"
    from hairjax.experimental import write_csv, write_text

    write_csv(csv_path, CSV_COLUMNS, rows, float_format=".6g")
    write_text(md_path, text)
    print()
    print(text)
    print(f"wrote {csv_path}\nwrote {md_path}\ntotal {time.perf_counter() - started:.1f} s")
    return 0


if __name__ == "__main__":
    sys.exit(main())
