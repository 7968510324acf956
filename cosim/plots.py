"""PNG plots (matplotlib, Agg backend): one curve per k, axes labelled with units."""
from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import List, Optional, Sequence, Tuple

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402


@dataclass
class Curve:
    x: Sequence[float]
    y: Sequence[float]
    label: str
    style: str = "-"


@dataclass
class Panel:
    """One axes: curves, labels (with units), optional horizontal reference lines."""

    curves: List[Curve]
    xlabel: str
    ylabel: str
    title: str = ""
    logx: bool = False
    logy: bool = False
    hlines: List[Tuple[float, str]] = field(default_factory=list)


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


def save_panels(path: Path, panels: Sequence[Panel], suptitle: Optional[str] = None, ncols: int = 1) -> Path:
    nrows = -(-len(panels) // ncols)
    fig, axes = plt.subplots(nrows, ncols, figsize=(7.5 * ncols, 3.6 * nrows), squeeze=False)
    for ax, panel in zip(axes.ravel(), panels):
        for c in panel.curves:
            ax.plot(c.x, c.y, c.style, label=c.label, lw=1.2, ms=4)
        for value, label in panel.hlines:
            ax.axhline(value, color="k", ls="--", lw=0.9)
            ax.annotate(label, (0.01, value), xycoords=("axes fraction", "data"), fontsize=8,
                        va="bottom", color="k")
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
            ax.legend(fontsize=8, ncol=2)
    for ax in axes.ravel()[len(panels):]:
        ax.set_visible(False)
    if suptitle:
        fig.suptitle(suptitle, fontsize=11)
    fig.tight_layout()
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path


def k_legend(k: float) -> str:
    return "k = inf (isothermal)" if np.isinf(k) else f"k = {k:g} W/K"
