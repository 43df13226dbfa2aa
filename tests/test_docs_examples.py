"""The how-to pages run as written: every command of their ``sh`` blocks that reads a shipped example
(docs/examples/) runs from a folder holding only those files, and the output a page pastes after it (the ``text``
block that follows, or ``$ command`` lines inside a ``text`` block) is what the command prints, number for number
(to one unit of the last digit shown; lines of ``...`` and the runtime are not compared). A ``fitbench`` command runs
in the test's process through its console script's entry point (tests/cli_calls.py; a child Python for each spent
~1 s of CPU importing the command again), a ``python`` command in a child Python. Marked slow: it runs with the whole
suite, not in the inner loop."""
import re
import shlex
import shutil
import subprocess
import sys

import pytest

from cli_calls import cli
from conftest import REPO, subprocess_env

PAGES = ("cli.md", "roundness.md", "circular-test.md", "positioning.md")
NUMBER = re.compile(r"[-+]?\d+(?:\.\d+)?(?:e[-+]?\d+)?")


def _examples(page: str) -> list[tuple[list[str], list[str]]]:
    """(commands, expected output lines) of each runnable example of a page."""
    text = (REPO / "docs" / page).read_text(encoding="utf-8")
    blocks = re.findall(r"```(\w*)\n(.*?)```", text, flags=re.S)
    found = []
    for i, (lang, body) in enumerate(blocks):
        if lang == "sh" and ("docs/examples/" in body or body.startswith("python -c")):
            commands = [c for c in body.replace("\\\n", " ").splitlines() if c.strip()]
            if not all(c.split()[0] in ("fitbench", "python") for c in commands):
                continue
            expected = blocks[i + 1][1].splitlines() if i + 1 < len(blocks) and blocks[i + 1][0] == "text" and \
                not blocks[i + 1][1].startswith("$ ") else []
            found.append((commands, expected))
        elif lang == "text" and body.startswith("$ "):
            for chunk in re.split(r"^\$ ", body, flags=re.M)[1:]:
                command, *expected = chunk.splitlines()
                found.append(([command], expected))
    return found


CASES = [(page, commands, expected) for page in PAGES for commands, expected in _examples(page)]


def _run(command: str, folder):
    """``command`` run in ``folder``: its exit status and its two streams (``returncode``, ``stdout``, ``stderr``)."""
    words = shlex.split(command, comments=True)
    if words[0] == "fitbench":
        return cli(*words[1:])  # the test has made ``folder`` its working directory
    return subprocess.run([sys.executable, *words[1:]], cwd=folder, env=subprocess_env(), capture_output=True,
                          text=True, timeout=300)


def _same(expected: str, got: str) -> bool:
    """One printed line equals another: the same text between the numbers, each number within one unit of the
    last digit shown."""
    parts_e, parts_g = NUMBER.split(expected.strip()), NUMBER.split(got.strip())
    nums_e, nums_g = NUMBER.findall(expected.strip()), NUMBER.findall(got.strip())
    if parts_e != parts_g or len(nums_e) != len(nums_g):
        return False
    for e, g in zip(nums_e, nums_g):
        mantissa = e.lower().split("e")[0]
        digits = len(mantissa.split(".")[1]) if "." in mantissa else 0
        scale = 10.0 ** int(e.lower().split("e")[1]) if "e" in e.lower() else 1.0
        if abs(float(e) - float(g)) > 1.01 * scale * 10.0 ** -digits:
            return False
    return True


def test_every_page_has_a_runnable_example():
    assert {page for page, _, _ in CASES} == set(PAGES)


@pytest.mark.slow  # 15 command runs
@pytest.mark.parametrize("page,commands,expected", CASES,
                         ids=[f"{p}:{' '.join(c[-1].split()[1:3])}" for p, c, _ in CASES])
def test_the_example_prints_what_the_page_says(page, commands, expected, tmp_path, monkeypatch):
    shutil.copytree(REPO / "docs" / "examples", tmp_path / "docs" / "examples")
    monkeypatch.chdir(tmp_path)
    refused = any(line.startswith("fitbench: error:") for line in expected)
    for command in commands:
        out = _run(command, tmp_path)
        assert out.returncode == (2 if refused and command == commands[-1] else 0), (command, out.stderr[-2000:])
        assert "Traceback" not in out.stderr, out.stderr
    printed = (out.stdout + out.stderr).splitlines()
    for line in expected:
        if line.strip() in ("", "...") or line.lstrip().startswith(("runtime", "...")):
            continue
        assert any(_same(line, got) for got in printed), (page, command, line, "\n".join(printed[:60]))
