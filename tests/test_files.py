"""The one file helper (methods.files): atomic writes through symlinks, special files refused on write and on
read (without blocking), the umask's mode for new files; and the command line's one-line refusals."""
from __future__ import annotations

import contextlib
import os
import signal
import stat

import numpy as np
import pytest

import cli_calls
from methods.files import NotRegularFileError, atomic_path, open_regular, write_atomic

needs_fifo = pytest.mark.skipif(not hasattr(os, "mkfifo"), reason="no FIFOs on this platform")


@contextlib.contextmanager
def deadline(seconds=5):
    """Fail instead of hanging when a call blocks (a FIFO opened without O_NONBLOCK)."""
    def boom(*_):
        raise TimeoutError("blocked")
    old = signal.signal(signal.SIGALRM, boom)
    signal.alarm(seconds)
    try:
        yield
    finally:
        signal.alarm(0)
        signal.signal(signal.SIGALRM, old)


@contextlib.contextmanager
def umask(mask):
    old = os.umask(mask)
    try:
        yield
    finally:
        os.umask(old)


def cli(*args):
    """``fitbench ARGS`` in this process (:func:`cli_calls.cli`), failing rather than hanging on a FIFO."""
    with deadline(60):
        return cli_calls.cli(*args)


def test_write_through_a_symlink_keeps_the_link(tmp_path):
    target = tmp_path / "real.txt"
    target.write_text("old")
    link = tmp_path / "link.txt"
    link.symlink_to(target)
    write_atomic(link, "new")
    assert link.is_symlink() and os.readlink(link) == str(target)
    assert target.read_text() == "new"
    chain = tmp_path / "chain.txt"
    chain.symlink_to(link)
    with atomic_path(chain) as tmp:
        tmp.write_text("via chain")
    assert chain.is_symlink() and link.is_symlink() and target.read_text() == "via chain"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["chain.txt", "link.txt", "real.txt"]  # no temporary left


@needs_fifo
def test_special_targets_are_refused_and_left_alone(tmp_path):
    fifo = tmp_path / "pipe"
    os.mkfifo(fifo)
    link = tmp_path / "to-null"
    link.symlink_to(os.devnull)
    for path, kind in ((fifo, "FIFO"), (tmp_path, "folder"), (os.devnull, "character device"), (link, "character device")):
        with pytest.raises(NotRegularFileError, match=kind):
            write_atomic(path, "x")
    assert stat.S_ISFIFO(os.stat(fifo).st_mode) and stat.S_ISCHR(os.stat(os.devnull).st_mode) and link.is_symlink()
    assert sorted(p.name for p in tmp_path.iterdir()) == ["pipe", "to-null"]


@pytest.mark.parametrize("mask", [0o022, 0o002, 0o077])
def test_new_files_get_the_umask_mode_and_existing_files_keep_theirs(tmp_path, mask):
    with umask(mask):
        write_atomic(tmp_path / "new.txt", "x")
        with atomic_path(tmp_path / "fig.png") as tmp:
            tmp.write_bytes(b"png")
    for name in ("new.txt", "fig.png"):
        assert stat.S_IMODE(os.stat(tmp_path / name).st_mode) == 0o666 & ~mask
    old = tmp_path / "kept.txt"
    old.write_text("a")
    os.chmod(old, 0o640)
    write_atomic(old, "b")
    assert stat.S_IMODE(os.stat(old).st_mode) == 0o640 and old.read_text() == "b"


def test_a_failed_write_leaves_the_old_file_and_no_temporary(tmp_path):
    path = tmp_path / "a.txt"
    path.write_text("old")
    with pytest.raises(RuntimeError):
        with atomic_path(path) as tmp:
            tmp.write_text("half")
            raise RuntimeError("writer failed")
    assert path.read_text() == "old" and [p.name for p in tmp_path.iterdir()] == ["a.txt"]


@needs_fifo
def test_reading_a_fifo_or_a_device_does_not_block(tmp_path):
    fifo = tmp_path / "pipe"
    os.mkfifo(fifo)
    with deadline():
        for path in (fifo, "/dev/zero" if os.path.exists("/dev/zero") else os.devnull):
            with pytest.raises(NotRegularFileError, match="not a regular file"):
                open_regular(path)
    regular = tmp_path / "a.txt"
    regular.write_text("\ufeffx,y\n")
    with open_regular(regular) as fh:
        assert fh.read() == "x,y\n"


