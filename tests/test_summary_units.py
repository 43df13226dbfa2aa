"""Every number of a study's summary.md carries its unit: the headers take the units the result classes declare
(form error, centre and radius errors in the data's unit, angles in rad, timings in s), a study on unit circles
its declared 'R'; counts and shares carry none."""
from __future__ import annotations

import re

import numpy as np
import pandas as pd

from experiments.run import run_study
from experiments.summary import summary_units, to_markdown
from test_verify import STUDY as VERIFY_STUDY

STUDY = VERIFY_STUDY.replace('name = "vstudy"', 'name = "ustudy"').replace("verify test study", "units test study")

UNITLESS = {"runs", "ok share", "iterations median", "n", "dataset", "method", "params"}


def _header(md: str) -> list[str]:
    line = next(x for x in md.splitlines() if x.startswith("|"))
    return [c.strip() for c in line.strip("|").split("|")]


def test_summary_md_headers_carry_the_declared_units(tmp_path):
    """Lengths of a generator's data are in the data's own units unless the study names them (length_unit), as in
    its default table and figure; declared, they carry that unit."""
    cfg = tmp_path / "ustudy.toml"
    cfg.write_text(STUDY, encoding="utf-8")
    run_study(str(cfg), tmp_path / "out", quick=False, jobs=1, log=lambda *a: None)
    head = _header((tmp_path / "out" / "ustudy" / "summary.md").read_text(encoding="utf-8"))
    assert "form error median [data units]" in head and "center rmse [data units]" in head
    assert "radius bias [data units]" in head and "radius [data units]" in head
    cfg.write_text(STUDY.replace('kind = "grid"', 'kind = "grid"\nlength_unit = "mm"'), encoding="utf-8")
    run_study(str(cfg), tmp_path / "out", quick=False, jobs=1, log=lambda *a: None)
    head = _header((tmp_path / "out" / "ustudy" / "summary.md").read_text(encoding="utf-8"))
    assert "form error median [mm]" in head and "center rmse [mm]" in head and "radius bias [mm]" in head
    assert "time median [s]" in head or not any(h.startswith("time") for h in head)
    numbers = pd.read_csv(tmp_path / "out" / "ustudy" / "summary.csv")   # machine-readable names stay
    assert "form_error_median" in numbers.columns
    for h, col in zip(head, numbers.columns):
        if pd.api.types.is_numeric_dtype(numbers[col]) and h not in UNITLESS:
            assert re.search(r"\[[^]]+\]$", h), f"{col}: {h!r} has no unit"


def test_a_unit_circle_study_shows_its_lengths_relative_to_the_radius():
    """The noise study declares its rankings in R (unit circles): its summary's lengths are in R too, angles
    and timings keep theirs."""
    summary = pd.DataFrame({"data_noise": [0.01], "method": ["circle.kasa"], "runs": [4], "ok_share": [1.0],
                            "form_error_median": [0.03], "center_rmse": [0.002], "angle_bias": [0.1],
                            "time_median_s": [1e-5], "iterations_median": [np.nan]})
    cfg = {"rankings": [{"profile": "p", "metric": "center_error", "unit": "R"},
                        {"profile": "t", "metric": "time_median_s", "unit": "s"}]}
    head = _header(to_markdown(summary, units=summary_units(summary, cfg)))
    assert head == ["noise [R]", "method", "runs", "ok share", "form error median [R]", "center rmse [R]",
                    "angle bias [rad]", "time median [s]", "iterations median"]
    plain = _header(to_markdown(summary))
    assert "form error median [mm]" in plain and "noise [mm]" in plain


def test_a_study_declares_the_unit_of_its_lengths():
    """The convergence study's data are unit circles (no rankings to carry a unit): length_unit = "R" says so, and
    its summary no longer labels radii as mm."""
    from experiments import config as configs
    cfg = configs.load("convergence")
    assert cfg["length_unit"] == "R"
    summary = pd.DataFrame({"method": ["circle.kasa"], "runs": [4], "center_rmse": [0.002]})
    assert _header(to_markdown(summary, units=summary_units(summary, cfg))) == ["method", "runs", "center rmse [R]"]


def test_a_share_below_one_never_reads_one_nor_one_above_zero_zero():
    """summary.md showed 'ok share 1' for a group with 1 crashed row of 25,000 (summary.csv: 0.99996): a share
    prints with the digits it takes to stay below 1 (above 0); exact shares and other numbers are as before."""
    shares = [24999 / 25000, 149999 / 150000, 1 / 150000, 1.0, 0.0, 0.5, 2 / 3, np.nan]
    summary = pd.DataFrame({"method": [f"m{i}" for i in range(len(shares))], "runs": [25000] * len(shares),
                            "ok_share": shares, "form_error_median": [0.123456] * len(shares)})
    md = to_markdown(summary, units={"runs": "", "ok_share": "", "form_error_median": "mm"})
    head = _header(md)
    rows = [[c.strip() for c in line.strip("|").split("|")] for line in md.splitlines()[2:] if line.startswith("|")]
    shown = [r[head.index("ok share")] for r in rows]
    for value, text in zip(shares, shown):
        if value != value:
            assert text == ""
            continue
        assert (float(text) == 1.0) == (value == 1.0) and (float(text) == 0.0) == (value == 0.0), (value, text)
        assert abs(float(text) - value) <= 5e-4 * max(value, 1e-300), (value, text)
    assert shown[:4] == ["0.99996", "0.99999", "6.667e-06", "1"] and shown[6] == "0.6667"
    assert {r[head.index("form error median [mm]")] for r in rows} == {"0.1235"}
