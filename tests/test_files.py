"""driver.core.files on real files: planted links are never followed, nothing is clobbered, modes are private."""
from __future__ import annotations

import os
import stat
import tempfile

import pytest

from driver.core import files
from driver.core.files import open_new, private_dir, runtime_dir, write_private

posix_only = pytest.mark.skipif(os.name != "posix", reason="modes, owners and symbolic links are POSIX")
as_root = pytest.mark.skipif(os.name != "posix" or os.geteuid() != 0, reason="needs root to make another user's file")
OTHER_UID = 65534                                     # nobody


def mode(path) -> int:
    return stat.S_IMODE(os.lstat(path).st_mode)


def victim(tmp_path, name="victim", content=b"precious\n"):
    """A file of ours that a planted link points at: it must come out of every test unchanged."""
    path = tmp_path / name
    path.write_bytes(content)
    os.chmod(path, 0o644)
    return path


# -- write_private -----------------------------------------------------------------------------------------

def test_write_private_writes_the_data_0600_and_leaves_nothing_else(tmp_path):
    path = tmp_path / "key"
    assert write_private(str(path), b"secret") == str(path)
    assert path.read_bytes() == b"secret"
    assert mode(path) == 0o600
    assert os.listdir(tmp_path) == ["key"]


@posix_only
def test_write_private_replaces_a_planted_link_instead_of_following_it(tmp_path):
    target = victim(tmp_path)
    link = tmp_path / "key"
    os.symlink(target, link)
    write_private(str(link), b"secret")
    assert not os.path.islink(link) and link.read_bytes() == b"secret" and mode(link) == 0o600
    assert target.read_bytes() == b"precious\n" and mode(target) == 0o644       # untouched


@posix_only
def test_write_private_through_a_dangling_link_creates_nothing_there(tmp_path):
    link = tmp_path / "key"
    os.symlink(tmp_path / "elsewhere", link)
    write_private(str(link), b"secret")
    assert not os.path.lexists(tmp_path / "elsewhere")
    assert link.read_bytes() == b"secret" and not os.path.islink(link)


@posix_only
def test_write_private_tightens_an_existing_file_and_replaces_its_content(tmp_path):
    path = victim(tmp_path, "key", b"old content that is longer")
    write_private(str(path), b"new")
    assert path.read_bytes() == b"new" and mode(path) == 0o600


def test_write_private_that_fails_leaves_the_old_file_and_no_temporary(tmp_path):
    path = tmp_path / "key"
    write_private(str(path), b"old")
    with pytest.raises(TypeError):
        write_private(str(path), "not bytes")
    assert path.read_bytes() == b"old" and os.listdir(tmp_path) == ["key"]


# -- open_new ----------------------------------------------------------------------------------------------

def test_open_new_creates_0600_by_default_or_the_mode_asked(tmp_path):
    with open_new(str(tmp_path / "a")) as f:
        f.write(b"a")
    with open_new(str(tmp_path / "b.txt"), "w", 0o644, encoding="ascii") as f:
        f.write("b")
    assert (tmp_path / "a").read_bytes() == b"a" and (tmp_path / "b.txt").read_text() == "b"
    if os.name == "posix":
        old = os.umask(0o022)
        os.umask(old)
        assert mode(tmp_path / "a") == 0o600 & ~old and mode(tmp_path / "b.txt") == 0o644 & ~old


def test_open_new_never_clobbers_an_existing_file(tmp_path):
    existing = victim(tmp_path, "rec.mp4")
    with pytest.raises(FileExistsError):
        open_new(str(existing))
    assert existing.read_bytes() == b"precious\n" and mode(existing) == 0o644


@posix_only
def test_open_new_never_follows_a_planted_link(tmp_path):
    target = victim(tmp_path)
    os.symlink(target, tmp_path / "rec.mp4")
    os.symlink(tmp_path / "nowhere", tmp_path / "snap.png")
    for name in ("rec.mp4", "snap.png"):
        with pytest.raises(FileExistsError):
            open_new(str(tmp_path / name))
    assert target.read_bytes() == b"precious\n"
    assert not os.path.lexists(tmp_path / "nowhere")