@needs_fifo
@pytest.mark.parametrize("command", [("fit", "circle.kasa"), ("roundness",), ("positioning",),
                                     ("circular-test", "--nominal-radius", "100"), ("magnify", "--eta", "10", "{ok}"),
                                     ("multilaterate",)])
def test_every_subcommand_refuses_a_fifo_and_dev_zero_in_one_line(tmp_path, command):
    fifo = tmp_path / "pipe"
    os.mkfifo(fifo)
    ok = tmp_path / "ok.csv"
    t = np.linspace(0, 2 * np.pi, 40, endpoint=False)
    ok.write_text("x,y\n" + "".join(f"{np.cos(a):.6f},{np.sin(a):.6f}\n" for a in t))
    sources = [fifo] + ([os.path.join(os.sep, "dev", "zero")] if os.path.exists("/dev/zero") else [])
    for src in sources:
        args = [a.format(ok=ok) for a in command]
        if command[0] == "circular-test":
            args = [command[0], src, *command[1:]]
        else:
            args = [*args, src]
        code, out, err = cli(*args)
        assert code == 2 and out == "", err
        assert err.count("\n") == 1 and "not a regular file" in err and "Traceback" not in err


@needs_fifo
def test_cli_outputs_onto_special_files_are_refused_and_through_links_written(tmp_path):
    t = np.linspace(0, 2 * np.pi, 60, endpoint=False)
    data = tmp_path / "c.csv"
    data.write_text("x,y\n" + "".join(f"{3 + 2 * np.cos(a):.6f},{2 * np.sin(a):.6f}\n" for a in t))
    fifo = tmp_path / "plot.png"
    os.mkfifo(fifo)
    code, _, err = cli("roundness", data, "--plot", fifo)
    assert code == 2 and err.count("\n") == 1 and "FIFO" in err and stat.S_ISFIFO(os.stat(fifo).st_mode)
    real = tmp_path / "real.png"
    real.write_bytes(b"")
    link = tmp_path / "link.png"
    link.symlink_to(real)
    code, _, err = cli("roundness", data, "--plot", link)
    assert code == 0, err
    assert link.is_symlink() and real.read_bytes().startswith(b"\x89PNG")


@needs_fifo
def test_compensation_tables_onto_a_fifo_a_device_or_through_a_symlink(tmp_path):
    from datasets.positioning import axis_test, to_frame
    data, _ = axis_test(rng=np.random.default_rng(2), mpe=0.002)
    csv = tmp_path / "axis.csv"
    to_frame(data, actual=False).to_csv(csv, index=False)
    fifo = tmp_path / "table.mpf"
    os.mkfifo(fifo)
    for target, kind in ((fifo, "FIFO"), (os.devnull, "character device")):
        code, _, err = cli("positioning", csv, "--deviation-unit", "mm", "--mpe", 0.002, "--axis", "X1", "--compensation", "siemens-eec", target)
        assert code == 2 and kind in err and err.count("\n") == 1, err
    assert stat.S_ISFIFO(os.stat(fifo).st_mode) and stat.S_ISCHR(os.stat(os.devnull).st_mode)
    real = tmp_path / "real.csv"
    real.write_text("old")
    link = tmp_path / "link.csv"
    link.symlink_to(real)
    with umask(0o022):
        code, _, err = cli("positioning", csv, "--deviation-unit", "mm", "--mpe", 0.002, "--compensation", "csv", link,
                           "--compensation", "fanuc-pitch", tmp_path / "new.txt")
    assert code == 0, err
    assert link.is_symlink() and "compensation" in real.read_text()
    assert stat.S_IMODE(os.stat(tmp_path / "new.txt").st_mode) == 0o644       # not 0600


def test_a_folder_as_plot_file_is_named_a_folder(tmp_path):
    data = tmp_path / "c.csv"
    t = np.linspace(0, 2 * np.pi, 30, endpoint=False)
    data.write_text("x,y\n" + "".join(f"{np.cos(a):.6f},{np.sin(a):.6f}\n" for a in t))
    for folder in (tmp_path / "pdir", tmp_path / "d.png"):
        folder.mkdir()
        code, _, err = cli("fit", "circle.kasa", data, "--plot", folder)
        assert code == 2 and err.count("\n") == 1 and "is a folder" in err, err
