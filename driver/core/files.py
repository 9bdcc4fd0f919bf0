"""Creating files safely on a machine other users share (no Qt; any part of the program may use it).

Another local user who can write to a directory we write into (``/tmp``, a shared media or
recordings folder) can plant a symbolic link or a file under the name we are about to use:
``open(path, "w")`` would then follow the link and truncate whatever it points to (a file of
ours, as our permissions allow), or write our data where that user reads it. A name that is
predictable (``/tmp/uavviewer-solo-5600.sdp``) makes that easy. These helpers never follow a
link at the name they create, never clobber a file that is already there, and keep temporary
files in a directory only we can enter:

- :func:`runtime_dir`: our private directory for temporary files (0700, ours, not a link);
- :func:`private_dir`: make or check such a directory anywhere;
- :func:`write_private`: replace a small file's content at once (a key, an SDP), mode 0600;
- :func:`open_new`: create a file that must not exist yet (a snapshot, a recording's name).
"""
from __future__ import annotations

import atexit
import logging
import os
import shutil
import stat
import sys
import tempfile
import threading

log = logging.getLogger(__name__)

__all__ = ["APP_DIR", "runtime_dir", "private_dir", "write_private", "open_new", "default_record_dir"]

APP_DIR = "uavviewer"
_NOFOLLOW = getattr(os, "O_NOFOLLOW", 0)        # POSIX; Windows has no symlinks we would follow here
_CLOEXEC = getattr(os, "O_CLOEXEC", 0)          # a child process (ffmpeg, a shell) does not inherit it
_BINARY = getattr(os, "O_BINARY", 0)            # Windows: no newline translation
_NEW_FILE = os.O_WRONLY | os.O_CREAT | os.O_EXCL | _NOFOLLOW | _CLOEXEC | _BINARY

_lock = threading.Lock()
_temp_dir: str | None = None                    # the last resort, made once per process


def private_dir(path: str) -> str:
    """``path`` as a directory only we can use: created 0700 if missing (parents too), else checked.

    Refused (PermissionError) when it is a symbolic link, not a directory, or another user's;
    a directory of ours that others may enter is tightened to 0700, with a warning. The check is
    made on the opened directory (O_NOFOLLOW), so nobody can swap the name between check and use.
    """
    path = os.path.abspath(path)
    os.makedirs(path, mode=0o700, exist_ok=True)    # mkdir never follows a link at the last name
    if os.name != "posix":
        return path
    try:
        fd = os.open(path, os.O_RDONLY | os.O_DIRECTORY | _NOFOLLOW | _CLOEXEC)
    except OSError as e:                            # ELOOP: a link; ENOTDIR: a file
        raise PermissionError(f"{path} is not a directory of ours ({e.strerror})") from None
    try:
        st = os.fstat(fd)
        if st.st_uid != os.geteuid():
            raise PermissionError(f"{path} belongs to another user (uid {st.st_uid})")
        if stat.S_IMODE(st.st_mode) & 0o077:
            log.warning("%s was open to others (mode %o); making it 0700", path, stat.S_IMODE(st.st_mode))
            os.fchmod(fd, 0o700)
    finally:
        os.close(fd)
    return path


def runtime_dir() -> str:
    """Our per-user private directory for temporary files (0700, owned by us, never a link).

    ``$XDG_RUNTIME_DIR/uavviewer`` when the session has a runtime directory that is ours and
    closed to others (systemd's ``/run/user/UID``: a tmpfs, emptied at logout); else
    ``$XDG_CACHE_HOME/uavviewer`` (``~/.cache/uavviewer``); else, if neither can be used, a
    directory made for this process by :func:`tempfile.mkdtemp` and removed when it exits.
    A file in it may still be given an unpredictable name: the directory outlives one run.
    """
    global _temp_dir
    candidates = []
    xdg = os.environ.get("XDG_RUNTIME_DIR", "")
    if os.name == "posix" and os.path.isabs(xdg) and _ours_and_closed(xdg):
        candidates.append(os.path.join(xdg, APP_DIR))
    cache = os.environ.get("XDG_CACHE_HOME", "")
    if not os.path.isabs(cache):
        cache = os.path.join(os.path.expanduser("~"), ".cache")
    if os.path.isabs(cache):                        # "~" unexpanded: no home, skip it
        candidates.append(os.path.join(cache, APP_DIR))
    for path in candidates:
        try:
            return private_dir(path)
        except OSError as e:
            log.warning("not using %s for temporary files: %s", path, e)
    with _lock:
        if _temp_dir is not None:
            try:
                return private_dir(_temp_dir)
            except OSError:                         # removed under us (a /tmp cleaner): make another
                pass
        _temp_dir = tempfile.mkdtemp(prefix=APP_DIR + "-")     # 0700, random name, created exclusively
        atexit.register(shutil.rmtree, _temp_dir, True)
        return _temp_dir


