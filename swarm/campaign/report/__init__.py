"""Campaign reports: explored-vs-time curves with confidence bands, cactus/ECDF plots of time to target,
paired per-map comparisons of algorithms, the radio model's effect, summary tables (Markdown, LaTeX, CSV)
and MAES-format CSVs, all from a results folder. See :mod:`.build` for the folder layout and
:mod:`.stats` for the statistical choices."""

from .build import build_report

__all__ = ["build_report"]
