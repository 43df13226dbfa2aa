"""Layers run one way: fitbench (command line, exports) -> experiments -> fitbench.plots -> datasets -> methods.

The import graph of the product packages is read with ``ast`` (every ``import`` statement, at module level and
inside functions, resolved to the product module it names): no module imports a higher layer, the graph has no
cycle, neither at module level nor through imports inside functions (which only postpone a cycle to the first
call), and ``methods`` imports no argparse, matplotlib, datasets, experiments or fitbench.
``fitbench.plots`` (matplotlib figures of results) sits below ``experiments`` because the studies draw their
example figures with it; it imports nothing above ``datasets``. The ``fitbench`` package module itself holds
the one version number and imports nothing, so every layer may read ``fitbench.__version__``; ``fitbench.threads``
(the numerical libraries' thread count), ``fitbench.streams`` (stdout sent to stderr) and ``fitbench.stopping`` (SIGTERM
and SIGHUP stopping a command as Ctrl-C does), the standard library only, sit below every layer likewise, for the CLI,
the engine and the experiment commands. A ``__main__`` module is a program (``python -m
methods`` runs the fitbench command line), not a module anything imports, so it is not part of the graph.
"""
from __future__ import annotations

import ast
import functools
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]
PACKAGES = ("methods", "datasets", "experiments", "fitbench")
#: layer of a module: the longest matching prefix decides
LAYERS = {"fitbench.threads": -1, "fitbench.streams": -1, "fitbench.stopping": -1, "methods": 0, "datasets": 1, "fitbench.plots": 2, "experiments": 3, "fitbench": 4}
FORBIDDEN_IN_METHODS = {"argparse", "matplotlib", "datasets", "experiments", "fitbench"}


def product_modules() -> dict[str, Path]:
    mods = {}
    for pkg in PACKAGES:
        for path in (REPO / pkg).rglob("*.py"):
            parts = list(path.relative_to(REPO).with_suffix("").parts)
            if parts[-1] == "__main__":
                continue
            if parts[-1] == "__init__":
                parts = parts[:-1]
            mods[".".join(parts)] = path
    return mods


@functools.lru_cache(maxsize=None)
def _parsed(path: Path, mtime_ns: int, size: int) -> ast.Module:
    return ast.parse(path.read_text(encoding="utf-8"))


def parse(path: Path) -> ast.Module:
    """The syntax tree of ``path``, parsed once per test process while the file is unchanged (its modification time
    and size are in the key): five checks read the whole import graph (parsing the product: ~0.6 s each time)."""
    st = path.stat()
    return _parsed(path, st.st_mtime_ns, st.st_size)


def layer(module: str) -> int:
    if module == "fitbench":  # __version__ only (test_the_version_module_imports_nothing)
        return -1
    best = max((p for p in LAYERS if module == p or module.startswith(p + ".")), key=len)
    return LAYERS[best]


def imports_of(module: str, path: Path, known: set[str]):
    """(imported name, line, at module level) for every import statement; a ``from X import Y`` names X.Y
    when that is a module, else X. Relative imports are resolved against the module's package."""
    tree = parse(path)
    is_pkg = path.name == "__init__.py"
    package = module if is_pkg else module.rpartition(".")[0]
    function_nodes = set()
    for node in ast.walk(tree):
        if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef, ast.Lambda)):
            function_nodes.update(id(n) for n in ast.walk(node) if n is not node)
    for node in ast.walk(tree):
        top = id(node) not in function_nodes
        if isinstance(node, ast.Import):
            for alias in node.names:
                yield alias.name, node.lineno, top
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                base = package.split(".")
                base = base[:len(base) - (node.level - 1)]
                target = ".".join(base + ([node.module] if node.module else []))
            else:
                target = node.module or ""
            for alias in node.names:
                full = f"{target}.{alias.name}"
                yield (full if full in known else target), node.lineno, top


def graph():
    mods = product_modules()
    files = tuple((mod, path, path.stat().st_mtime_ns, path.stat().st_size) for mod, path in mods.items())
    return mods, _edges(files)


@functools.lru_cache(maxsize=None)
def _edges(files: tuple) -> tuple:
    """The import statements of ``files`` ((module, path, mtime, size), ...) as (module, imported, line, at module
    level), read once per test process while the files are unchanged."""
    known = {mod for mod, *_ in files}
    return tuple((mod, name, line, top) for mod, path, *_ in files for name, line, top in imports_of(mod, path, known))


def test_no_import_from_a_lower_layer_to_a_higher_one():
    _, edges = graph()
    upward = [f"{m}:{line} imports {n}" for m, n, line, _ in edges
              if n.split(".")[0] in PACKAGES and layer(n) > layer(m)]
    assert upward == [], "\n".join(upward)


def test_the_version_module_imports_nothing():
    tree = ast.parse((REPO / "fitbench" / "__init__.py").read_text(encoding="utf-8"))
    assert not [n for n in ast.walk(tree) if isinstance(n, (ast.Import, ast.ImportFrom))]


def test_methods_imports_no_command_line_plotting_or_higher_package():
    _, edges = graph()
    bad = [f"{m}:{line} imports {n}" for m, n, line, _ in edges
           if m.split(".")[0] == "methods" and n.split(".")[0] in FORBIDDEN_IN_METHODS]
    assert bad == [], "\n".join(bad)


