"""Turn an :class:`~cosim.outcome.Outcome` into files: the time series (CSV, one file per case),
``summary.csv``, the figures (PNG) and ``run.json`` (provenance, status, metrics, diagnoses,
warnings), in that order; every file is written atomically."""
from __future__ import annotations

from concurrent.futures import ProcessPoolExecutor
from pathlib import Path
from typing import Sequence

from .outcome import Outcome
from .plots import Figure
from .results import write_columns, write_rows, write_run_json
from .series import case_columns


def write_outcome(outcome: Outcome, out: Path, figures: Sequence[Figure] = (), jobs: int = 1) -> None:
    """Write everything ``outcome`` holds into the folder ``out``; ``figures`` are drawn on up to
    ``jobs`` processes."""
    out = Path(out)
    for name, ds in outcome.series.items():
        if "case" in ds.dims:
            for case in ds["case"].values:
                write_columns(out / "timeseries" / f"{name}_{case}.csv", case_columns(ds, case))
        else:
            write_columns(out / "timeseries" / f"{name}.csv", case_columns(ds))
    write_rows(out / "summary.csv", outcome.rows)
    save_figures(out, figures, jobs)
    write_run_json(out, outcome.scenario, outcome.wall_s,
                   {"diverged": outcome.diverged, "metrics": outcome.metrics, "warnings": outcome.warnings,
                    **outcome.info})


def save_figures(out: Path, figures: Sequence[Figure], jobs: int = 1) -> None:
    """Draw independent figures into ``out`` on up to ``jobs`` processes, the largest first."""
    figures = sorted(figures, key=lambda f: -len(f.panels))
    workers = max(1, min(jobs, len(figures)))
    if workers == 1:
        for figure in figures:
            figure.save(out)
        return
    with ProcessPoolExecutor(workers) as pool:
        list(pool.map(Figure.save, figures, [out] * len(figures)))
