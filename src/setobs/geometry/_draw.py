"""2-D drawing of constrained zonotopes, public as :func:`setobs.plotting.plot_set`.

matplotlib is imported lazily.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import TYPE_CHECKING, Any

from ..exceptions import DimensionError
from .polytope import polygon_2d
from .zonotope import ConstrainedZonotope

if TYPE_CHECKING:  # pragma: no cover
    from matplotlib.axes import Axes
    from matplotlib.patches import Patch

__all__ = ["plot_set"]


def plot_set(
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
