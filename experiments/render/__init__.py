"""Rendering helpers for the comparison report: one figure style (``style``), LaTeX tables (``latex``),
Dolan–Moré performance profiles (``profiles``), HTML tables coloured relative to the best method
(``html_tables``) and the redrawn study figures (``figures``). None of them knows a study by name."""
