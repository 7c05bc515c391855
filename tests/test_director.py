"""XS and XSL combinations (sections 4.3, 4.5)."""
from __future__ import annotations

import numpy as np
import pytest
from support.cli_wording import refused_in_flags

from xsl_render.core.errors import InputError
from xsl_render.core.maps.director import combine, to_unit_range, xs_map, xsl_map

rng = np.random.default_rng(7)
X = rng.uniform(0, 1, (9, 16)).astype(np.float32)
S = rng.uniform(0, 1, (9, 16)).astype(np.float32)
L = rng.uniform(0, 1, (9, 16)).astype(np.float32)


def test_paper_defaults_are_the_mean():
    np.testing.assert_allclose(xs_map(X, S), 0.5 * X + 0.5 * S, rtol=1e-6)


def test_xsl_degenerates_to_its_inputs_bit_for_bit():
    xs = xs_map(X, S)
    assert np.array_equal(xsl_map(xs, L, 1.0, 0.0, "add"), xs)
    assert np.array_equal(xsl_map(xs, L, 0.0, 1.0, "add"), L)
    assert np.array_equal(xs_map(X, S, 1.0, 0.0, "multiply"), X)


@pytest.mark.parametrize("op", ["add", "multiply"])
@pytest.mark.parametrize("weights", [(0.5, 0.5), (1.0, 1.0), (0.2, 3.0)])
def test_results_stay_in_unit_range(op, weights):
    out = combine(X * 7, S, *weights, op)
    assert out.dtype == np.float32 and out.min() >= 0 and out.max() <= 1


def test_multiply_is_saliency_modulated_by_extinction():
    np.testing.assert_allclose(xs_map(X, S, 1.0, 1.0, "multiply"), X * S, rtol=1e-6)


@pytest.mark.parametrize("weights", [(0.5, 0.5), (0.8, 0.2), (1.0, 1.0)])
def test_no_saliency_is_the_floor_of_the_add_operator(weights):
    # bench/bench_bounds.py rests on this: with "add", XS is never below the XS of S = 0, so
    # the samples the map asks for with S = 0 bound the speedup any saliency map can give.
    none = xs_map(X, np.zeros_like(S), *weights)
    for saliency in (S, S * 0.01, np.ones_like(S)):
        assert (xs_map(X, saliency, *weights) >= none).all()
        assert (xsl_map(xs_map(X, saliency, *weights), L) >= xsl_map(none, L)).all()
    # and the floor is the weighted X itself: thin fog alone keeps the map high
    np.testing.assert_allclose(none, X * weights[0] / max(1.0, sum(weights)), rtol=1e-6)


def test_maps_already_in_unit_range_are_not_stretched():
    thin_fog = np.full((4, 4), 0.8, np.float32)
    assert np.array_equal(to_unit_range(thin_fog), thin_fog)


@pytest.mark.parametrize("w_a, w_b, op, message", [
    (-0.1, 0.5, "add", "--wx"), (0.5, float("nan"), "add", "--ws"),
    (0.5, 0.5, "max", "--xs-op"), (0.0, 0.0, "add", "both be 0")])
def test_bad_weights_and_operators_name_the_option(w_a, w_b, op, message):
    with refused_in_flags(message):
        xs_map(X, S, w_a, w_b, op)


def test_nan_input_is_refused():
    bad = X.copy()
    bad[0, 0] = np.nan
    with pytest.raises(ValueError):
        xs_map(bad, S)
