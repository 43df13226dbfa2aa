"""The refusal of ``--out results`` for a study that is not one of the project's says what is true where it runs:
outside a fitbench checkout that folder holds no committed results, its name is reserved (the default --out of the
project's studies)."""
import pytest

from experiments import config as configs
from experiments.provenance import REPO
from experiments.run import output_folder
from methods import InvalidInputError

STUDY = ('name = "mine"\ntitle = "a personal study"\nseed = 1\nrepetitions = 1\n[[datasets]]\nsource = "circle"\n'
         'params = { radius = 5.0, noise = 0.01, n = 12 }\n[[methods]]\nid = "circle.kasa"\n')


@pytest.fixture
def mine(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    (tmp_path / "mine.toml").write_text(STUDY, encoding="utf-8")
    return configs.load(str(tmp_path / "mine.toml"))


@pytest.mark.parametrize("out", ["results", "results/quick"])
def test_outside_the_checkout_the_name_is_reserved_not_committed(mine, out):
    with pytest.raises(InvalidInputError) as info:
        output_folder(out, [mine], False)
    text = str(info.value)
    assert "committed" not in text and "reserved for the project's studies" in text and "mine.toml" in text, text


@pytest.mark.parametrize("sub", ["results", "results/quick"])
def test_the_checkout_s_results_folder_holds_the_committed_results(mine, sub):
    with pytest.raises(InvalidInputError, match="holds the project's committed results"):
        output_folder(str(REPO / sub), [mine], False)
