# SPDX-License-Identifier: BSD-3-Clause
"""Result.save_animation and Result.save_plots in a directory that others can write (issue #29;
reproducer py_temp_symlink.py): the temporary beside the target has a name nobody can guess and
is created with O_EXCL and O_NOFOLLOW (tempfile.mkstemp), so a symbolic link planted where the
old name (.NAME.tmp-PID) was, or anywhere, is never followed; a target that exists and is not a
regular file (a symbolic link, a FIFO, a directory) is refused before anything is written; a
failed write leaves the old file and no temporary; the file gets the mode open() gives."""

import os
import stat

import matplotlib

matplotlib.use("Agg")

import pytest  # noqa: E402

import ukdyn  # noqa: E402
from ukdyn import plotting, viewer  # noqa: E402

PRECIOUS = b"precious data\n"


@pytest.fixture(scope="module")
def result():
    return ukdyn.load("pendulum").simulate(t_end=0.3)


def _plant(directory, names, victim):
    """Symbolic links to `victim` under each of `names` in `directory`."""
    victim.write_bytes(PRECIOUS)
    for name in names:
        os.symlink(victim, directory / name)


def _listing(directory):
    return sorted(os.listdir(directory))


def test_save_animation_follows_no_planted_link(result, tmp_path):
    shared, victim = tmp_path / "shared", tmp_path / "victim.txt"
    shared.mkdir()
    planted = [".page.html.tmp-%d" % os.getpid(), ".page.html.tmp"]
    _plant(shared, planted, victim)
    result.save_animation(shared / "page.html")
    assert victim.read_bytes() == PRECIOUS
    assert (shared / "page.html").read_bytes().startswith(b"<!DOCTYPE html>")
    assert _listing(shared) == sorted(planted + ["page.html"])  # no temporary left


def test_save_plots_follows_no_planted_link(result, tmp_path):
    shared, victim = tmp_path / "shared", tmp_path / "victim.txt"
    shared.mkdir()
    planted = [".%s.png.tmp-%d" % (stem, os.getpid()) for stem in result.figures()]
    _plant(shared, planted, victim)
    written = result.save_plots(shared)
    assert victim.read_bytes() == PRECIOUS
    assert len(written) >= 3
    for path in written:
        with open(path, "rb") as f:
            assert f.read(8) == b"\x89PNG\r\n\x1a\n"
    assert _listing(shared) == sorted(planted + [os.path.basename(p) for p in written])


def _fifo(path):
    os.mkfifo(path)


def _directory(path):
    os.mkdir(path)


def _link(path):
    (path.parent / "elsewhere.html").write_bytes(PRECIOUS)
    os.symlink(path.parent / "elsewhere.html", path)


@pytest.mark.parametrize("make", [_fifo, _directory, _link], ids=["fifo", "directory", "link"])
def test_a_target_that_is_not_a_regular_file_is_refused(result, tmp_path, make):
    target = tmp_path / "page.html"
    make(target)
    before = _listing(tmp_path)
    with pytest.raises(OSError, match="exists and is not a regular file") as caught:
        result.save_animation(target)
    assert caught.value.filename == str(target)
    assert _listing(tmp_path) == before
    if (tmp_path / "elsewhere.html").exists():
        assert (tmp_path / "elsewhere.html").read_bytes() == PRECIOUS


def test_a_failed_write_keeps_the_old_file_and_no_temporary(tmp_path):
    target = tmp_path / "coordinates.png"
    target.write_bytes(PRECIOUS)

    class Failing:
        def savefig(self, f, **kw):
            f.write(b"half a picture")
            raise RuntimeError("disk full")

    with pytest.raises(RuntimeError, match="disk full"):
        plotting.save(Failing(), str(target))
    assert target.read_bytes() == PRECIOUS
    assert _listing(tmp_path) == ["coordinates.png"]


@pytest.mark.parametrize("umask", [0o022, 0o077])
@pytest.mark.parametrize("module", [viewer, plotting], ids=["viewer", "plotting"])
def test_the_file_has_the_mode_open_would_give(tmp_path, umask, module):
    """(viewer.py and plotting.py each have write_replacing: each runs alone as a script.)"""
    old = os.umask(umask)
    try:
        module.write_replacing(tmp_path / "a.txt", lambda f: f.write(b"x"))
    finally:
        os.umask(old)
    assert stat.S_IMODE(os.stat(tmp_path / "a.txt").st_mode) == 0o666 & ~umask
