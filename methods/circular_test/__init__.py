"""Circular tests of NC machine tools (ISO 230-4): evaluation, diagnostics of error sources, report."""
from methods.circular_test.diagnostics import diagnose
from methods.circular_test.evaluation import evaluate

__all__ = ["evaluate", "diagnose"]
