"""2-D plotting of constrained zonotopes (matplotlib is imported lazily)."""

from __future__ import annotations

from collections.abc import Sequence
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import NDArray

from ..exceptions import DimensionError, UnboundedSetError
from .zonotope import ConstrainedZonotope

if TYPE_CHECKING:  # pragma: no cover
    from matplotlib.axes import Axes
    from matplotlib.patches import Patch

__all__ = ["plot_cz", "polygon_2d"]


def polygon_2d(Z: ConstrainedZonotope) -> NDArray[np.float64]:
    """Vertices (counter-clockwise) of a bounded 2-D constrained zonotope.

    The verified vertices of :func:`setobs.geometry.polytope.vertices` (support
    LPs, every edge confirmed by a certified support value), in angular order.

    Raises
    ------
    DimensionError
        If ``Z`` is not 2-D.
    UnboundedSetError
        If ``Z`` is unbounded.
    """
    from .polytope import vertices

    if Z.dim != 2:
        raise DimensionError(f"polygon_2d needs a 2-D set, got dimension {Z.dim}")
    try:
        P = vertices(Z)
    except UnboundedSetError:
        raise UnboundedSetError("cannot draw an unbounded set; intersect it with a box "
                                "first") from None
    if len(P) <= 2:
        return P
    ctr = P.mean(axis=0)
    return P[np.argsort(np.arctan2(P[:, 1] - ctr[1], P[:, 0] - ctr[0]))]


def plot_cz(
    Z: ConstrainedZonotope,
    ax: Axes | None = None,
    dims: Sequence[int] = (0, 1),
    **kwargs: Any,
) -> Patch:
    """Draw the projection of ``Z`` onto ``dims`` as a filled polygon.

    Parameters
    ----------
    Z : ConstrainedZonotope
    ax : matplotlib Axes, optional
        Axes to draw on (default: the current axes).
    dims : pair of int
        Coordinates to project on.
    **kwargs
        Passed to :class:`matplotlib.patches.Polygon` (e.g. ``facecolor``,
        ``alpha``, ``label``).

    Returns
    -------
    matplotlib.patches.Polygon
        The artist added to ``ax``.
    """
    import matplotlib.pyplot as plt
    from matplotlib.patches import Polygon

    if len(dims) != 2:
        raise DimensionError(f"dims must name two coordinates, got {list(dims)}")
    P = polygon_2d(Z.project(dims))
    if ax is None:
        ax = plt.gca()
    kwargs.setdefault("alpha", 0.4)
    kwargs.setdefault("edgecolor", "k")
    patch = Polygon(P, closed=True, **kwargs)
    ax.add_patch(patch)
    ax.update_datalim(P)
    ax.autoscale_view()
    return patch