def _ours_and_closed(path: str) -> bool:
    try:
        st = os.lstat(path)
    except OSError:
        return False
    return stat.S_ISDIR(st.st_mode) and st.st_uid == os.geteuid() and not stat.S_IMODE(st.st_mode) & 0o077


def write_private(path: str, data: bytes, mode: int = 0o600) -> str:
    """Replace ``path``'s content with ``data`` at once; the file is 0600 (only we read it), or ``mode``
    for what others may read (a CA certificate).

    The data goes to a new temporary file in the same directory (random name, created with
    O_EXCL|O_NOFOLLOW, mode 0600), is flushed to disk, then renamed over ``path``. A rename
    replaces a symbolic link planted at ``path`` instead of writing through it, and a reader
    (or a crash) sees the old content or the new, never half of it. Returns ``path``.
    """
    folder, name = os.path.split(os.path.abspath(path))
    fd, tmp = tempfile.mkstemp(prefix=f".{name}.", suffix=".tmp", dir=folder)  # O_EXCL|O_NOFOLLOW, 0600
    try:
        with os.fdopen(fd, "wb") as f:
            if os.name == "posix":
                os.fchmod(f.fileno(), mode)         # exactly this mode whatever the umask
            f.write(data)
            f.flush()
            os.fsync(f.fileno())
        os.replace(tmp, path)
    except BaseException:
        try:
            os.unlink(tmp)
        except OSError:
            pass
        raise
    _fsync_dir(folder)                              # the rename itself survives a power cut
    return path


def _fsync_dir(folder: str) -> None:
    if os.name != "posix":
        return
    try:
        fd = os.open(folder, os.O_RDONLY | os.O_DIRECTORY | _CLOEXEC)
    except OSError:
        return
    try:
        os.fsync(fd)
    except OSError:
        pass
    finally:
        os.close(fd)


def open_new(path: str, mode: str = "wb", perm: int = 0o600, **kwargs):
    """A new file at ``path``, opened for writing (``mode`` "wb" or "w"; ``kwargs`` go to :func:`open`).

    Created with O_CREAT|O_EXCL|O_NOFOLLOW: if anything is already at ``path`` (a file, a
    directory, a symbolic link even to nowhere) it raises FileExistsError and touches nothing.
    ``perm`` is the mode (less the umask): 0600 for what is only ours, 0644 for media meant to be
    copied and shared.
    """
    if mode not in ("wb", "w"):
        raise ValueError(f"open_new writes a new file: mode 'wb' or 'w', not {mode!r}")
    fd = os.open(path, _NEW_FILE, perm)
    try:
        return os.fdopen(fd, mode, **kwargs)
    except BaseException:
        os.close(fd)
        raise


def default_record_dir() -> str:
    """Where Extra.recordOnUsb writes when ``Camera.RecordDir`` is not set: the per-user data folder
    the viewer also uses (Qt's AppDataLocation, found here without Qt), never the current directory."""
    if sys.platform == "win32":
        base = os.environ.get("APPDATA") or os.path.join(os.path.expanduser("~"), "AppData", "Roaming")
    elif sys.platform == "darwin":
        base = os.path.join(os.path.expanduser("~"), "Library", "Application Support")
    else:
        base = os.environ.get("XDG_DATA_HOME") or os.path.join(os.path.expanduser("~"), ".local", "share")
    return os.path.join(base, "UavViewerPy", "recordings")
