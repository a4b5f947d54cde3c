"""Figures; matplotlib is imported only inside this package.

Every figure is a ``matplotlib.figure.Figure`` made by :func:`subplots`: no pyplot and no
backend switch, so the package works headless and inside notebooks alike (a notebook's
inline backend is left alone).
"""


def subplots(nrows: int = 1, ncols: int = 1, figsize=(8, 6), dpi: int = 90, **kw):
    """``(figure, axes)`` like ``pyplot.subplots``, without pyplot."""
    from matplotlib.figure import Figure

    fig = Figure(figsize=figsize, dpi=dpi)
    return fig, fig.subplots(nrows, ncols, **kw)
