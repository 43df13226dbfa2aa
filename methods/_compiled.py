"""Access to the compiled kernels, one rule for every family.

A kernel module (``methods/<family>/_ckernels.c``, built by ``setup.py`` at install) computes the same
quantities as the NumPy reference code beside it, in fewer sweeps and without temporaries. The environment
variable ``FITBENCH_KERNELS`` chooses the path for the whole process:

* unset or ``compiled``: the compiled kernels (an install that did not build them is an error that says so, and so is
  a kernel built from another version of the C source beside it: rows keyed on that source must come from it);
* ``numpy``: the NumPy reference path (tests compare the two paths on the same data).
"""
from __future__ import annotations

import hashlib
import importlib
import os
from pathlib import Path

from methods._errors import InvalidInputError

_CHOICES = ("compiled", "numpy")


class KernelsNotBuiltError(InvalidInputError):
    """The compiled kernels are missing from this checkout or install."""


def kernel_path() -> str:
    """``"compiled"`` or ``"numpy"``, from ``FITBENCH_KERNELS`` (default ``compiled``)."""
    choice = os.environ.get("FITBENCH_KERNELS", "compiled").strip().lower() or "compiled"
    if choice not in _CHOICES:
        raise InvalidInputError(f"FITBENCH_KERNELS={choice!r} is not one of {', '.join(_CHOICES)}; "
                                "unset it for the compiled kernels")
    return choice


def kernels(module: str):
    """The compiled kernel module ``module`` (e.g. ``"methods.circle._ckernels"``), or None when the
    NumPy path is selected. A kernel that was not built raises :class:`KernelsNotBuiltError`."""
    if kernel_path() == "numpy":
        return None
    hit = _CHECKED.get(module)
    if hit is not None:
        return hit
    try:
        mod = importlib.import_module(module)
    except ImportError as exc:
        raise KernelsNotBuiltError(
            f"fitbench's compiled kernel {module} is not built ({exc}); reinstall with `pip install -e .` "
            "(or `python setup.py build_ext --inplace` in a checkout), or set FITBENCH_KERNELS=numpy") from None
    source = Path(mod.__file__).with_name(module.rpartition(".")[2] + ".c")
    if source.is_file() and getattr(mod, "source_sha256", "") != hashlib.sha256(source.read_bytes()).hexdigest():
        raise KernelsNotBuiltError(
            f"fitbench's compiled kernel {module} is stale: it was built from another version of {source.name} than "
            "the one beside it (an edit or a pull since the build); rebuild it with `pip install -e .` (or "
            "`python setup.py build_ext --inplace` in a checkout), or set FITBENCH_KERNELS=numpy")
    _CHECKED[module] = mod
    return mod


#: kernel modules imported and found built from the C source beside them (checked once per process; an installed
#: package without its C sources has nothing to be stale against)
_CHECKED: dict = {}
