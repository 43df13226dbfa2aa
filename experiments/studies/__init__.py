"""The study kinds: each module ``experiments/studies/KIND.py`` defines one subclass of
:class:`experiments.study.Study`; :func:`study_of` finds it by importing the module (the framework knows no
study by name). This package imports nothing of the framework, so the engine's workers can look a kind up."""
from __future__ import annotations

import importlib
import pkgutil
import sys
from pathlib import Path

from methods import InvalidInputError

#: every subclass of experiments.study.Study (filled by ``Study.__init_subclass__``)
CLASSES: set[type] = set()
#: study kind -> (its module, its instance)
_STUDIES: dict[str, tuple] = {}


class StudyKindError(InvalidInputError):
    """A config's ``kind`` names no study: no such module, or a module without exactly one Study subclass."""


def study_of(kind: str):
    """The study of ``kind`` (an instance of the :class:`experiments.study.Study` subclass its module defines)."""
    name = f"experiments.studies.{kind}"
    hit = _STUDIES.get(kind)
    if hit is not None and sys.modules.get(name) is hit[0]:
        return hit[1]
    if not isinstance(kind, str) or not kind.isidentifier():
        raise StudyKindError(f"kind: unknown kind {kind!r} (a module in experiments/studies/)")
    try:
        module = importlib.import_module(name)
    except ModuleNotFoundError as exc:
        if exc.name != name:
            raise
        raise StudyKindError(f"kind: unknown kind {kind!r} (a module in experiments/studies/)") from None
    classes = [c for c in vars(module).values() if isinstance(c, type) and c in CLASSES and c.__module__ == name]
    if len(classes) != 1:
        old = [f for f in ("analyse", "tasks", "execute", "validate", "count_rows", "CONFIG_SCHEMA") if f in vars(module)]
        why = (f"it has module-level {', '.join(old)}: a study is a class, class "
               f"{''.join(w.title() for w in kind.split('_'))}Study(experiments.study.Study), with these as its "
               "methods and attributes (docs/experiments.md)" if old and not classes
               else f"it defines {len(classes)} (one module, one study; a helper module of the studies is named "
                    f"with a leading underscore, _{kind}.py, and is no kind)")
        raise StudyKindError(f"kind: experiments/studies/{kind}.py must define one subclass of "
                             f"experiments.study.Study; {why}")
    study = classes[0]()
    study.kind = kind
    _STUDIES[kind] = (module, study)
    return study


def kinds() -> list[str]:
    """Every study kind of this package (a module each)."""
    return sorted(m.name for m in pkgutil.iter_modules([str(Path(__file__).parent)]) if not m.name.startswith("_"))


_TOLERANCES: dict = {}


def tolerances() -> dict:
    """{column: Tolerance} of the columns the study kinds' own rows add (each class's ``tolerances``), for
    ``python -m experiments.verify``; a column two kinds declare differently is an error. A module of this package
    that is not a study (a helper without a leading underscore) declares nothing: it does not stop the comparison of
    the studies (a study of its kind says what is wrong with it when it is loaded)."""
    if not _TOLERANCES:
        merged: dict = {}
        for kind in kinds():
            try:
                study = study_of(kind)
            except StudyKindError:
                continue
            for column, tol in study.tolerances.items():
                if column in merged and merged[column] != tol:
                    raise ValueError(f"the studies declare the column {column!r} with two tolerances")
                merged[column] = tol
        _TOLERANCES.update(merged)
    return _TOLERANCES