def test_open_new_only_writes(tmp_path):
    for bad in ("ab", "r+", "wb+", "a"):
        with pytest.raises(ValueError):
            open_new(str(tmp_path / "x"), bad)
    assert os.listdir(tmp_path) == []


# -- private_dir and runtime_dir ---------------------------------------------------------------------------

@posix_only
def test_private_dir_is_made_0700_and_ours(tmp_path):
    path = private_dir(str(tmp_path / "a" / "b"))
    st = os.lstat(path)
    assert stat.S_ISDIR(st.st_mode) and mode(path) == 0o700 and st.st_uid == os.geteuid()


@posix_only
def test_private_dir_of_ours_open_to_others_is_tightened(tmp_path):
    path = tmp_path / "d"
    path.mkdir()
    os.chmod(path, 0o777)
    assert private_dir(str(path)) == str(path) and mode(path) == 0o700


@posix_only
def test_private_dir_refuses_a_link_and_a_file(tmp_path):
    target = tmp_path / "real"
    target.mkdir()
    os.chmod(target, 0o755)
    os.symlink(target, tmp_path / "link")
    with pytest.raises(PermissionError):
        private_dir(str(tmp_path / "link"))
    assert mode(target) == 0o755                                       # not tightened through the link
    (tmp_path / "file").write_bytes(b"")
    with pytest.raises(OSError):
        private_dir(str(tmp_path / "file"))


@as_root
def test_private_dir_refuses_another_users_directory(tmp_path):
    theirs = tmp_path / "theirs"
    theirs.mkdir(mode=0o700)
    os.chown(theirs, OTHER_UID, OTHER_UID)
    with pytest.raises(PermissionError, match="another user"):
        private_dir(str(theirs))


@pytest.fixture
def env(tmp_path, monkeypatch):
    """A fresh environment for runtime_dir: its XDG directories and tempfile's under tmp_path."""
    monkeypatch.setattr(files, "_temp_dir", None)
    monkeypatch.setattr(tempfile, "tempdir", str(tmp_path / "tmp"))
    (tmp_path / "tmp").mkdir()
    run = tmp_path / "run"
    run.mkdir(mode=0o700)
    os.chmod(run, 0o700)
    monkeypatch.setenv("XDG_RUNTIME_DIR", str(run))
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path / "cache"))
    return tmp_path


def assert_private(path):
    st = os.lstat(path)
    assert stat.S_ISDIR(st.st_mode) and not stat.S_ISLNK(st.st_mode)
    if os.name == "posix":
        assert stat.S_IMODE(st.st_mode) == 0o700 and st.st_uid == os.geteuid()


@posix_only
def test_runtime_dir_is_in_the_sessions_runtime_directory(env):
    path = runtime_dir()
    assert path == str(env / "run" / "uavviewer")
    assert_private(path)
    assert runtime_dir() == path                                       # the same one each time


@posix_only
def test_runtime_dir_skips_a_runtime_directory_others_can_enter(env):
    os.chmod(env / "run", 0o755)
    path = runtime_dir()
    assert path == str(env / "cache" / "uavviewer")
    assert_private(path)


@posix_only
def test_runtime_dir_skips_a_planted_link(env):
    target = env / "attacker"
    target.mkdir()
    os.chmod(target, 0o777)
    os.symlink(target, env / "run" / "uavviewer")
    path = runtime_dir()
    assert path == str(env / "cache" / "uavviewer")
    assert_private(path)
    assert mode(target) == 0o777 and os.listdir(target) == []


@as_root
def test_runtime_dir_skips_a_runtime_directory_of_another_user(env):
    os.chown(env / "run", OTHER_UID, OTHER_UID)
    assert runtime_dir() == str(env / "cache" / "uavviewer")


@posix_only
def test_runtime_dir_last_resort_is_a_private_temporary_directory(env, monkeypatch):
    monkeypatch.delenv("XDG_RUNTIME_DIR")
    (env / "cache").mkdir()
    (env / "cache" / "uavviewer").write_bytes(b"")                      # in the way: not a directory
    path = runtime_dir()
    assert os.path.dirname(path) == str(env / "tmp") and os.path.basename(path).startswith("uavviewer-")
    assert_private(path)
    assert runtime_dir() == path                                       # made once, then kept
