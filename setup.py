"""Build of fitbench's compiled kernels; everything else is declared in pyproject.toml.

Each kernel is a small C99 extension over the CPython buffer protocol (no NumPy headers needed to build).
They are compiled without -ffast-math and with floating-point contraction off, so every operation is the
IEEE one its C source names, in source order: the same bits on every x86-64 CPU (AMD or Intel) and no FMA
contraction on aarch64. ``methods/_compiled.py`` loads them; ``FITBENCH_KERNELS=numpy`` selects the NumPy
reference path that tests compare them against.
"""
import hashlib
from pathlib import Path

from setuptools import Extension, setup

#: (importable module name, C source) of every compiled kernel.
KERNELS: list[tuple[str, str]] = [
    ("methods.circle._ckernels", "methods/circle/_ckernels.c"),
    ("methods.ellipse._ckernels", "methods/ellipse/_ckernels.c"),
]

COMPILE_ARGS = ["-std=c99", "-O2", "-ffp-contract=off", "-fno-fast-math", "-fno-associative-math"]



def source_sha256(source: str) -> str:
    """The SHA-256 of a kernel's C source, built into the kernel (its ``source_sha256``): methods/_compiled.py refuses a
    kernel whose source beside it has changed since it was built."""
    return hashlib.sha256(Path(source).read_bytes()).hexdigest()


setup(ext_modules=[Extension(name, [source], extra_compile_args=COMPILE_ARGS,
                             define_macros=[("FITBENCH_SOURCE_SHA256", f'"{source_sha256(source)}"')])
                   for name, source in KERNELS])
