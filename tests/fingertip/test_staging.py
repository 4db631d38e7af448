"""fingertip.staging: the shared output-folder check and atomic output."""
import os
import subprocess
import sys

import pytest

from fingertip.errors import InputError
from fingertip.staging import check_output_dir, claimed, staged_output


def test_existing_and_new_folders_pass_and_nothing_is_left(tmp_path):
    assert check_output_dir(tmp_path) == tmp_path
    new = tmp_path / "a" / "b"
    assert check_output_dir(new) == new
    assert not new.exists()
    assert list(tmp_path.iterdir()) == []          # the probe folder is removed again


def test_existing_file_is_refused(tmp_path):
    f = tmp_path / "f.txt"
    f.write_text("x")
    with pytest.raises(InputError, match="existing file") as e:
        check_output_dir(f)
    assert "\n" not in str(e.value)
    with pytest.raises(InputError, match="is a file"):
        check_output_dir(f / "sub")


def test_uncreatable_folder_is_refused():
    with pytest.raises(InputError, match="--out /proc/x cannot be created"):
        check_output_dir("/proc/x")


@pytest.mark.skipif(os.geteuid() == 0, reason="root may write anywhere")
def test_read_only_parent_is_refused(tmp_path):
    ro = tmp_path / "ro"
    ro.mkdir()
    ro.chmod(0o555)
    try:
        with pytest.raises(InputError, match="not writable"):
            check_output_dir(ro / "out", option="--run")
    finally:
        ro.chmod(0o755)


def test_staged_output_leaves_nothing_on_failure(tmp_path):
    out = tmp_path / "out"
    with pytest.raises(RuntimeError):
        with staged_output(out) as tmp:
            (tmp / "a.txt").write_text("x")
            raise RuntimeError("boom")
    assert list(tmp_path.iterdir()) == []
    with staged_output(out) as tmp:
        (tmp / "a.txt").write_text("x")
    assert (out / "a.txt").read_text() == "x"


def test_empty_path_is_refused(tmp_path, monkeypatch):
    """`--out ""` would write into the current folder (Path("") is "."): refused."""
    monkeypatch.chdir(tmp_path)
    for empty in ("", "  "):
        with pytest.raises(InputError, match="--out is empty"):
            check_output_dir(empty)
    assert list(tmp_path.iterdir()) == []


def test_marker_refuses_a_folder_of_other_files(tmp_path):
    out = tmp_path / "run"
    out.mkdir()
    assert check_output_dir(out, marker="run.json", what="indent run") == out           # empty: fine
    (out / "notes.txt").write_text("mine")
    with pytest.raises(InputError, match="holds files that are not an earlier indent run"):
        check_output_dir(out, marker="run.json", what="indent run")
    (out / "run.json").write_text("{}")
    assert check_output_dir(out, marker="run.json", what="indent run") == out           # an earlier run


def test_replace_leaves_no_stale_file_and_keeps_the_mode(tmp_path):
    out = tmp_path / "run"
    with staged_output(out, replace=True) as tmp:
        for name in ("run.json", "C5_001.vtu", "C5_002.vtu"):
            (tmp / name).write_text("old")
        (tmp / "sub").mkdir()
    (tmp_path / "x").mkdir()
    assert out.stat().st_mode & 0o777 == (tmp_path / "x").stat().st_mode & 0o777        # the umask's, not 0700
    with staged_output(out, replace=True) as tmp:
        (tmp / "run.json").write_text("new")
        (tmp / "C5_001.vtu").write_text("new")
    assert sorted(p.name for p in out.iterdir()) == ["C5_001.vtu", "run.json"]
    assert (out / "run.json").read_text() == "new"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["run", "x"]                # no staging left
    with pytest.raises(RuntimeError):                                                   # a failure keeps it
        with staged_output(out, replace=True) as tmp:
            (tmp / "run.json").write_text("broken")
            raise RuntimeError("boom")
    assert (out / "run.json").read_text() == "new"


def test_merge_keeps_other_files(tmp_path):
    out = tmp_path / "model"
    out.mkdir()
    (out / "sections.json").write_text("{}")
    with staged_output(out) as tmp:
        (tmp / "mesh.vtu").write_text("x")
    assert sorted(p.name for p in out.iterdir()) == ["mesh.vtu", "sections.json"]


def test_lock_refuses_a_live_holder_and_takes_over_a_dead_one(tmp_path):
    out = tmp_path / "a" / "run"
    lock = tmp_path / "a" / ".run.lock"
    holder = subprocess.Popen([sys.executable, "-c", "import time; time.sleep(30)"])
    try:
        with claimed(out):
            assert lock.read_text().split() == [str(os.getpid())]
            with pytest.raises(InputError, match=f"in use by another command \\(pid {os.getpid()}\\)"):
                with claimed(out):
                    pass
        assert not lock.exists() and not (tmp_path / "a").exists()   # the lock and its parent are gone
        lock.parent.mkdir()
        lock.write_text(f"{holder.pid}\n")
        with pytest.raises(InputError, match=f"pid {holder.pid}") as e:
            with claimed(out):
                pass
        assert "\n" not in str(e.value) and str(lock) in str(e.value)
    finally:
        holder.kill()
        holder.wait()
    with claimed(out):                                              # its process is gone: taken over
        assert lock.read_text().split() == [str(os.getpid())]
    assert not lock.exists()


def test_lock_checks_the_folder_first(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    with pytest.raises(InputError, match="--out is empty"):
        with claimed(""):
            pass
    assert list(tmp_path.iterdir()) == [] and not (tmp_path.parent / f".{tmp_path.name}.lock").exists()
