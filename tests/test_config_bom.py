"""A study TOML saved by a Windows editor as "UTF-8 with BOM" (and CRLF line ends) is the same study; before, it
was refused as 'not valid TOML (Invalid statement (at line 1, column 1))'."""
from __future__ import annotations

import codecs

import experiments.config as configs

STUDY = '''name = "bomtest"
title = "a study saved with a byte-order mark"
seed = 7
repetitions = 3

[[datasets]]
generator = "circle"
params = { center = [0.0, 0.0], radius = 1.0, noise_model = "isotropic" }
grid = { arc_deg = [360.0, 90.0], noise = [0.01], n = [20] }

[[methods]]
id = "circle.kasa"
'''


def test_a_utf8_bom_and_crlf_config_is_the_same_study(tmp_path):
    plain = tmp_path / "plain" / "bomtest.toml"
    bom = tmp_path / "bom" / "bomtest.toml"
    plain.parent.mkdir()
    bom.parent.mkdir()
    plain.write_text(STUDY, encoding="utf-8")
    bom.write_bytes(codecs.BOM_UTF8 + STUDY.replace("\n", "\r\n").encode("utf-8"))
    a, b = configs.load(str(plain), quick=True), configs.load(str(bom), quick=True)
    assert b["name"] == "bomtest" and b["seed"] == 7 and [m["id"] for m in b["methods"]] == ["circle.kasa"]
    assert dict(b) == dict(a)
    assert configs.count_rows(b) == configs.count_rows(a) > 0
