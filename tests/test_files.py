from __future__ import annotations

import os
from pathlib import Path

import pytest

from curiosity_cli.errors import ConfigError
from curiosity_cli.files import atomic_path
from curiosity_cli.yamlfile import read_yaml


def test_atomic_path_replaces_only_on_success(tmp_path):
    target = tmp_path / "out" / "result.txt"
    with atomic_path(target) as tmp:
        tmp.write_text("first")
    assert target.read_text() == "first"
    with pytest.raises(RuntimeError):
        with atomic_path(target) as tmp:
            tmp.write_text("half")
            raise RuntimeError("killed")
    assert target.read_text() == "first"
    assert os.listdir(target.parent) == ["result.txt"]


def test_a_folder_where_the_result_belongs_is_named_not_the_temporary_file(tmp_path):
    (tmp_path / "mi.csv").mkdir()
    with pytest.raises(OSError) as info:
        with atomic_path(tmp_path / "mi.csv") as tmp:
            tmp.write_text("rows")
    assert info.value.filename == str(tmp_path / "mi.csv")
    assert sorted(os.listdir(tmp_path)) == ["mi.csv"], "the temporary file is gone"


def test_a_read_only_folder_is_named_by_the_file_being_written_not_the_temporary_one(tmp_path, monkeypatch):
    import tempfile

    from typer.testing import CliRunner

    from curiosity_cli.cli import app

    def refused(dir, prefix, suffix):  # what a read-only folder does to mkstemp, even for root's files elsewhere
        raise PermissionError(13, "Permission denied", os.path.join(dir, f"{prefix}0gfy9i8s{suffix}"))

    monkeypatch.setattr(tempfile, "mkstemp", refused)
    with pytest.raises(OSError) as info:
        with atomic_path(tmp_path / "foo.yaml"):
            pass
    assert info.value.filename == str(tmp_path / "foo.yaml")
    monkeypatch.chdir(tmp_path)
    result = CliRunner().invoke(app, ["config", "init", "mine"])
    assert result.exit_code == 1 and result.stderr.strip() == "Error: mine.yaml: Permission denied"
    monkeypatch.undo()
    with pytest.raises(OSError) as info:  # the temporary file refused inside the block is named as the result too
        with atomic_path(tmp_path / "bar.csv") as tmp:
            raise PermissionError(13, "Permission denied", str(tmp))
    assert info.value.filename == str(tmp_path / "bar.csv")


def test_atomic_path_gives_ordinary_permissions(tmp_path):
    umask = os.umask(0o022)
    try:
        with atomic_path(tmp_path / "r.txt") as tmp:
            tmp.write_text("x")
    finally:
        os.umask(umask)
    assert (tmp_path / "r.txt").stat().st_mode & 0o777 == 0o644


def test_read_yaml_refuses_a_binary_file(tmp_path):
    path = tmp_path / "x.yaml"
    path.write_bytes(b"\xff\xfe\x00")
    with pytest.raises(ConfigError, match="x.yaml: not a text file; expected YAML"):
        read_yaml(path, "config file")


def test_the_leftovers_of_killed_atomic_writers_are_removed_and_nothing_else(tmp_path):
    from curiosity_cli.files import atomic_path, remove_leftovers

    result = tmp_path / "a" / "result.npz"
    with pytest.raises(RuntimeError):
        with atomic_path(result) as tmp:
            tmp.write_bytes(b"half")
            leftover = tmp_path / "a" / "b" / tmp.name  # as a killed writer would leave it
            leftover.parent.mkdir()
            leftover.write_bytes(b"half")
            raise RuntimeError
    (tmp_path / "a" / "kept.npz").write_bytes(b"whole")
    (tmp_path / "a" / ".hidden").write_bytes(b"not ours")
    assert remove_leftovers(tmp_path) == 1
    assert sorted(p.name for p in tmp_path.rglob("*") if p.is_file()) == [".hidden", "kept.npz"]


def test_a_folder_behind_a_symbolic_link_that_leads_nowhere_names_the_link():
    """Issue 64: a labels/ symlink loop was reported as "File exists"."""
    import tempfile

    from curiosity_cli.files import os_error_message

    with tempfile.TemporaryDirectory() as top:
        loop = Path(top) / "labels"
        loop.symlink_to(loop)
        with pytest.raises(OSError) as info:
            (loop / "own" / "random-walk").mkdir(parents=True, exist_ok=True)
        assert os_error_message(info.value) == (
            f"{loop}: a symbolic link that leads nowhere (a loop, or its target is missing); expected a folder"
        )
