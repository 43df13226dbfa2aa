"""One loader for every plugin group (methods._plugins.load_entry_points): a broken plugin of the
``fitbench.methods`` or ``fitbench.datasets`` group is skipped with one warning of one line (which entry
point, which distribution, why, what to do), the built-ins keep working, and each group loads once."""
import pytest

from conftest import install_plugin, run_python

BROKEN = '''
raise RuntimeError("boom: the plugin's own bug\\nsecond line of the message")
'''

GOOD = '''
from methods import register
from methods._result import circle_result


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
    """Both groups go through methods._plugins.load_entry_points (no second copy of the loop)."""
    import inspect

    import methods._registry
    from datasets import sources
    for module in (methods._registry, sources):
        code = inspect.getsource(module)
        assert "load_entry_points(" in code and "entry_points(group" not in code, module.__name__
