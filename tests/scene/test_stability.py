"""Numerical stability of the scene's own arrays (the shared part and the other
stages: tests/stability_helpers.py): the guards in hairjax/_scene.

| guard (file: function)                          | test_guard_… (or test_… in full)            |
|-------------------------------------------------|---------------------------------------------|
| _values/_strands: tangents/unit_rows, zero diff. | zero_tangent_of_repeated_points             |
| _scene/_procedural: _unit_vectors, _grow        | fur_sources                                 |
| _scene/_procedural: scalp clip(1 − y², 0)       | unreachable: |y| ≤ 1 gives fl(y²) ≤ 1       |
"""

from __future__ import annotations

import numpy as np

import hairjax as hj

# --- the guards ----------------------------------------------------------------------------
# One test per guard (the table in the module docstring): inputs that make it fire, and the
# guarded result checked against the model's value.


def test_guard_zero_tangent_of_repeated_points():
    """_values/_strands.tangents/unit_rows: a zero central difference (repeated points, one-point
    strands) gives the zero tangent, exactly; other tangents are unit vectors."""
    from hairjax._values._strands import tangents

    hair = hj.Strands.from_list(
        [
            [[0, 0, 0], [0, 0, 0], [1, 0, 0]],  # one-sided p1 − p0 = 0
            [[2, 2, 2]],  # one point
            [[0, 1, 0], [0, 1, 0], [0, 1, 0]],  # all equal
            [[0, 0, 0], [1, 2, 2], [0, 0, 0]],
        ]
    )  # p2 − p0 = 0 (middle)
    t = tangents(hair.points, hair.offsets)
    zero = [0, 3, 4, 5, 6, 8]
    np.testing.assert_array_equal(t[zero], 0.0)
    np.testing.assert_allclose(np.linalg.norm(np.delete(t, zero, axis=0), axis=1), 1.0, rtol=1e-15)


def test_guard_fur_sources():
    """_scene/_procedural: a normal draw of exactly 0 (a stub generator) gives the direction +y;
    a step where gravity + inertia cancel the direction keeps the direction."""
    from hairjax._scene._procedural import _grow, _unit_vectors

    class Zeros:
        def normal(self, size):
            return np.zeros(size)

    np.testing.assert_array_equal(_unit_vectors(Zeros(), 2), [[0.0, 1.0, 0.0]] * 2)
    out = _grow(
        np.zeros((1, 3)), np.array([[0.0, 1.0, 0.0]]), np.array([0.5]), 3, (0.0, -1.0, 0.0), (0.0, 0.0, 0.0)
    )
    np.testing.assert_array_equal(out[0], [[0.0, 0.0, 0.0], [0.0, 0.5, 0.0], [0.0, 1.0, 0.0]])
