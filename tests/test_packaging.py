"""Guards: the top-level packages are fitbench's own, not same-named packages from PyPI."""
from conftest import REPO


def test_datasets_is_fitbench_package():
    import datasets
    assert getattr(datasets, "FITBENCH", False), f"imported a foreign 'datasets' from {datasets.__file__}"
    assert REPO in __import__("pathlib").Path(datasets.__file__).resolve().parents


def test_methods_and_experiments_are_from_repository():
    import experiments
    import methods
    from pathlib import Path
    for mod in (methods, experiments):
        assert REPO in Path(mod.__file__).resolve().parents, mod.__file__
