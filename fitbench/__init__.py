"""fitbench: fitting methods of machine-tool metrology compared on published and synthetic data.

The ``fitbench`` console command (``fitbench --help``) dispatches to ``fitbench.cli`` (fit, list,
circular-test, positioning, magnify, multilaterate, ...) and to the experiment runner (run, report,
verify). ``__version__`` is the package's one version number (pyproject.toml reads it from here).
"""
__version__ = "0.1.0"
