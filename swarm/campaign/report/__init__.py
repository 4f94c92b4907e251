"""Campaign reports: explored-vs-time curves with confidence bands, cactus/ECDF plots of time to target,
paired per-map comparisons of algorithms, the radio model's effect, summary tables (Markdown, LaTeX, CSV)
and MAES-format CSVs, all from a results folder. See :mod:`.build` for the folder layout, :mod:`.stats` for
the statistical choices and :mod:`.effects` for the paired tests, effect sizes, Holm's correction and the
``compare_cells`` hook for ablations."""

from .build import build_report

__all__ = ["build_report"]
