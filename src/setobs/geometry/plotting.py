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


def polygon_2d(Z: ConstrainedZonotope, max_iter: int = 10_000) -> NDArray[np.float64]:
    """Vertices (counter-clockwise) of a bounded 2-D constrained zonotope.

    Exact up to LP accuracy, without vertex enumeration of the factor polytope:
    starting from the support points in the four axis directions, each edge
    between consecutive known vertices is tested by an LP in its outward
    normal; a support point beyond the edge is a new vertex, otherwise the edge
    is a facet. One LP per vertex and facet.

    Raises
    ------
    DimensionError
        If ``Z`` is not 2-D.
    UnboundedSetError
        If ``Z`` is unbounded.
    """
    if Z.dim != 2:
        raise DimensionError(f"polygon_2d needs a 2-D set, got dimension {Z.dim}")
    box = Z.interval_hull()
    if not box.is_bounded:
        raise UnboundedSetError("cannot draw an unbounded set; intersect it with a box first")
    scale = max(float(np.abs(np.concatenate([box.lo, box.hi])).max()), 1e-300)
    tol = 1e-9 * scale
    dirs = [np.array(d, dtype=float) for d in ((1, 0), (0, 1), (-1, 0), (0, -1))]
    pts: list[NDArray[np.float64]] = []
    for d in dirs:
        p = Z.support_point(d)
        if not pts or np.linalg.norm(p - pts[-1]) > tol:
            pts.append(p)
    if len(pts) > 1 and np.linalg.norm(pts[0] - pts[-1]) <= tol:
        pts.pop()
    if len(pts) <= 1:
        return np.array(pts)
    done = [False] * len(pts)
    i = 0
    for _ in range(max_iter):
        if all(done):
            break
        if done[i]:
            i = (i + 1) % len(pts)
            continue
        a, b = pts[i], pts[(i + 1) % len(pts)]
        e = b - a
        nrm = np.array([e[1], -e[0]])  # outward normal of a CCW polygon
        nrm /= np.linalg.norm(nrm)
        p = Z.support_point(nrm)
        if nrm @ p > nrm @ a + tol:
            pts.insert(i + 1, p)
            done.insert(i + 1, False)
        else:
            done[i] = True
            i = (i + 1) % len(pts)
    # Degenerate LPs may return points inside an edge: drop collinear points.
    P = np.array(pts)
    while len(P) > 2:
        prev, nxt = np.roll(P, 1, axis=0), np.roll(P, -1, axis=0)
        u, v = P - prev, nxt - P
        cross = np.abs(u[:, 0] * v[:, 1] - u[:, 1] * v[:, 0])
        flat = cross <= tol * (np.linalg.norm(u, axis=1) + np.linalg.norm(v, axis=1))
        if not flat.any():
            break
        P = np.delete(P, int(np.argmax(flat)), axis=0)
    return P


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
