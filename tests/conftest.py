"""Shared fixtures and helpers. Tests import fitbench's own ``datasets``/``methods`` from the repository;
a test that starts another Python (a CLI, a study run, a Dask worker) gives it :func:`subprocess_env`, and
a test that needs a third-party plugin builds one offline with :func:`install_plugin`, and a test that
interrupts a run among its rows does it through :func:`while_storing_rows` (not after a poll that a loaded
machine makes late), and a test that only reads the rows of a default study's quick grid takes them from
:func:`quick_study` (one run per test session, not one per test)."""
import fcntl
import os
import shutil
import signal
import sqlite3
import subprocess
import sys
import textwrap
import time
from pathlib import Path

# One BLAS thread per test process, set before NumPy is first imported (no pytest plugin imports it earlier) and
# inherited by every Python a test starts, unless the user chose otherwise: with `-n auto` on 2 cores, two xdist
# workers x 2 OpenBLAS threads oversubscribe the cores, and OpenBLAS's waiting threads made the circular-test
# diagnostics' small least-squares solves ~9x slower in CPU (10 arcs of the coverage test: 3.5 s against 0.39 s).
# The same rule as the engine's workers (experiments.executors.BLAS_THREAD_VARS).
for _var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")

import numpy as np  # noqa: E402  (after the BLAS thread count)
import pytest

REPO = Path(__file__).resolve().parents[1]


@pytest.fixture
def rng():
    return np.random.default_rng(20261121)


def nist_dir() -> Path | None:
    """Directory of the NIST Circle2d reference sets, from FITBENCH_NIST_DIR (None if unset/missing)."""
    value = os.environ.get("FITBENCH_NIST_DIR")
    if not value:
        return None
    path = Path(value)
    return path if path.is_dir() else None


def subprocess_env(*path_first, repo: Path = REPO, **variables) -> dict:
    """The environment of a child Python that imports fitbench from ``repo`` (this checkout, or a copy of it)
    from any working directory: PYTHONPATH = ``path_first`` (e.g. a plugin's install folder), then ``repo``;
    ``variables`` are set on top of this process's environment."""
    return {**os.environ, **variables, "PYTHONPATH": os.pathsep.join([*map(str, path_first), str(repo)])}


def stop_processes(procs) -> None:
    """Terminate the processes a test started (a scheduler and its workers: the last started first), and kill those
    still alive 20 s later."""
    for p in reversed(procs):
        p.terminate()
    for p in procs:
        try:
            p.wait(timeout=20)
        except subprocess.TimeoutExpired:
            p.kill()


def run_python(*args, cwd=REPO, path_first=(), repo: Path = REPO, timeout=600, preexec_fn=None, **variables):
    """``python ARGS`` in ``cwd`` with :func:`subprocess_env`, output captured as text."""
    return subprocess.run([sys.executable, *map(str, args)], cwd=cwd, capture_output=True, text=True,
                          timeout=timeout, env=subprocess_env(*path_first, repo=repo, **variables), preexec_fn=preexec_fn)


def default_sigint() -> None:
    """In a child before it runs (``preexec_fn``): SIGINT's and SIGHUP's default actions, as in a terminal. A test run
    in the background of a shell without job control inherits SIGINT ignored, and one run under ``nohup`` SIGHUP
    ignored: a Python started so never sees a Ctrl-C, and a run keeps SIGHUP ignored (as it should under nohup)."""
    import signal
    signal.signal(signal.SIGINT, signal.SIG_DFL)
    if hasattr(signal, "SIGHUP"):
        signal.signal(signal.SIGHUP, signal.SIG_DFL)


def stored_rows(db: Path) -> int:
    """Rows in a run's row store (0 while it does not exist or cannot be read)."""
    try:
        con = sqlite3.connect(f"file:{db}?mode=ro", uri=True, timeout=0.2)
        try:
            return con.execute("SELECT count(*) FROM rows").fetchone()[0]
        finally:
            con.close()
    except sqlite3.Error:
        return 0


