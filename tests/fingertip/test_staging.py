"""fingertip.staging: the shared output-folder check and atomic output."""
import os

import pytest

from fingertip.errors import InputError
from fingertip.staging import check_output_dir, staged_output


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
