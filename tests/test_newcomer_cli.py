"""What a newcomer tripped on at the command line: saved documents used with the wrong spec,
output paths found unwritable only after the work, init making folders, simulate --build solving
again, which tolerance the workshop builds to, limited_by in JSON, and the docs against --help.
"""

import json
from pathlib import Path

import pytest
from click.testing import CliRunner

from pdm_design.cli import main

ROOT = Path(__file__).resolve().parents[1]
PROBLEMS = ROOT / "problems"


def run(*args):
    result = CliRunner().invoke(main, [str(a) for a in args])
    return result.exit_code, result.stdout, result.stderr


# ------------------------------------------------------------ init --out makes no folders

def test_init_into_a_missing_folder_is_bad_input_and_creates_nothing(tmp_path):
    target = tmp_path / "no" / "such" / "dir" / "x.toml"
    code, out, err = run("init", "manipulators", "--out", target)
    assert code == 2 and out == ""
    assert err.startswith("error: command line: --out: expected a file in an existing folder")
    assert f"no folder {target.parent}" in err
    assert list(tmp_path.iterdir()) == []  # not even tmp_path/no


def test_init_into_an_existing_folder_writes_only_the_file(tmp_path):
    target = tmp_path / "x.toml"
    code, out, err = run("init", "stairs", "--out", target)
    assert code == 0 and err == ""
    assert [p.name for p in tmp_path.iterdir()] == ["x.toml"]
    assert "[scene]" in target.read_text()
