"""One loader for every plugin group (methods.plugins.load_entry_points): a broken plugin of the
``fitbench.methods`` or ``fitbench.datasets`` group is skipped with one warning of one line (which entry
point, which distribution, why, what to do), the built-ins keep working, and each group loads once."""
import pytest

from conftest import install_plugin, run_python

BROKEN = '''
raise RuntimeError("boom: the plugin's own bug\\nsecond line of the message")
'''

HALF = '''
"""Registers a method and three data sources, then fails: none of them may stay registered."""
from methods import register
from methods.results import circle_result
from datasets.sources import register_source

for name in ("half_a", "half_b", "half_c"):
    register_source(name, random=False, summary="half-registered plugin source")(lambda rng=None: (None, None))


@register("circle.half_method", kind="closed form", summary="half-registered", reference="fitbench test")
def half_method(points):
    return circle_result(points, points[0], 1.0, converged=True, message="closed form")


raise ImportError("boom: a dependency of the plugin is missing")
'''

GOOD = '''
from methods import register
from methods.results import circle_result


@register("circle.first_point", kind="closed form", summary="plugin-loading test", reference="fitbench test")
def first_point(points):
    return circle_result(points, points[0], 1.0, converged=True, message="closed form")
'''


@pytest.fixture(scope="module")
def broken_site(tmp_path_factory):
    """A distribution with a broken entry point in each group and a working method beside them."""
    return install_plugin(tmp_path_factory.mktemp("broken"), "fitbench-broken-plugin",
                          {"fitbench_broken": BROKEN, "fitbench_good": GOOD},
                          {"fitbench.methods": {"bad_method": "fitbench_broken", "good": "fitbench_good"},
                           "fitbench.datasets": {"bad_source": "fitbench_broken"}}, version="0.2")


def plugin_lines(stderr: str) -> list[str]:
    return [line for line in stderr.splitlines() if "fitbench_broken" in line or "boom" in line]


def check_one_line(stderr: str, what: str, name: str, group: str) -> None:
    assert "Traceback" not in stderr and "second line" not in stderr, stderr
    lines = plugin_lines(stderr)
    assert len(lines) == 1, stderr
    line = lines[0]
    for part in (f"{what} plugin {name!r}", "'fitbench_broken'", f"group {group!r}",
                 "distribution fitbench-broken-plugin 0.2", "RuntimeError: boom: the plugin's own bug",
                 "fix or uninstall that distribution"):
        assert part in line, (part, line)


def test_broken_method_plugin_warns_in_one_line_and_the_rest_works(broken_site):
    out = run_python("-m", "methods", "list", path_first=[broken_site])
    assert out.returncode == 0, out.stderr
    listed = [line.split()[0] for line in out.stdout.splitlines() if line.strip()]
    assert "circle.kasa" in listed and "circle.first_point" in listed  # built-ins and the working plugin
    check_one_line(out.stderr, "method", "bad_method", "fitbench.methods")


def test_broken_data_source_plugin_warns_in_one_line_and_the_rest_works(broken_site):
    code = "from datasets import sources; print(sorted(s.name for s in sources.list_sources()))"
    out = run_python("-c", code, path_first=[broken_site])
    assert out.returncode == 0, out.stderr
    assert "'circle'" in out.stdout and "'published'" in out.stdout
    check_one_line(out.stderr, "data source", "bad_source", "fitbench.datasets")


def test_each_group_is_loaded_once_per_process(broken_site):
    """Asking the registries again imports no entry point again (one warning per group, even with -W always)."""
    code = ("import methods; from datasets import sources\n"
            "for _ in range(3): methods.list_methods(); sources.list_sources(); methods.get('circle.kasa')\n")
    out = run_python("-W", "always", "-c", code, path_first=[broken_site])
    assert out.returncode == 0, out.stderr
    lines = plugin_lines(out.stderr)
    assert len(lines) == 2, out.stderr
    assert sum("'fitbench.methods'" in line for line in lines) == 1
    assert sum("'fitbench.datasets'" in line for line in lines) == 1


