"""`_member` (hairjax/_disagreement/_camera.py), end_band's membership test: the same
answer as `np.isin` on int64 keys, repeated, unsorted, past either end, and for an
empty set."""

from __future__ import annotations

import numpy as np
import pytest

from hairjax._disagreement._camera import _member


@pytest.mark.parametrize("sizes", [(1000, 700), (50, 0), (0, 20), (1, 1)])
def test_member_is_isin(sizes):
    rng = np.random.default_rng(sum(sizes))
    a = rng.integers(-5, 2000, sizes[0]).astype(np.int64)
    b = rng.integers(0, 1900, sizes[1]).astype(np.int64)
    np.testing.assert_array_equal(_member(a, b), np.isin(a, b))
