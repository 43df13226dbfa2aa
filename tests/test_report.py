"""The comparison report: built from results only; missing and failed studies shown; HTML renders in
headless Chromium with every image loaded; LaTeX fragments compile where a toolchain exists."""
import json
import re
import shutil
import subprocess
from pathlib import Path

import numpy as np
import pytest

from experiments.report import build
from experiments.run import run_study
from conftest import quick_study


# The tests reading ``built`` are in the slow tier (pytest -m "not slow" leaves them out): the quick studies it reports
# (the magnification study's alone ~8 s of CPU; no other test of the inner loop runs them) and the report's build
# make its first test ~12 s on two cores.
@pytest.fixture(scope="module")
def built(tmp_path_factory):
    root = tmp_path_factory.mktemp("report")
    results = root / "results"
    for name in ("published", "magnification", "ellipse_angle"):
        shutil.copytree(quick_study(tmp_path_factory, name), results / name)
    # a study whose rows failed: flip the status counts of a copy
    shutil.copytree(results / "ellipse_angle", results / "broken_study")
    meta = json.loads((results / "broken_study" / "meta.json").read_text())
    meta["status_counts"] = {"ok": 3, "error": 2}
    (results / "broken_study" / "meta.json").write_text(json.dumps(meta))
    # a study whose meta.json is a JSON list, and one whose declared figures escape its folder or are no PNG
    shutil.copytree(results / "published", results / "list_meta")
    (results / "list_meta" / "meta.json").write_text("[1, 2]")
    shutil.copytree(results / "published", results / "bad_figures")
    manifest = json.loads((results / "bad_figures" / "report.json").read_text())
    (results / "bad_figures" / "fake.png").write_text("not a png")
    manifest["figures"] = [{"caption": "escapes", "file": "../magnification/magnification.png"},
                           {"caption": "fake", "file": "fake.png"}]
    (results / "bad_figures" / "report.json").write_text(json.dumps(manifest))
    (results / "paper").mkdir()  # an earlier build under --out: not a study
    (results / "paper" / "report.md").write_text("old")
    paper = root / "paper"
    (paper / "tables").mkdir(parents=True)
    (paper / "tables" / "table-99.tex").write_text("an earlier build")    # listed in that build's manifest
    (paper / ".report-build.json").write_text(json.dumps({"files": ["tables/table-99.tex", "../outside.txt"]}))
    (paper / "tables" / "measurements.csv").write_text("a user's file")   # not listed: never deleted
    (paper / "figures").mkdir()
    (paper / "figures" / "photo.png").write_bytes(b"\x89PNG\r\n\x1a\n a user's photo")
    (root / "outside.txt").write_text("named by a forged manifest")
    (results / "leftover").mkdir()
    return build(results, paper, log=lambda *a: None)


@pytest.mark.slow  # built (above)
def test_broken_studies_shown_with_reason_rest_built(built):
    md = (built / "report.md").read_text()
    assert "(`list_meta`)" in md and "**Broken**: meta.json is not a JSON object" in md
    section = md.split("(`bad_figures`)")[1].split("### ")[0]
    assert "**Broken figure**: figure '../magnification/magnification.png' lies outside the study folder" in section
    assert "**Broken figure**: figure 'fake.png' is not a PNG" in section and "*Table " in section
    assert "(`paper`)" not in md and "(`leftover`)" not in md  # folders that are not studies
    assert not (built / "tables" / "table-99.tex").exists()  # never mix builds: the previous build's files go
    assert (built / "tables" / "measurements.csv").read_text() == "a user's file"  # what it did not write stays
    assert (built / "figures" / "photo.png").exists() and (built.parent / "outside.txt").exists()
    # one number per table; a table too wide for the page is split into parts table-N-1.tex, table-N-2.tex ...
    numbers = {re.match(r"table-(\d+)", p.stem).group(1) for p in built.glob("tables/*.tex")}
    assert len(list(built.glob("tables/*.csv"))) == len(list(built.glob("tables/table-*.csv"))) + 1
    assert len(numbers) == len(list(built.glob("tables/table-*.csv"))) == md.count("*Table ")


