"""Output files that cannot be written: one clear message naming the path, never a traceback or
a half-written file. A path that cannot hold a file is bad input (exit 2); a full disk is not the
user's input (exit 1)."""

import errno
from pathlib import Path

import pytest
from click.testing import CliRunner

from pdm_design import io
from pdm_design.cli import main
from pdm_design.errors import OutputError

PAPER = str(Path(__file__).resolve().parents[1] / "problems" / "paper_manipulators.toml")


def simulate_with_plot(target):
    result = CliRunner().invoke(main, ["simulate", PAPER, "--stages", "2", "--plot", str(target)])
    return result.exit_code, result.stderr


def test_plot_under_a_file_is_bad_input_naming_the_path(tmp_path):
    blocker = tmp_path / "not_a_folder"
    blocker.write_text("")
    target = blocker / "run.png"
    code, err = simulate_with_plot(target)
    assert code == 2
    assert f"--plot: expected a file that can be written, found {target}" in err
    assert "is a file, not a folder" in err
    assert "Traceback" not in err and "internal error" not in err


def test_full_disk_exits_1_and_leaves_no_file(tmp_path, monkeypatch):
    def full(tmp, path):
        raise OSError(errno.ENOSPC, "No space left on device")

    monkeypatch.setattr(io, "_publish", full)
    target = tmp_path / "run.png"
    code, err = simulate_with_plot(target)
    assert code == 1
    assert f"cannot write {target}: No space left on device" in err
    assert list(tmp_path.iterdir()) == []  # neither the plot nor its temporary file


@pytest.mark.parametrize("data", ["text", b"bytes"])
def test_write_atomic_reports_the_path_and_keeps_the_old_file(tmp_path, monkeypatch, data):
    target = tmp_path / "table.csv"
    target.write_text("old")

    def full(tmp, path):
        raise OSError(errno.ENOSPC, "No space left on device")

    monkeypatch.setattr(io, "_publish", full)
    with pytest.raises(OutputError) as caught:
        io.write_atomic(target, data)
    assert not caught.value.bad_input
    assert target.read_text() == "old"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["table.csv"]


def test_a_set_of_files_is_written_whole_or_not_at_all(tmp_path):
    (tmp_path / "b.csv").mkdir()  # the second file's name is taken by a folder
    with pytest.raises(OutputError, match=r"cannot write .*b\.csv: Is a directory$"):
        io.write_all({tmp_path / "a.md": "a", tmp_path / "b.csv": "b"})
    assert sorted(p.name for p in tmp_path.iterdir()) == ["b.csv"]  # no a.md, no temporaries


def test_a_named_pipe_is_written_into_not_replaced(tmp_path):
    import os
    import stat
    import threading

    pipe = tmp_path / "report.xml"
    os.mkfifo(pipe)
    received = []
    reader = threading.Thread(target=lambda: received.append(pipe.read_text()))
    reader.start()
    io.write_atomic(pipe, "<ok/>")
    reader.join(timeout=10)
    assert received == ["<ok/>"]
    assert stat.S_ISFIFO(pipe.stat().st_mode)
