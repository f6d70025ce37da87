"""`hairjax` entry point: parse, run one subcommand, turn every failure into one line.

Exit codes (README.md): 0 done, 2 bad input (an unreadable or invalid scene, hair file,
image or option, an output that cannot be written), 3 a fit that stopped without
converging, 1 an unexpected error (rerun with --debug for the traceback), 130 interrupted.
"""

from __future__ import annotations

import importlib
import os
import sys
import warnings
from pathlib import Path

from ._parser import build_parser

__all__ = ["main", "EXIT_BAD_INPUT", "EXIT_NOT_CONVERGED", "EXIT_UNEXPECTED"]

EXIT_UNEXPECTED = 1
EXIT_BAD_INPUT = 2
EXIT_NOT_CONVERGED = 3
EXIT_INTERRUPTED = 130

_JAX_COMMANDS = ("render", "animate", "bench", "compare", "fit", "sweep")


def _enable_compilation_cache() -> None:
    """Keep compiled XLA kernels on disk, so a second `hairjax` run skips compilation.

    The folder is $HAIRJAX_CACHE_DIR, else ~/.cache/hairjax/xla; set the variable to an
    empty string to turn the cache off.
    """
    import jax

    folder = os.environ.get("HAIRJAX_CACHE_DIR", str(Path.home() / ".cache" / "hairjax" / "xla"))
    if not folder or jax.config.jax_compilation_cache_dir:  # type: ignore[attr-defined]  # options are set at run time
        return  # off, or the user configured a cache already
    jax.config.update("jax_compilation_cache_dir", folder)
    jax.config.update("jax_persistent_cache_min_compile_time_secs", 0.2)


def _is_bad_input(err: BaseException) -> bool:
    """Errors about the user's input, as opposed to a bug: the package's input errors are
    ValueErrors (SceneError, HairFormatError, FitError, …) or OSErrors (ImageError, a
    missing or unreadable file); the GL renderer's are GLUnavailable and GLError; an optional
    extra that is not installed is MissingDependency (its message names the pip line)."""
    from .._errors import MissingDependency

    if isinstance(err, (ValueError, OSError, MissingDependency)):
        return True
    return type(err).__module__.startswith("hairjax.gl") and isinstance(err, RuntimeError)


def _one_line(err: BaseException) -> str:
    if isinstance(err, OSError) and err.filename is not None and err.strerror:
        return f"{err.filename}: {err.strerror}"  # not "[Errno 2] No such file …: 'x'"
    text = str(err).strip() or type(err).__name__
    return " ".join(text.split("\n")[0].split()) if "\n" in text else text


def _show_warning(message, category, filename, lineno, file=None, line=None):
    """Warnings as one line, without the source line Python shows by default."""
    print(f"hairjax: warning: {message}", file=sys.stderr if file is None else file)


def main(argv: list[str] | None = None) -> int:
    args = build_parser().parse_args(argv)
    module = importlib.import_module(f"{__package__}._{args.command}")
    with warnings.catch_warnings():  # restores the filters and showwarning afterwards
        warnings.simplefilter("default")  # each warning once per place, as one line
        warnings.showwarning = _show_warning
        return _run(module, args)


def _run(module, args) -> int:
    try:
        if args.command in _JAX_COMMANDS:
            _enable_compilation_cache()
        return module.run(args)
    except KeyboardInterrupt:
        print("hairjax: interrupted", file=sys.stderr)
        return EXIT_INTERRUPTED
    except Exception as err:
        if args.debug:
            raise
        if _is_bad_input(err):
            print(f"hairjax: error: {_one_line(err)}", file=sys.stderr)
            return EXIT_BAD_INPUT
        print(
            f"hairjax: unexpected error: {type(err).__name__}: {_one_line(err)} "
            "(rerun with --debug for the traceback)",
            file=sys.stderr,
        )
        return EXIT_UNEXPECTED