@pytest.mark.slow  # built (above)
def test_sections_tables_figures(built):
    md = (built / "report.md").read_text()
    assert md.startswith("# fitbench: comparison report")
    abstract = md.split("**Abstract.** ")[1].split("\n")[0]      # generated from the studies' findings
    manifest = json.loads((built.parent / "results" / "published" / "report.json").read_text())
    first = re.split(r"(?<=[.;])\s", manifest["findings"], maxsplit=1)[0].rstrip(".;")
    assert first.split()[0] in abstract and "studies (" in abstract
    for section in ("Roundness paper", "Circle/ellipse paper", "Magnification paper"):  # the studies present
        assert f"## {section}" in md
    assert "*Table 1:" in md and "| roundness_set2 | MIC | 1.7287 |" in re.sub(r" +", " ", md)
    for name in ("published", "magnification", "ellipse_angle"):  # a table and a figure per study
        section = md.split(f"(`{name}`)")[1].split("### ")[0]
        assert "*Table " in section and "![" in section, name
    pngs = sorted(built.glob("figures/figure-*.png"))
    assert pngs and all(png.stat().st_size > 10_000 for png in pngs)
    # the LaTeX report includes the vector PDF each study saved beside its PNG (never a PDF wrapping a picture)
    tex = (built / "report.tex").read_text(encoding="utf-8")
    included = re.findall(r"\\includegraphics\[[^]]*\]\{(figures/[^}]+)\}", tex)
    assert sorted(included) == sorted(f"figures/{p.with_suffix('.pdf').name if p.with_suffix('.pdf').exists() else p.name}"
                                      for p in pngs)
    vector = [p for p in built.glob("figures/figure-*.pdf") if b"/Subtype /Image" not in p.read_bytes()]
    assert len(vector) >= 3 and len(vector) == len(list(built.glob("figures/*.pdf"))), sorted(built.glob("figures/*"))


@pytest.mark.slow  # built (above)
def test_failed_studies_are_shown_and_a_results_folder_holds_its_own_studies(built):
    """A report of a results folder of one's own (--out DIR) holds the studies in it: no default study it lacks
    is listed as missing (it listed 10 "**Missing**: no results in DIR/published ..." sections)."""
    md = (built / "report.md").read_text()
    assert "(`broken_study`)" in md and "**failed rows: 2 of" in md
    assert "**Missing**" not in md and "(`noise`)" not in md and "(`multilateration`)" not in md


@pytest.mark.slow  # built (above)
def test_the_default_results_folder_shows_the_default_studies_it_lacks(built, tmp_path, monkeypatch):
    """results/ (of the current folder) is what a run of the default studies fills: a default study it lacks is
    missing, with the command that fills it (the same grid: --quick, and this folder as --out, since results/
    is not the quick grid's default folder)."""
    results = tmp_path / "results"
    shutil.copytree(built.parent / "results" / "magnification", results / "magnification")
    monkeypatch.chdir(tmp_path)
    md = (build(results, tmp_path / "paper", log=lambda *a: None) / "report.md").read_text()
    assert "**Missing**: no results" in md and "python -m experiments.run multilateration" in md
    # the folder as the command, run here, names it (no folder of this machine in a shared report)
    assert "python -m experiments.run noise --quick --out results" in md.replace("\\", "") and str(tmp_path) not in md


@pytest.mark.slow  # built (above)
def test_latex_fragments(built, tmp_path):
    tex = sorted(built.glob("tables/*.tex"))
    assert tex and all(r"\toprule" in t.read_text() and r"\bottomrule" in t.read_text() for t in tex)
    latex = shutil.which("pdflatex")
    if latex is None:
        pytest.skip("no LaTeX toolchain (pdflatex) on this machine: the fragments' compilation is not checked")
    from experiments.render.latex import compile_pdf, standalone_document
    result = compile_pdf(standalone_document([t.read_text() for t in tex]), tmp_path)  # the preamble of report.tex
    assert result["ok"], result["errors"] or result["log"][-2000:]
    assert not [o for o in result["overfull"] if o[1] > 1.0], result["overfull"][:5]


CHROMIUM_FLAGS = ["--headless", "--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run",
                  "--disable-background-networking", "--disable-component-update", "--disable-sync"]


@pytest.mark.slow  # built (above)
def test_html_renders_in_headless_chromium(built, tmp_path):
    chromium = shutil.which("chromium") or shutil.which("chromium-browser")
    if chromium is None:
        pytest.skip("Debian's chromium is not installed (.ci/run installs it: apt-get install chromium)")
    url = (built / "report.html").as_uri()
    dom = subprocess.run([chromium, *CHROMIUM_FLAGS, f"--user-data-dir={tmp_path / 'profile'}",
                          "--virtual-time-budget=5000", "--dump-dom", url], capture_output=True, text=True, timeout=120)
    assert dom.returncode == 0, dom.stderr[-2000:]
    m = re.search(r'data-images="(\d+)/(\d+)"', dom.stdout)
    assert m, "the page's load handler did not run"
    loaded, total = map(int, m.groups())
    assert total >= 3 and loaded == total
    shot = tmp_path / "shot.png"
    subprocess.run([chromium, *CHROMIUM_FLAGS, f"--user-data-dir={tmp_path / 'profile2'}", "--window-size=1200,2400",
                    f"--screenshot={shot}", url], capture_output=True, text=True, timeout=120)
    import matplotlib.image as mpimg
    img = mpimg.imread(shot)
    assert img.std() > 0.05  # not blank