def test_the_registries_share_one_loader():
    """Both groups go through methods.plugins.load_entry_points (no second copy of the loop)."""
    import inspect

    import methods._registry
    from datasets import sources
    for module in (methods._registry, sources):
        code = inspect.getsource(module)
        assert "load_entry_points(" in code and "entry_points(group" not in code, module.__name__


@pytest.fixture(scope="module")
def half_site(tmp_path_factory):
    return install_plugin(tmp_path_factory.mktemp("half"), "fitbench-half-plugin", {"fitbench_half": HALF},
                          {"fitbench.methods": {"half": "fitbench_half"}}, version="1.0")


def test_a_plugin_that_fails_to_load_registers_nothing(half_site):
    """The entry point registered a method and three data sources before its import failed: after the warning
    neither registry holds any of them (the data sources were registered from a method entry point)."""
    code = ("import methods; from datasets import sources\n"
            "ids = [s.id for s in methods.list_methods()]\n"
            "names = [s.name for s in sources.list_sources()]\n"
            "print('circle.half_method' in ids, [n for n in names if n.startswith('half_')], 'circle.kasa' in ids)\n")
    out = run_python("-c", code, path_first=[half_site])
    assert out.returncode == 0, out.stderr
    assert out.stdout.strip() == "False [] True"
    assert "failed to load and is skipped: ImportError: boom" in out.stderr


def test_provenance_names_a_plugin_installed_inside_the_checkout(tmp_path):
    """An environment inside the checkout (the README's ``.venv``): the plugin's distribution is still named,
    both for what its entry point registered and for a module found by its top-level package."""
    import shutil
    import uuid

    from conftest import REPO
    inside = REPO / ".venv" / f"plugin-test-{uuid.uuid4().hex[:8]}"
    try:
        site = install_plugin(inside, "fitbench-inside-plugin", {"fitbench_inside": GOOD},
                              {"fitbench.methods": {"good": "fitbench_inside"}}, version="0.7")
        code = ("import methods; from methods.plugins import distributions_of\n"
                "print(distributions_of([methods.get('circle.first_point').module, 'methods.circle.algebraic']))\n"
                "import importlib.metadata as m; print(m.packages_distributions().get('fitbench_inside'))\n")
        out = run_python("-c", code, path_first=[site])
        assert out.returncode == 0, out.stderr
        assert out.stdout.splitlines()[0] == "{'fitbench-inside-plugin': '0.7'}"
    finally:
        shutil.rmtree(inside, ignore_errors=True)
        if inside.parent.is_dir() and not any(inside.parent.iterdir()):
            inside.parent.rmdir()


REGISTERS_THEN_FAILS = '''
"""Registers a method (which loads the built-ins, the first plugin register does), then fails."""
from methods import register
from methods.results import circle_result


@register("circle.bad", kind="closed form", summary="registers then fails", reference="fitbench test")
def bad(points):
    return circle_result(points, points[0], 1.0, converged=True, message="closed form")


raise RuntimeError("boom: failed after registering")
'''


@pytest.fixture(scope="module")
def fails_after_register_site(tmp_path_factory):
    return install_plugin(tmp_path_factory.mktemp("after"), "fitbench-after-plugin", {"fitbench_after": REGISTERS_THEN_FAILS},
                          {"fitbench.methods": {"after": "fitbench_after"}}, version="0.1")


def listed_ids(out) -> list[str]:
    assert out.returncode == 0, out.stderr
    return [line.split()[0] for line in out.stdout.splitlines() if line.strip()]


def test_a_plugin_failing_after_register_takes_out_only_its_own_method(fails_after_register_site, tmp_path):
    """'list' with a plugin that registers then raises: every built-in method is still listed (the failing
    plugin's rollback takes out only what it added), and the manifest cached by that listing is whole: a later
    listing without the plugin, from the same cache, shows every built-in too."""
    builtins = listed_ids(run_python("-m", "methods", "list", FITBENCH_CACHE_DIR=str(tmp_path / "clean")))
    assert len(builtins) > 20 and "circle.kasa" in builtins and "roundness.iso12181" in builtins
    cache = str(tmp_path / "cache")
    with_plugin = run_python("-m", "methods", "list", path_first=[fails_after_register_site], FITBENCH_CACHE_DIR=cache)
    assert listed_ids(with_plugin) == builtins
    assert "failed to load and is skipped: RuntimeError: boom: failed after registering" in with_plugin.stderr
    assert listed_ids(run_python("-m", "methods", "list", FITBENCH_CACHE_DIR=cache)) == builtins
    # a current manifest already cached: the plugin's failure does not take the built-ins out either
    again = run_python("-m", "methods", "list", path_first=[fails_after_register_site], FITBENCH_CACHE_DIR=cache)
    assert listed_ids(again) == builtins


