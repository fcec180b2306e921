"""Bad input: one test per case, each with ``match=`` on the message."""

from __future__ import annotations

import numpy as np
import pytest

from setobs import Box, ConstrainedZonotope, DimensionError, SetobsError
from setobs.exceptions import ArgumentError, InvalidValueError
from setobs.geometry import reduce_order

nan, inf = np.nan, np.inf
G2 = np.eye(2)


@pytest.mark.parametrize(
    ("kwargs", "error", "match"),
    [
        ({"G": np.ones((3, 2)), "c": [0, 0]}, DimensionError, r"G must have 2 rows, got 3"),
        ({"G": np.ones((2, 2, 2)), "c": [0, 0]}, DimensionError, r"G must be a 2-D matrix"),
        ({"G": G2, "c": [[0, 1], [1, 0]]},
         DimensionError, r"c must be a vector, got an array of shape \(2, 2\)"),
        ({"G": G2, "c": [0, 0], "A": np.ones((1, 3)), "b": [1]},
         DimensionError, r"A must have 2 columns, got 3"),
        ({"G": G2, "c": [0, 0], "A": np.ones((2, 2)), "b": [1]},
         DimensionError, r"b must have one entry per row of A \(2\), got 1"),
        ({"G": G2, "c": [0, 0], "A": np.ones((1, 2))},
         ArgumentError, r"A and b must be given together"),
        ({"G": G2, "c": [0, 0], "b": [1.0]}, ArgumentError, r"A and b must be given together"),
        ({"G": [[1, nan], [0, 1]], "c": [0, 0]},
         InvalidValueError, r"G contains NaN \(first at index \(0, 1\)\)"),
        ({"G": [[1, inf], [0, 1]], "c": [0, 0]},
         InvalidValueError, r"G contains inf .* must be finite"),
        ({"G": G2, "c": [0, nan]}, InvalidValueError, r"c contains NaN"),
        ({"G": G2, "c": [inf, 0]}, InvalidValueError, r"c contains inf"),
        ({"G": G2, "c": [0, 0], "A": [[nan, 1]], "b": [1]}, InvalidValueError, r"A contains NaN"),
        ({"G": G2, "c": [0, 0], "A": [[inf, 1]], "b": [1]}, InvalidValueError, r"A contains inf"),
        ({"G": G2, "c": [0, 0], "A": [[1, 1]], "b": [nan]}, InvalidValueError, r"b contains NaN"),
        ({"G": G2, "c": [0, 0], "A": [[1, 1]], "b": [inf]}, InvalidValueError, r"b contains inf"),
        ({"G": G2, "c": [0, 0], "h": [1, -0.5]},
         InvalidValueError, r"h must be nonnegative \(h\[1\] = -0.5\)"),
        ({"G": G2, "c": [0, 0], "h": [1, nan]}, InvalidValueError, r"h contains NaN"),
        ({"G": G2, "c": [0, 0], "h": [1, 1, 1]}, DimensionError, r"h must have length 2, got 3"),
        ({"G": G2, "c": ["a", "b"]}, ArgumentError, r"c must be a real numeric vector"),
    ],
)
def test_constructor_rejects(kwargs, error, match):
    with pytest.raises(error, match=match):
        ConstrainedZonotope(**kwargs)


def test_errors_are_value_errors_and_setobs_errors():
    with pytest.raises(ValueError, match="G must have"):
        ConstrainedZonotope(np.ones((3, 2)), [0, 0])
    assert issubclass(DimensionError, SetobsError)


@pytest.fixture
def Z():
    return ConstrainedZonotope([[1.0, 0.0, 1.0], [0.0, 1.0, 1.0]], [0.0, 0.0],
                               A=[[1.0, 1.0, 1.0]], b=[1.0])


def test_contains_wrong_length(Z):
    with pytest.raises(DimensionError, match=r"x must have length 2, got 3"):
        Z.contains([0.0, 0.0, 0.0])


def test_support_wrong_length(Z):
    with pytest.raises(DimensionError, match=r"direction must have length 2, got 1"):
        Z.support([1.0])


def test_support_nan_direction(Z):
    with pytest.raises(InvalidValueError, match=r"direction contains NaN"):
        Z.support([1.0, nan])


def test_linear_map_wrong_columns(Z):
    with pytest.raises(DimensionError, match=r"M \(linear map\) must have 2 columns, got 3"):
        np.ones((2, 3)) @ Z


def test_minkowski_dimension_mismatch(Z):
    with pytest.raises(DimensionError, match=r"Minkowski sum: dimensions differ \(2 vs 3\)"):
        Z + ConstrainedZonotope.point([0.0, 0.0, 0.0])


def test_minkowski_vector_wrong_length(Z):
    with pytest.raises(DimensionError, match=r"vector must have length 2, got 3"):
        Z + np.zeros(3)


def test_intersect_affine_wrong_y(Z):
    with pytest.raises(DimensionError, match=r"y must have length 1, got 2"):
        Z.intersect_affine([[1.0, 0.0]], [1.0, 2.0])


def test_intersect_affine_wrong_C(Z):
    with pytest.raises(DimensionError, match=r"C must have 2 columns, got 3"):
        Z.intersect_affine([[1.0, 0.0, 0.0]], [1.0])


def test_generalized_intersection_wrong_R(Z):
    with pytest.raises(DimensionError,
                       match=r"R \(generalised intersection\) must have 3 rows, got 2"):
        Z.intersect(ConstrainedZonotope.full_space(3), np.eye(2))


def test_intersection_dimension_mismatch(Z):
    with pytest.raises(DimensionError, match=r"intersection: dimensions differ"):
        Z.intersect(ConstrainedZonotope.full_space(3))


def test_project_bad_index(Z):
    with pytest.raises(DimensionError, match=r"dims must be indices in \[0, 1\]"):
        Z.project([0, 2])


def test_one_sided_box_is_not_representable():
    with pytest.raises(InvalidValueError, match=r"coordinate 1 has a one-sided infinite bound"):
        ConstrainedZonotope.from_box([0.0, 0.0], [1.0, inf])


def test_box_lo_above_hi():
    with pytest.raises(InvalidValueError, match=r"lo must not exceed hi \(index 0"):
        Box([2.0], [1.0])


def test_full_space_bad_n():
    with pytest.raises(InvalidValueError, match=r"n must be a positive integer"):
        ConstrainedZonotope.full_space(0)


def test_reduce_order_too_few(Z):
    with pytest.raises(InvalidValueError,
                       match=r"max_generators must be at least n \+ n_unbounded"):
        reduce_order(Z, Z.dim - 1)


def test_cartesian_type_error(Z):
    with pytest.raises(TypeError, match="cartesian expects a ConstrainedZonotope"):
        Z.cartesian(np.eye(2))


def test_immutable(Z):
    with pytest.raises(AttributeError, match="immutable"):
        Z.G = np.eye(2)
    with pytest.raises(ValueError, match="read-only"):
        Z.G[0, 0] = 5.0
    G = np.eye(2)
    W = ConstrainedZonotope(G, [0.0, 0.0])
    G[0, 0] = 7.0  # the set keeps its own copy
    assert W.G[0, 0] == 1.0


def test_properties(Z):
    assert (Z.dim, Z.n_gen, Z.n_con) == (2, 3, 1)
    assert Z.is_bounded and not Z.has_unbounded_factors
    assert "n_gen=3" in repr(Z)