def import_cycles(module_level_only: bool) -> list[list[str]]:
    """The cycles of the import graph (strongly connected components of more than one module, Tarjan), over the
    module-level imports only or over every import statement, inside functions too."""
    mods, edges = graph()
    succ = {m: set() for m in mods}
    for m, n, _, top in edges:
        if (top or not module_level_only) and n in mods and n != m:
            succ[m].add(n)
    index, low, stack, on, cycles, counter = {}, {}, [], set(), [], [0]

    def visit(v):
        index[v] = low[v] = counter[0]
        counter[0] += 1
        stack.append(v)
        on.add(v)
        for w in sorted(succ[v]):
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            comp = []
            while True:
                w = stack.pop()
                on.discard(w)
                comp.append(w)
                if w == v:
                    break
            if len(comp) > 1:
                cycles.append(sorted(comp))

    for v in sorted(mods):
        if v not in index:
            visit(v)
    return sorted(cycles)


def test_no_import_cycle_at_module_level():
    cycles = import_cycles(module_level_only=True)
    assert cycles == [], cycles


def test_no_import_cycle_even_through_imports_inside_functions():
    """A function-local import only postpones a cycle to the first call: the graph of every import statement
    has no cycle either."""
    cycles = import_cycles(module_level_only=False)
    assert cycles == [], cycles


def test_the_checker_sees_an_upward_import_cycles_and_a_relative_import(tmp_path, monkeypatch):
    """The walker itself: an upward import inside a function, a module-level cycle, a cycle closed by an import
    inside a function (only the second check sees it) and a relative import."""
    root = tmp_path
    for pkg in PACKAGES:
        (root / pkg).mkdir()
        (root / pkg / "__init__.py").write_text("")
    (root / "methods" / "a.py").write_text("def f():\n    import matplotlib\n    from experiments import run\n")
    (root / "datasets" / "b.py").write_text("from . import c\n")
    (root / "datasets" / "c.py").write_text("from datasets import b\n")
    (root / "datasets" / "d.py").write_text("def f():\n    from datasets import e\n")
    (root / "datasets" / "e.py").write_text("import datasets.d\n")
    (root / "experiments" / "run.py").write_text("")
    monkeypatch.setattr(__import__(__name__), "REPO", root)
    mods, edges = graph()
    assert ("datasets.b", "datasets.c", 1, True) in edges
    assert ("datasets.d", "datasets.e", 2, False) in edges
    upward = [(m, n) for m, n, _, _ in edges if n.split(".")[0] in PACKAGES and layer(n) > layer(m)]
    assert upward == [("methods.a", "experiments.run")]
    assert import_cycles(module_level_only=True) == [["datasets.b", "datasets.c"]]
    assert import_cycles(module_level_only=False) == [["datasets.b", "datasets.c"], ["datasets.d", "datasets.e"]]
    for test in (test_no_import_cycle_at_module_level, test_no_import_cycle_even_through_imports_inside_functions):
        try:
            test()
        except AssertionError as exc:
            assert "datasets.b" in str(exc)
            assert ("datasets.d" in str(exc)) == (test is test_no_import_cycle_even_through_imports_inside_functions)
        else:
            raise AssertionError(f"{test.__name__} did not fail on the cycle datasets.b <-> datasets.c")


def test_no_package_imports_another_packages_private_names():
    """What crosses a package boundary is public: no ``from methods._x import ...`` (or ``import methods._x``,
    or a private name from a public module) outside ``methods``, and the same for every product package."""
    bad = []
    for mod, path in product_modules().items():
        tree = parse(path)
        for node in ast.walk(tree):
            if isinstance(node, ast.ImportFrom) and not node.level and node.module:
                names = [node.module] + [f"{node.module}.{a.name}" for a in node.names]
            elif isinstance(node, ast.Import):
                names = [a.name for a in node.names]
            else:
                continue
            for name in names:
                parts = name.split(".")
                if parts[0] in PACKAGES and parts[0] != mod.split(".")[0] \
                        and any(p.startswith("_") and not p.startswith("__") for p in parts[1:]):
                    bad.append(f"{mod}:{node.lineno} imports {name}")
    assert bad == [], "\n".join(bad)


def test_every_private_module_is_imported_by_the_product():
    """A private module (``_name``) no product module imports, nor names as a string (``importlib`` by name), is
    dead code: a left-over shim. Its public counterpart is the one to use."""
    mods, edges = graph()
    imported = {name for _, name, _, _ in edges}
    imported |= {p for name in imported for p in [name.rsplit(".", k)[0] for k in range(name.count(".") + 1)]}
    named = {node.value for path in mods.values() for node in ast.walk(parse(path))
             if isinstance(node, ast.Constant) and isinstance(node.value, str)}
    dead = sorted(m for m in mods if m.rpartition(".")[2].startswith("_") and not m.rpartition(".")[2].startswith("__")
                  and m not in imported and not any(m in s for s in named))
    assert not dead, f"private modules nothing imports: {dead}"


def test_the_verdict_names_the_same_config_folder_as_the_config_module():
    """experiments.verdict keeps its own path of the project's configs (importing experiments.config would close an
    import cycle through the engine): it is the config module's."""
    from experiments import config, verdict
    assert verdict._CONFIG_DIR == config.CONFIG_DIR