def while_storing_rows(proc: subprocess.Popen, db: Path, at_least: int, total: int, act, *, group: bool,
                       timeout: float = 300.0) -> int | None:
    """Call ``act()`` (send a signal, kill...) while the run ``proc`` is among its rows: ``at_least`` of its
    ``total`` rows are in the row store ``db`` and the others are not. Whatever the speed of the machine or its load,
    the run cannot get past its rows between the count and ``act``: the test stops it (SIGSTOP; its whole process
    group with ``group``, which must then be its own session) for the count and ``act``, then lets it go on
    (SIGCONT), so a signal that ``act`` sends lands among the rows.

    Returns the rows counted, or None when the run stored all its rows or ended while it ran between two counts
    (this test was descheduled that long: start the run again)."""
    pause = (lambda s: os.killpg(proc.pid, s)) if group else (lambda s: os.kill(proc.pid, s))
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        if proc.poll() is not None:
            return None
        pause(signal.SIGSTOP)
        try:
            n = stored_rows(db)
            if n >= total:
                return None
            if n >= at_least:
                act()
                return n
        finally:
            try:
                pause(signal.SIGCONT)
            except ProcessLookupError:  # ``act`` killed it (and its group)
                pass
        time.sleep(0.02)
    raise AssertionError(f"the run stored fewer than {at_least} rows in {timeout:.0f} s")


def once_per_session(tmp_path_factory, name: str, make) -> Path:
    """The folder ``name`` of this test session, filled by ``make(folder)`` once: the pytest-xdist workers whose tests
    need it share it (the first fills it under a file lock in the session's temporary folder, the others wait for
    it). Its users only read it."""
    base = tmp_path_factory.getbasetemp()
    worker = os.environ.get("PYTEST_XDIST_WORKER")  # set in each pytest-xdist worker
    shared = (base.parent if worker else base) / name  # the session's folder, above each worker's own
    shared.parent.mkdir(parents=True, exist_ok=True)
    with open(shared.parent / f"{name}.lock", "w") as lock:
        fcntl.flock(lock, fcntl.LOCK_EX)
        if not (shared / ".done").exists():
            shutil.rmtree(shared, ignore_errors=True)
            shared.mkdir()
            make(shared)
            (shared / ".done").write_text("")
    return shared


def run_once_per_session(tmp_path_factory, name: str, args, cwd: Path = REPO, **variables) -> Path:
    """The results folder of ``python -m experiments.run ARGS --out RESULTS`` (in ``cwd``, with
    :func:`subprocess_env` and ``variables``), run once per test session (:func:`once_per_session`); what the run
    printed is in ``stdout.txt`` beside that folder. Its users only read it."""
    def make(folder):
        proc = subprocess.run([sys.executable, "-m", "experiments.run", *map(str, args), "--out", str(folder / "results")],
                              cwd=cwd, capture_output=True, text=True, timeout=1800, env=subprocess_env(**variables))
        assert proc.returncode == 0, proc.stderr[-2000:]
        (folder / "stdout.txt").write_text(proc.stdout, encoding="utf-8")
    return once_per_session(tmp_path_factory, name, make) / "results"


#: two machines for the reproduction tests: an AVX2 machine (OpenBLAS's Haswell kernels, NumPy's loops limited to AVX2
#: + FMA) and this CPU's NumPy loops with OpenBLAS's Sandybridge kernels (AVX, no FMA); tests/test_cpu_independence.py
MACHINES = {
    "avx2_fma": {"OPENBLAS_CORETYPE": "Haswell", "NPY_DISABLE_CPU_FEATURES": "X86_V4 AVX512_ICL AVX512_SPR"},
    "other_blas": {"OPENBLAS_CORETYPE": "Sandybridge"},
}


def quick_run_on(tmp_path_factory, machine: str) -> Path:
    """The results folder of ``python -m experiments.run --quick --jobs 2`` from the repository (every default
    study's quick grid, compared with results/quick, and its report in ``paper/``) on the simulated ``machine`` of
    :data:`MACHINES`, once per test session (:func:`run_once_per_session`). Its users only read it."""
    return run_once_per_session(tmp_path_factory, f"quick-{machine}", ["--quick", "--jobs", "2"], cwd=REPO,
                                OPENBLAS_NUM_THREADS="1", **MACHINES[machine])


def quick_study(tmp_path_factory, name: str) -> Path:
    """The folder of the shipped study ``name`` run on its quick grid, once per test session; read only. Without
    ``--system``: run with one job in this process (``run_study(name, OUT, quick=True, jobs=1)``,
    :func:`once_per_session`). With ``--system``: the study's folder of the session's whole quick run on the simulated
    AVX2 machine (:func:`quick_run_on`, which the system tier runs anyway: tests/test_cpu_independence.py,
    tests/test_verify.py), the same study's quick grid and outputs, checked against results/quick by that run; not
    a second run of the same rows (~40 s of CPU for these studies in this process)."""
    if SYSTEM_TIER:
        return quick_run_on(tmp_path_factory, "avx2_fma") / name
    from experiments.run import run_study
    def make(folder):
        run_study(name, folder / "results", quick=True, jobs=1, log=lambda *a: None)
    shared = once_per_session(tmp_path_factory, f"quick-{name}", make)
    return shared / "results" / name


