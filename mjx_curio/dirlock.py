"""One writer per sweep directory: an exclusive OS file lock on `<out>/.lock`.

`flock` locks belong to the open file, so the kernel drops the lock the moment its process
ends, however it ends (SIGKILL included): a killed sweep never leaves a stale lock, and
`resume=true` can take over at once. The file's text names the holder (host, pid, start time)
for the message a second sweep gets. The file itself stays; only the lock on it matters.
"""

from __future__ import annotations

import datetime
import fcntl
import os
import pathlib
import platform

from mjx_curio.config import ConfigError

LOCK_NAME = ".lock"


def _holder(path: pathlib.Path) -> str:
    try:
        text = path.read_text().strip()
    except OSError:
        text = ""
    return text or "another process"


def _in_use(out: pathlib.Path, path: pathlib.Path) -> ConfigError:
    return ConfigError(f"out={out} is in use by another sweep ({_holder(path)} holds {path}); wait for it to end "
                       "or stop it, then resume=true continues it; two sweeps must not write one directory")


def check_free(out: pathlib.Path) -> None:
    """Raise ConfigError if a live process holds `out`'s lock. Creates nothing."""
    path = pathlib.Path(out) / LOCK_NAME
    try:
        fd = os.open(path, os.O_RDONLY)
    except OSError:
        return  # no lock file: nobody has ever held it
    try:
        fcntl.flock(fd, fcntl.LOCK_SH | fcntl.LOCK_NB)
    except BlockingIOError:
        raise _in_use(out, path) from None
    finally:
        os.close(fd)


class DirLock:
    """Holds `<out>/.lock` exclusively until `release()` or the process ends."""

    def __init__(self, out: pathlib.Path):
        self.out = pathlib.Path(out)
        self.path = self.out / LOCK_NAME
        self.fd = os.open(self.path, os.O_RDWR | os.O_CREAT, 0o644)
        try:
            fcntl.flock(self.fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            os.close(self.fd)
            raise _in_use(self.out, self.path) from None
        os.ftruncate(self.fd, 0)
        since = datetime.datetime.now().isoformat(timespec="seconds")
        os.write(self.fd, f"pid {os.getpid()} on host {platform.node()} since {since}\n".encode())

    def release(self) -> None:
        if self.fd is not None:
            os.close(self.fd)  # closing the file drops the lock
            self.fd = None

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.release()
