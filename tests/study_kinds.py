"""A study kind of a test's own, found as the project's are (a module ``experiments.studies.KIND``), and the TOML of
the small studies the tests run."""
from __future__ import annotations

import sys
import types


def plant(monkeypatch, kind: str, **attrs) -> types.ModuleType:
    """The module ``experiments.studies.KIND`` holding ``attrs`` (each class among them made the module's own, as a
    ``Study`` subclass defined there would be), in ``sys.modules`` for this test only."""
    module = types.ModuleType(f"experiments.studies.{kind}")
    for name, value in attrs.items():
        if isinstance(value, type):
            value.__module__ = module.__name__
        setattr(module, name, value)
    monkeypatch.setitem(sys.modules, module.__name__, module)
    return module


def small_study(name: str, title: str, kind: str = "", findings: str = "") -> str:
    """A study NAME of ``kind`` (none: the base study): 2 repetitions of circle.kasa on a circle of 12 points (centre
    (1, 2) mm, radius 5 mm, noise 0.01 mm), seed 3; ``findings``: its ``[report] findings`` template."""
    return (f'name = "{name}"\ntitle = "{title}"\n' + (f'kind = "{kind}"\n' if kind else "") + "seed = 3\n"
            "repetitions = 2\n\n[[datasets]]\nsource = \"circle\"\n"
            "params = { center = [1.0, 2.0], radius = 5.0, noise = 0.01, n = 12 }\n\n"
            "[[methods]]\nid = \"circle.kasa\"\n" + (f'\n[report]\nfindings = "{findings}"\n' if findings else ""))


def circle_study(folder, name: str, title: str, method_ids, repetitions: int, extra: str = ""):
    """``folder/NAME.toml`` (its path): a grid study (seed 3) of ``repetitions`` of one generated circle (30 points,
    radius 5 mm, noise 0.01 mm) with the methods ``method_ids``; ``extra``: more top-level lines
    (``chunk_rows = 6``)."""
    study = folder / f"{name}.toml"
    study.write_text(f'name = "{name}"\ntitle = "{title}"\nkind = "grid"\nseed = 3\nrepetitions = {repetitions}\n'
                     f'{extra}[[datasets]]\nsource = "circle"\nparams = {{ radius = 5.0, noise = 0.01, n = 30 }}\n'
                     + "".join(f'[[methods]]\nid = "{m}"\n' for m in method_ids))
    return study
