"""`hairjax info`: what a hair file holds (format, strands, points, bounding box, …)."""

from __future__ import annotations

import argparse

__all__ = ["run"]


def run(args: argparse.Namespace) -> int:
    from .._io import format_info, hair_info, load_hair

    strands = load_hair(args.file)
    print(format_info(args.file, hair_info(strands)))
    return 0