def install_plugin(workdir: Path, name: str, modules: dict, entry_points: dict, version: str = "0.0.1") -> Path:
    """Install a plugin distribution offline into a new folder ``workdir/site`` and return that folder (put it first on
    PYTHONPATH). The files are those ``pip install --target`` of its built wheel writes (PyPA's "Recording installed
    projects"): the modules and ``NAME-VERSION.dist-info`` with METADATA, entry_points.txt, top_level.txt, WHEEL,
    INSTALLER, REQUESTED, direct_url.json (naming the source folder ``workdir/plugin_src``, with its pyproject.toml)
    and the RECORD of them all with their sha256 and sizes, which importlib.metadata reads (entry points, version,
    the files a plugin's rows are keyed by). Written here in milliseconds: pip took 1-3 s of CPU per plugin.

    ``modules`` maps a top-level module name to its source; ``entry_points`` maps an entry-point group
    (``fitbench.methods``, ``fitbench.datasets``) to ``{entry point name: module}``."""
    import base64
    import hashlib
    import json
    import re
    src, site = Path(workdir) / "plugin_src", Path(workdir) / "site"
    src.mkdir(parents=True)
    site.mkdir()
    groups = "".join(f'[project.entry-points."{group}"]\n' + "".join(f'{ep} = "{value}"\n' for ep, value in eps.items())
                     for group, eps in entry_points.items())
    py_modules = ", ".join(f'"{m}"' for m in modules)
    (src / "pyproject.toml").write_text(
        '[build-system]\nrequires = ["setuptools>=61"]\nbuild-backend = "setuptools.build_meta"\n'
        f'[project]\nname = "{name}"\nversion = "{version}"\n{groups}'
        f'[tool.setuptools]\npy-modules = [{py_modules}]\n')
    info = f"{re.sub(r'[-_.]+', '_', name)}-{version}.dist-info"
    files = {f"{module}.py": textwrap.dedent(code) for module, code in modules.items()}
    for module, code in files.items():
        (src / module).write_text(code)
    files.update({
        f"{info}/METADATA": f"Metadata-Version: 2.4\nName: {name}\nVersion: {version}\n",
        f"{info}/entry_points.txt": "\n".join(f"[{group}]\n" + "".join(f"{ep} = {value}\n" for ep, value in eps.items())
                                              for group, eps in entry_points.items()),
        f"{info}/top_level.txt": "".join(f"{m}\n" for m in sorted(modules)),
        f"{info}/WHEEL": "Wheel-Version: 1.0\nGenerator: fitbench tests\nRoot-Is-Purelib: true\nTag: py3-none-any\n",
        f"{info}/INSTALLER": "pip\n",
        f"{info}/REQUESTED": "",
        f"{info}/direct_url.json": json.dumps({"dir_info": {}, "url": src.resolve().as_uri()}),
    })
    record = []
    for rel, text in files.items():
        data = text.encode()
        (site / rel).parent.mkdir(parents=True, exist_ok=True)
        (site / rel).write_bytes(data)
        digest = base64.urlsafe_b64encode(hashlib.sha256(data).digest()).rstrip(b"=").decode()
        record.append(f"{rel},sha256={digest},{len(data)}\n")
    (site / info / "RECORD").write_text("".join(sorted(record + [f"{info}/RECORD,,\n"])))
    return site


#: whether this session runs the system tier (``--system``); set by :func:`pytest_configure` in every process of a
#: session (pytest-xdist's workers included)
SYSTEM_TIER = False


def pytest_configure(config):
    global SYSTEM_TIER
    SYSTEM_TIER = bool(config.getoption("--system"))


def pytest_addoption(parser):
    parser.addoption("--system", action="store_true",
                     help="also run the system tier (tests marked 'system': end-to-end runs of whole installations and "
                          "processes); .ci/run runs it as its own step")


def pytest_collection_modifyitems(config, items):
    """The system tier is deselected (not skipped) unless ``--system`` is given: the default command runs the
    whole suite but for those, and ``-m system --system`` runs them alone."""
    if config.getoption("--system"):
        return
    kept, dropped = [], []
    for item in items:
        (dropped if item.get_closest_marker("system") else kept).append(item)
    if dropped:
        config.hook.pytest_deselected(items=dropped)
        items[:] = kept
