"""PNG plots (matplotlib, Agg backend): one curve per k, axes labelled with units."""
from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import List, Optional, Sequence, Tuple

import numpy as np


def pyplot():
    """matplotlib's pyplot on the Agg backend, imported when a figure is drawn (loading a
    scenario, or running one without figures, does not need it)."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    return plt


@dataclass
class Curve:
    """A line; ``style`` a matplotlib format (``-``, ``o-``); ``lower``/``upper``: an envelope
    shaded in the line's colour (e.g. the range of each cycle around its mean)."""

    x: Sequence[float]
    y: Sequence[float]
    label: str
    style: str = "-"
    lower: Optional[Sequence[float]] = None
    upper: Optional[Sequence[float]] = None


#: line styles cycled after the ten colours: every curve of a panel looks different (40 curves)
LINE_STYLES = ("-", "--", ":", "-.")


@dataclass(frozen=True)
class Span:
    """A stretch of the x axis to shade and name, e.g. a test zone of the track: from ``start`` to
    ``end``, ``label`` written at its top; ``shade`` False: only its boundaries are drawn."""

    start: float
    end: float
    label: str
    shade: bool = True


@dataclass
class Panel:
    """One axes: curves, labels (with units), optional horizontal reference lines and stretches of
    the x axis (:class:`Span`: the track's zones along a position axis)."""

    curves: List[Curve]
    xlabel: str
    ylabel: str
    title: str = ""
    logx: bool = False
    logy: bool = False
    hlines: List[Tuple[float, str]] = field(default_factory=list)
    spans: List[Span] = field(default_factory=list)


@dataclass
class Figure:
    """A figure to draw: ``name`` (the PNG's file name), its panels, a title and the number of
    panel columns."""

    name: str
    panels: List[Panel]
    title: Optional[str] = None
    ncols: int = 1

    def save(self, folder: Path) -> Path:
        return save_panels(Path(folder) / self.name, self.panels, self.title, ncols=self.ncols)


def curve_style(i: int) -> Tuple[str, str]:
    """(colour, line style) of a panel's ``i``-th curve: ten colours, then the next line style."""
    return f"C{i % 10}", LINE_STYLES[(i // 10) % len(LINE_STYLES)]


def save_panels(path: Path, panels: Sequence[Panel], suptitle: Optional[str] = None, ncols: int = 1) -> Path:
    """Draw the panels (:func:`draw_panels`) into the PNG ``path``."""
    plt = pyplot()
    fig = draw_panels(panels, suptitle, ncols)
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path


def draw_panels(panels: Sequence[Panel], suptitle: Optional[str] = None, ncols: int = 1):
    """A matplotlib figure of the panels, ``ncols`` to a row, each legend to the right of its axes."""
    nrows = -(-len(panels) // ncols)
    title_in = 0.2 * (suptitle.count("\n") + 1) + 0.1 if suptitle else 0.0   # room for the title lines [in]
    height_in = 3.6 * nrows + title_in
    plt = pyplot()
    # each panel's legend sits to the right of its axes, never over the traces
    longest = max([len(c.label) for panel in panels for c in panel.curves] + [0])
    legend_in = min(0.065 * longest + 0.6, 3.5) if longest else 0.0
    fig, axes = plt.subplots(nrows, ncols, figsize=((7.5 + legend_in) * ncols, height_in), squeeze=False)
    for ax, panel in zip(axes.ravel(), panels):
        for i, c in enumerate(panel.curves):
            colour, dashes = curve_style(i)
            marker = c.style.replace("-", "").replace(":", "").replace(".", "") or None
            ax.plot(c.x, c.y, color=colour, ls=dashes if "-" in c.style or ":" in c.style else "none",
                    marker=marker, label=c.label, lw=1.2, ms=4)
            if c.lower is not None and c.upper is not None:
                ax.fill_between(c.x, c.lower, c.upper, color=colour, alpha=0.2, lw=0)
        for value, label in panel.hlines:
            ax.axhline(value, color="k", ls="--", lw=0.9)
            ax.annotate(label, (0.01, value), xycoords=("axes fraction", "data"), fontsize=8,
                        va="bottom", color="k")
        draw_spans(ax, panel.spans)
        if panel.logx:
            ax.set_xscale("log")
        if panel.logy:
            ax.set_yscale("log")
        ax.set_xlabel(panel.xlabel)
        ax.set_ylabel(panel.ylabel)
        if panel.title:
            ax.set_title(panel.title, fontsize=10)
        ax.grid(True, alpha=0.3)
        if panel.curves:
            ax.legend(fontsize=8, ncol=1 if len(panel.curves) <= 14 else 2, loc="upper left",
                      bbox_to_anchor=(1.01, 1.0), borderaxespad=0.0)
    for ax in axes.ravel()[len(panels):]:
        ax.set_visible(False)
    if suptitle:
        fig.suptitle(suptitle, fontsize=11)
    # tight layout below the title (constrained layout does the same at twice the cost)
    fig.tight_layout(rect=(0.0, 0.0, 1.0, 1.0 - title_in / height_in))
    return fig


#: the shades of successive spans (by their place in the list: the same span has the same shade in
#: every panel); the band above the curves that holds the spans' labels (fraction of the y range)
SPAN_SHADES = ("#f3d9b1", "#cfe0f3")
SPAN_LABEL_BAND = 0.2


def draw_spans(ax, spans: Sequence[Span]) -> None:
    """Shade the spans within the axes' x range (the curves' range: the spans do not widen it), a
    dotted line at each boundary, each label in a band added above the curves (every other one a
    line lower, so that short neighbours do not overlap)."""
    lo, hi = ax.get_xlim()
    shown = [(i, s) for i, s in enumerate(spans) if s.end > lo and s.start < hi]
    if not shown:
        return
    bottom, top = ax.get_ylim()
    if ax.get_yscale() == "log":
        ax.set_ylim(bottom, top * (top / bottom) ** SPAN_LABEL_BAND)
    else:
        ax.set_ylim(bottom, top + SPAN_LABEL_BAND * (top - bottom))
    for row, (i, s) in enumerate(shown):
        a, b = max(s.start, lo), min(s.end, hi)
        if s.shade:
            ax.axvspan(a, b, color=SPAN_SHADES[i % len(SPAN_SHADES)], alpha=0.45, lw=0, zorder=0)
        for edge in (s.start, s.end):
            if lo < edge < hi:
                ax.axvline(edge, color="0.35", ls=":", lw=0.8, zorder=1)
        ax.text(0.5 * (a + b), 0.99 - 0.045 * (row % 2), s.label, transform=ax.get_xaxis_transform(), ha="center",
                va="top", fontsize=7, color="0.2", clip_on=True)
    ax.set_xlim(lo, hi)


def k_legend(k: float) -> str:
    return "k = inf (isothermal)" if np.isinf(k) else f"k = {k:g} W/K"
