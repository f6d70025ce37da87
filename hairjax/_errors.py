"""Errors raised for bad input: one class per kind of input, each naming what is wrong."""

from __future__ import annotations


class HairFormatError(ValueError):
    """A hair file (``.hair``, ``.tfx``, ``.ply``) is malformed; the message names the file."""

    def __init__(self, path, problem: str):
        self.path = str(path)
        self.problem = problem
        super().__init__(f"{self.path}: {problem}")


class SceneError(ValueError):
    """A scene (TOML file or Python values) is invalid; the message names the key."""


class SceneTooLarge(SceneError, MemoryError):
    """A render would need more memory than the machine has available; raised before the
    render allocates it, and the message names the fragment count and the bytes. A
    `MemoryError` too, and a `SceneError`: the scene asks for more than this machine has."""


class MeshFormatError(ValueError):
    """A mesh file (``.obj``) is malformed; the message names the file and the line."""

    def __init__(self, path, line: int | None, problem: str):
        self.path = str(path)
        self.line = line
        self.problem = problem
        where = self.path if line is None else f"{self.path}:{line}"
        super().__init__(f"{where}: {problem}")


class EmptyViewWarning(UserWarning):
    """A render's hair covers no pixel of the image (the camera misses it); the message
    gives the hair's bounding box and the camera, and how to frame the hair."""


class MissingDependency(ImportError):
    """An optional extra that a feature needs is not installed; the message says which
    feature, and the `pip install` line that adds it."""