def test_built_ins_registered_while_a_plugin_loads_are_not_the_plugin_s(fails_after_register_site):
    """Built-ins loaded by a plugin's first register belong to no plugin: a failing data-source plugin that
    registered a method does not take them out, and a loaded plugin's distribution is not named for them."""
    code = ("from datasets import sources; sources.list_sources()\n"
            "import methods; from methods.plugins import distributions_of\n"
            "ids = [s.id for s in methods.list_methods()]\n"
            "print('circle.kasa' in ids, 'roundness.iso12181' in ids, 'circle.half_method' in ids,\n"
            "      distributions_of(['methods.circle.algebraic', 'methods.roundness.iso12181']))\n")
    site = install_plugin(fails_after_register_site.parent / "ds", "fitbench-ds-plugin", {"fitbench_ds": HALF},
                          {"fitbench.datasets": {"half_ds": "fitbench_ds"}}, version="0.3")
    out = run_python("-c", code, path_first=[site])
    assert out.returncode == 0, out.stderr
    assert out.stdout.split() == ["True", "True", "False", "{}"], out.stdout + out.stderr
    good = install_plugin(fails_after_register_site.parent / "good", "fitbench-good-plugin", {"fitbench_good2": GOOD},
                          {"fitbench.methods": {"good": "fitbench_good2"}}, version="0.4")
    code = ("from methods import _manifest; _manifest.describe_methods()\n"
            "from methods.plugins import distributions_of\n"
            "print(distributions_of(['fitbench_good2', 'methods.circle.algebraic', 'methods.roundness.iso12181']))\n")
    out = run_python("-c", code, path_first=[good], FITBENCH_CACHE_DIR=str(fails_after_register_site.parent / "c"))
    assert out.returncode == 0, out.stderr
    assert out.stdout.strip() == "{'fitbench-good-plugin': '0.4'}"


@pytest.mark.slow
def test_experiments_run_reports_a_broken_plugin_once_in_one_line(broken_site, tmp_path):
    """``experiments.run`` with worker processes (spawned: each loads the plugins again) prints the plugin's
    warning once, as 'fitbench: warning: ...', not in ``warnings``' format with a file path and source line."""
    out = run_python("-m", "experiments.run", "ellipse_angle", "--quick", "--jobs", "2", "--no-report",
                     "--out", tmp_path / "results", path_first=[broken_site])
    assert out.returncode == 0, out.stderr
    lines = plugin_lines(out.stderr)
    assert len(lines) == 2, out.stderr          # the method group and the data-source group, once each
    assert all(line.startswith("fitbench: warning: ") for line in lines), out.stderr
    assert "PluginLoadWarning" not in out.stderr and "load_plugins()" not in out.stderr


def test_a_built_in_method_needs_no_plugin_loaded(broken_site):
    """Fitting with a built-in method (what fitbench circular-test or positioning do) imports no plugin: a broken or
    slow one unrelated to it neither warns nor delays; a plugin's method id still loads the plugins."""
    code = ("import numpy as np, methods\n"
            "t = np.linspace(0, 6, 30)\n"
            "print(methods.fit('circle.kasa', np.column_stack([np.cos(t), np.sin(t)])).radius)\n"
            "import sys; print(sorted(m for m in sys.modules if m.startswith('fitbench_')))\n"
            "print(methods.get('circle.first_point').id)\n")
    out = run_python("-c", code, path_first=[broken_site])
    assert out.returncode == 0, out.stderr
    lines = out.stdout.splitlines()
    assert float(lines[0]) == pytest.approx(1.0) and lines[1] == "[]" and lines[2] == "circle.first_point"
    assert len(plugin_lines(out.stderr)) == 1  # the broken plugin is met only when the plugins load
