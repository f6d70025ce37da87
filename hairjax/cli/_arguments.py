"""The command line's argument types: what argparse turns a word into, or refuses with
one line (`argparse.ArgumentTypeError`). Standard library only, as `_parser`."""

from __future__ import annotations

import argparse

__all__ = [
    "positive_int",
    "non_negative_float",
    "positive_float",
    "parse_size",
    "parse_assignment",
    "parse_key",
]


def positive_int(text: str) -> int:
    """argparse type: an integer ≥ 1."""
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a positive integer, got {text!r}") from None
    if value < 1:
        raise argparse.ArgumentTypeError(f"expected a positive integer, got {text!r}")
    return value


def non_negative_float(text: str) -> float:
    """argparse type: a finite number ≥ 0."""
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a number ≥ 0, got {text!r}") from None
    if not 0 <= value < float("inf"):
        raise argparse.ArgumentTypeError(f"expected a number ≥ 0, got {text!r}")
    return value


def positive_float(text: str) -> float:
    """argparse type: a finite number > 0."""
    value = non_negative_float(text)
    if value == 0:
        raise argparse.ArgumentTypeError(f"expected a number > 0, got {text!r}")
    return value


def parse_size(text: str) -> tuple[int, int | None]:
    """argparse type for --size: `W` (height follows the scene's aspect) or `WxH`."""
    width, sep, height = text.lower().partition("x")
    try:
        w = positive_int(width)
        h = positive_int(height) if sep else None
    except argparse.ArgumentTypeError:
        raise argparse.ArgumentTypeError(f"expected W or WxH in pixels, each ≥ 1, got {text!r}") from None
    return w, h


def parse_assignment(text: str) -> tuple[str, str]:
    """argparse type for --set: `table.key=value` (the value is read as TOML later)."""
    key, sep, value = text.partition("=")
    if not sep or not key.strip() or not value.strip():
        raise argparse.ArgumentTypeError(f"expected table.key=value, got {text!r}")
    return key.strip(), value.strip()


def parse_key(text: str) -> str:
    """argparse type for --unset: `table.key` (or a top-level key such as `name`)."""
    key = text.strip()
    if not key or "=" in key or any(not part for part in key.split(".")):
        raise argparse.ArgumentTypeError(f"expected table.key, got {text!r}")
    return key
