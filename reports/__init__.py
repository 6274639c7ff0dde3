"""HTML comparison report: ``build_report(out_dir, comparisons)`` writes
``out_dir/index.html`` and one page per scene (see :mod:`reports.build`)."""

from reports.build import build_report, scene_folder

__all__ = ["build_report", "scene_folder"]
