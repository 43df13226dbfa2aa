"""The README's "Fit your own file" commands run as written from the repository root on the example files that
ship in docs/examples/ (a fresh clone has nothing else), and docs/examples/make_examples.py writes those files."""
import os
import re
import shlex
import shutil
import subprocess
import sys

import pytest

from conftest import REPO, subprocess_env

EXAMPLES = REPO / "docs" / "examples"


def _section() -> str:
    text = (REPO / "README.md").read_text(encoding="utf-8")
    return text.split("\n## Fit your own file\n", 1)[1].split("\n## ", 1)[0]


def _blocks(language: str) -> list[str]:
    return re.findall(rf"```{language}\n(.*?)```", _section(), flags=re.S)


def _commands() -> list[list[str]]:
    lines = [ln for block in _blocks("sh") for ln in block.splitlines() if ln.strip()]
    return [shlex.split(ln, comments=True) for ln in lines]


def _tracked(path: str) -> bool:
    """Whether git ships ``path`` (a file only on this disk is not on a user's clone)."""
    if not (REPO / ".git").exists() or shutil.which("git") is None:
        return (REPO / path).is_file()
    out = subprocess.run(["git", "-C", str(REPO), "ls-files", "--error-unmatch", path], capture_output=True)
    return out.returncode == 0


@pytest.fixture
def clone(tmp_path):
    """A working folder holding what a clone has under docs/examples/ (outputs the commands write land here)."""
    shutil.copytree(EXAMPLES, tmp_path / "docs" / "examples")
    return tmp_path


def test_the_section_has_commands_on_shipped_files():
    commands = _commands()
    assert len(commands) >= 5 and all(c[0] == "fitbench" for c in commands), commands
    inputs = [a for c in commands for a in c if a.startswith("docs/")]
    assert {"fit", "roundness", "circular-test", "positioning"} <= {c[1] for c in commands}
    assert inputs and all(_tracked(a) for a in inputs), inputs


@pytest.mark.parametrize("command", _commands(), ids=lambda c: " ".join(c[1:3]))
def test_each_command_runs_as_written(command, clone):
    out = subprocess.run([sys.executable, "-m", "fitbench", *command[1:]], cwd=clone, env=subprocess_env(),
                         capture_output=True, text=True, timeout=120)
    assert out.returncode == 0, (command, out.stdout[-2000:], out.stderr[-2000:])
    assert "Traceback" not in out.stderr and "error" not in out.stderr, out.stderr


def test_the_python_block_runs_as_written(clone, monkeypatch):
    (code,) = _blocks("python")
    monkeypatch.chdir(clone)
    namespace = {}
    exec(compile(code, "README.md", "exec"), namespace)
    res = namespace["res"]
    assert res.converged and abs(res.radius - 50.0) < 1e-3, (res.radius, res.message)


def _numbers_agree(a: str, b: str) -> bool:
    """Two written fields agree: the same text, or numbers within one unit of the last decimal written."""
    if a == b:
        return True
    try:
        x, y = float(a), float(b)
    except ValueError:
        return False
    decimals = len(a.split(".")[1]) if "." in a else 0
    return abs(x - y) <= 1.01 * 10.0 ** -decimals


def test_make_examples_writes_the_shipped_files(tmp_path):
    sys.path.insert(0, str(EXAMPLES))
    try:
        import make_examples
    finally:
        sys.path.remove(str(EXAMPLES))
    make_examples.main(tmp_path)
    written = sorted(p.name for p in tmp_path.iterdir())
    assert written == sorted(make_examples.files()), written
    for name in written:
        new = (tmp_path / name).read_text(encoding="utf-8").splitlines()
        shipped = (EXAMPLES / name).read_text(encoding="utf-8").splitlines()
        assert len(new) == len(shipped) and new[0] == shipped[0], name
        for line_new, line_shipped in zip(new[1:], shipped[1:]):
            fields_new, fields_shipped = re.split("[,;]", line_new), re.split("[,;]", line_shipped)
            assert len(fields_new) == len(fields_shipped), (name, line_new, line_shipped)
            assert all(map(_numbers_agree, fields_new, fields_shipped)), (name, line_new, line_shipped)
    assert os.path.getsize(EXAMPLES / "trace.csv") < 20_000