def test_report_module_names_no_study():
    """The report renders what studies declare: its code contains no study's name."""
    from conftest import REPO
    source = (REPO / "experiments" / "report.py").read_text(encoding="utf-8")
    names = [p.stem for p in (REPO / "experiments" / "configs").glob("*.toml")]
    assert names
    import re
    # a name with an underscore (nist_circle) is never prose: any occurrence counts; a plain English word
    # ("published", "noise") counts when it is used as a string, a key or an identifier
    found = [n for n in names if ("_" in n and re.search(rf"\b{re.escape(n)}\b", source))
             or re.search(rf"['\"`]{re.escape(n)}['\"`]|\b{re.escape(n)}\s*[=(.\[]", source)]
    assert not found, f"experiments/report.py names the studies {found}"


def test_the_report_writes_files_only_through_the_one_atomic_writer():
    """experiments/report.py and experiments/render/ write every file with methods.files (write_atomic, or a
    figure with fitbench.plots.save_atomic, which uses methods.files.atomic_path): no direct write_text,
    write_bytes, savefig, shutil copy or open() for writing."""
    import ast
    from conftest import REPO
    import methods.files
    from experiments import report
    assert report.write_atomic is methods.files.write_atomic
    direct = {"write_text", "write_bytes", "savefig"}
    found = []
    for path in [REPO / "experiments" / "report.py", *sorted((REPO / "experiments" / "render").glob("*.py"))]:
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
            if not isinstance(node, ast.Call):
                continue
            name = node.func.attr if isinstance(node.func, ast.Attribute) else getattr(node.func, "id", "")
            mode = [a.value for a in node.args[1:2] + [k.value for k in node.keywords if k.arg == "mode"]
                    if isinstance(a, ast.Constant)]
            shutil = isinstance(node.func, ast.Attribute) and getattr(node.func.value, "id", "") == "shutil"
            if name in direct or shutil or (name == "open" and any(set(str(m)) & set("wax+") for m in mode)):
                found.append(f"{path.name}:{node.lineno} {name}")
    assert not found, found


@pytest.mark.slow  # built (above)
def test_quick_run_is_marked_in_the_pdf_source(built):
    """The studies of ``built`` ran --quick: the TeX says so in its title, beside the abstract and per study,
    as the HTML and Markdown do."""
    tex = (built / "report.tex").read_text(encoding="utf-8")
    head = tex.split(r"\tableofcontents")[0]
    assert r"\title{fitbench: comparison report (quick run, reduced grid)}" in head
    assert "reduced --quick grid; their numbers are not the published comparison" in head.replace(r"-{}-", "--")
    published = tex.split(r"\subsection{")[1:]
    assert any("Quick run (reduced grid)" in s for s in published)


@pytest.mark.slow
@pytest.mark.skipif(shutil.which("pdflatex") is None, reason="pdflatex is not installed (apt-get install "
                    "texlive-latex-extra texlive-science)")
def test_docs_say_how_to_get_the_pdf_and_the_command_works(built):
    """docs/report.md gives the command that compiles report.tex to report.pdf; run in the built folder, it
    makes the PDF with settled page numbers."""
    from pathlib import Path
    docs = (Path(__file__).resolve().parents[1] / "docs" / "report.md").read_text(encoding="utf-8")
    command = next(line for line in docs.splitlines() if line.startswith("cd paper && pdflatex"))
    assert "report.tex" in command and "-no-shell-escape" in command
    (built / "report.pdf").unlink(missing_ok=True)
    done = subprocess.run(command.replace("cd paper && ", "", 1), shell=True, cwd=built, capture_output=True,
                          text=True, timeout=600, stdin=subprocess.DEVNULL)
    assert done.returncode == 0, done.stdout[-2000:]
    assert (built / "report.pdf").stat().st_size > 10_000
    # the page numbers have settled (two passes left "Label(s) may have changed": a contents with wrong pages)
    log = (built / "report.log").read_text(encoding="latin-1")
    assert not re.search(r"Rerun to get|Label\(s\) may have changed", log), log[-2000:]


def test_the_committed_paper_shows_every_study_from_its_last_run():
    """paper/ is built after one run of every study it shows: no section carries the 'older results' mark
    (running one study alone after the default run marks all the others as older)."""
    paper = Path(__file__).resolve().parents[1] / "paper"
    for name in ("report.md", "report.tex", "report.html"):
        text = (paper / name).read_text(encoding="utf-8")
        assert "older than the last run" not in text, f"paper/{name}: rebuild it from one run of every study"


