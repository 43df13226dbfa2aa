"""A row's message is bounded (its start kept, with how long it was): a method returning a solver's whole log as its
message made results.csv unreadable by Python's csv module (a field above 131,072 characters)."""
import csv

import numpy as np
import pytest

from experiments.rows import MESSAGE_CHARS, bounded_message, failed_row
from experiments.run import main as run_main
from methods.results import circle_result
from plugin_methods import registered


def _chatty(points):
    c = points.mean(axis=0)
    return circle_result(points, c, float(np.hypot(*(points - c).T).mean()), converged=True,
                         message="iteration ok\n" * 20000)


STUDY = ('name = "chatty"\ntitle = "a chatty method"\nseed = 1\nrepetitions = 2\n[[datasets]]\nsource = "circle"\n'
         'params = { radius = 5.0, noise = 0.01, n = 30 }\n[[methods]]\nid = "circle.test_chatty"\n')


@pytest.fixture
def chatty():
    """A plugin's method, registered from this module for one test only."""
    with registered({"circle.test_chatty": _chatty}, kind="closed form",
                    summary="a fit whose message is a huge log (test)", reference="a test"):
        yield


def test_results_csv_with_a_huge_message_reads_with_the_csv_module(tmp_path, chatty):
    cfg = tmp_path / "chatty.toml"
    cfg.write_text(STUDY, encoding="utf-8")
    assert run_main([str(cfg), "--jobs", "1", "--no-report", "--out", str(tmp_path / "out")]) == 0
    with open(tmp_path / "out" / "chatty" / "results.csv", newline="", encoding="utf-8") as fh:
        rows = list(csv.DictReader(fh))
    assert len(rows) == 2 and {r["status"] for r in rows} == {"ok"}
    for r in rows:
        assert r["message"].startswith("iteration ok\niteration ok\n")
        assert r["message"].endswith("[message cut: 260,000 characters in all]")
        assert len(r["message"]) < MESSAGE_CHARS + 100


def test_bounded_message_keeps_short_messages_and_other_values():
    assert bounded_message("converged") == "converged"
    assert bounded_message(None) is None
    long = "y" * (MESSAGE_CHARS + 1)
    assert bounded_message(long) == "y" * MESSAGE_CHARS + f" ... [message cut: {MESSAGE_CHARS + 1:,} characters in all]"
    task = {"dataset": {"label": "d"}, "params": {}, "study": "s", "repetition": 0, "seed": 1, "stream": [0, 0, 0],
            "method": "circle.kasa", "index": 3}
    assert failed_row(task, "error", long)["message"].endswith("characters in all]")
