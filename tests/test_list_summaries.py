"""``fitbench list`` shows what each method computes (its registered one-line summary: kasa/pratt/taubin/hyper
algebraic, powell_hybrid Kåsa's objective, chebyshev_lp an algebraic Chebyshev fit), not only a citation; ``--long``
adds the reference under each line."""
import pytest

from cli_calls import cli
from fitbench.cli import main
from methods import describe_methods


def listing(*args) -> list[str]:
    called = cli("list", *args)
    assert called.returncode == 0 and called.stderr == "", called.stderr
    return called.stdout.splitlines()


def test_each_line_gives_the_id_kind_and_summary():
    specs = describe_methods("circle")
    lines = listing("--family", "circle")
    assert len(lines) == len(specs)
    for spec, line in zip(specs, lines):
        assert line.split()[0] == spec.id and spec.kind in line
        assert line.endswith(" ".join(spec.summary.split())), (spec.id, line)
    powell = next(ln for ln in lines if ln.startswith("circle.powell_hybrid"))
    assert "S_CA" in powell and "Powell hybrid" in powell   # what it solves: Kåsa's objective, by Powell's method


def test_long_adds_the_reference_under_each_method():
    specs = describe_methods("ellipse")
    lines = listing("--family", "ellipse", "--long")
    assert len(lines) == 2 * len(specs)
    for spec, (line, ref) in zip(specs, zip(lines[::2], lines[1::2])):
        assert line.startswith(spec.id) and ref.strip() == f"reference: {spec.reference}"
        assert ref.startswith(" " * len(spec.id))


def test_help_says_what_the_list_shows(capsys):
    with pytest.raises(SystemExit):
        main(["list", "--help"])
    text = " ".join(capsys.readouterr().out.split())
    assert "--long also each method's literature reference" in text