def test_every_row_the_tables_leave_out_is_counted_by_status_and_method(tmp_path):
    """Rows that are not results (timeout, crashed, unavailable, as error and invalid, and any other status) are
    counted per status and method in the report's text and in the PDF's notes: the report of a study with 3 ok,
    3 timeout and 3 crashed rows said only "9 rows" and showed a table of the one method that ran."""
    import hashlib

    import pandas as pd
    cfg = tmp_path / "leftout.toml"
    cfg.write_text('name = "leftout"\ntitle = "rows left out"\nseed = 3\nrepetitions = 3\n[[datasets]]\n'
                   'source = "circle"\nparams = { radius = 5.0, noise = 0.01, n = 12 }\n'
                   '[[methods]]\nid = "circle.kasa"\n[[methods]]\nid = "circle.gauss_newton"\n[[methods]]\n'
                   'id = "circle.taubin"\n', encoding="utf-8")
    results = tmp_path / "results"
    folder = run_study(str(cfg), results, jobs=1, log=lambda *a: None)
    df = pd.read_csv(folder / "results.csv", dtype=str, keep_default_na=False)
    statuses = {"circle.gauss_newton": ["timeout"] * 3, "circle.taubin": ["crashed", "crashed", "my status"]}
    for method, new in statuses.items():   # as a run whose rows timed out and whose workers died would leave them
        df.loc[df["method"] == method, "status"] = new
    df.to_csv(folder / "results.csv", index=False)
    meta = json.loads((folder / "meta.json").read_text(encoding="utf-8"))
    meta["status_counts"] = df["status"].value_counts().to_dict()
    meta["results_sha256"] = hashlib.sha256((folder / "results.csv").read_bytes()).hexdigest()
    (folder / "meta.json").write_text(json.dumps(meta), encoding="utf-8")
    paper = build(results, tmp_path / "paper", log=lambda *a: None)
    md = (paper / "report.md").read_text(encoding="utf-8")
    lines = {line.split("**")[1]: line for line in md.splitlines() if line.startswith("**") and " of 9**" in line}
    assert set(lines) == {"timed-out rows: 3 of 9", "crashed rows: 2 of 9", "rows with status 'my status': 1 of 9"}, lines
    assert lines["timed-out rows: 3 of 9"].endswith("by method: circle.gauss_newton 3.")
    assert lines["crashed rows: 2 of 9"].endswith("by method: circle.taubin 2.")
    assert lines["rows with status 'my status': 1 of 9"].endswith("by method: circle.taubin 1.")
    tex = (paper / "report.tex").read_text(encoding="utf-8")
    assert "timed-out rows: 3 of 9" in tex and "crashed rows: 2 of 9" in tex and "circle.taubin 2" in tex
    # the default table holds the ok rows: its caption counts those (it said "over 9 rows" of a table of 3)
    from experiments.analysis import default_declarations
    table, _ = default_declarations({"name": "leftout"}, pd.read_csv(folder / "results.csv"))
    assert "over the 3 ok rows of 9 of leftout" in table["caption"], table["caption"]


def test_the_report_goes_where_experiments_run_puts_it(tmp_path, monkeypatch):
    """One rule for both commands (experiments.report.default_out): paper/ for results/ of the current folder, else
    RESULTS/paper. `experiments.report --results DIR` wrote DIR/../paper (a shared parent: two results folders
    overwrote one report), while `experiments.run --out DIR` writes DIR/paper; results/quick gave results/paper."""
    from experiments import report
    from experiments.run import main as run_main
    monkeypatch.chdir(tmp_path)
    for folder in ("mine", "results", "results/quick"):   # each holds a study (an unfinished one: shown as such)
        (tmp_path / folder / "unfinished").mkdir(parents=True, exist_ok=True)
        (tmp_path / folder / "unfinished" / "rows.sqlite").write_bytes(b"")
    assert report.main(["--results", "mine"]) == 0
    assert (tmp_path / "mine" / "paper" / "report.md").is_file() and not (tmp_path / "paper").exists()
    assert report.main(["--results", str(tmp_path / "results" / "quick")]) == 0
    assert (tmp_path / "results" / "quick" / "paper" / "report.md").is_file()
    assert not (tmp_path / "results" / "paper").exists() and not (tmp_path / "paper").exists()
    assert report.main([]) == 0 and (tmp_path / "paper" / "report.md").is_file()   # results/ -> paper/
    assert report.default_out(tmp_path / "results") == Path("paper")            # however results/ is named
    # experiments.run --out DIR builds the same place
    cfg = tmp_path / "rstudy.toml"
    cfg.write_text('name = "rstudy"\ntitle = "where the report goes"\nseed = 1\nrepetitions = 1\n[[datasets]]\n'
                   'source = "circle"\nparams = { radius = 5.0, noise = 0.01, n = 12 }\n[[methods]]\nid = "circle.kasa"\n',
                   encoding="utf-8")
    assert run_main([str(cfg), "--jobs", "1", "--out", "other"]) == 0
    assert (tmp_path / "other" / "paper" / "report.md").is_file()
    assert report.default_out(Path("other")) == Path("other") / "paper"
