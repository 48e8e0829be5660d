"""How the study's figures are made: each is a :class:`matplotlib.figure.Figure` built
directly, not through pyplot (no global figure registry, no backend switch for the caller,
headless machines work). Each ``plot_*`` function saves the figure that a
``_figure_*`` twin returns, so tests can inspect legends and labels without reading
pixels."""
from __future__ import annotations


def new_figure(**kwargs):
    """A Matplotlib :class:`~matplotlib.figure.Figure` (``kwargs`` as its constructor's)."""
    from matplotlib.figure import Figure
    return Figure(**kwargs)
