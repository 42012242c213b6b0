"""Sequential niche technique: niche radius and the derating function."""

import numpy as np
import pytest

from framework.optimizers.niching import derating, niche_radius


def test_niche_radius_of_the_source():
    assert niche_radius(6, 4) == pytest.approx(0.97, abs=0.005)


def test_derating_raises_objective_only_inside_niche():
    s = np.zeros(2)
    X = np.array([[0.0, 0.0], [0.5, 0.0], [1.0, 0.0], [2.0, 0.0]])
    G = derating(X, [s], r=1.0, m=0.1)
    np.testing.assert_allclose(G, [0.1, np.sqrt(0.1), 1.0, 1.0])
    raw = np.full(4, 0.01)
    derated = (1 + raw) / G - 1
    assert np.all(derated[:2] > raw[:2]) and np.allclose(derated[2:], raw[2:])
