"""Atomic writes: an output appears under its final name complete, or not at all."""
from __future__ import annotations

import contextlib
import errno
import os
import secrets
from pathlib import Path
from typing import Any, Iterator

_PART = ".part"  # marks a temporary name: ".<final name>.<pid>-<random>.part<suffix>"


#: The errors of a write that failed for want of room or of a writable disk: one raised without a
#: file name inside atomic_path is the output's.
_WRITE_ERRNOS = {errno.ENOSPC, errno.EDQUOT, errno.EFBIG, errno.EROFS, errno.EIO}


def check_replaceable(path: str | os.PathLike[str]) -> Path:
    """The file ``path`` names (through a symbolic link), which a write may replace: not empty, and
    not an existing folder (``IsADirectoryError``), device or pipe (``ValueError``)."""
    if not os.fspath(path):
        raise ValueError("the output path is empty")
    final = Path(os.fspath(path))
    if final.is_symlink():  # written through: the file it points to is replaced, the link kept
        final = Path(os.path.realpath(final))
    if final.is_dir():
        raise IsADirectoryError(errno.EISDIR, os.strerror(errno.EISDIR), str(final))
    if final.exists() and not final.is_file():
        raise ValueError(f"{str(final)!r} exists and is not a regular file (a device or pipe): not replaced")
    return final


@contextlib.contextmanager
def atomic_path(path: str | os.PathLike[str]) -> Iterator[Path]:
    """A temporary path beside ``path`` with the same suffix (writers pick the format from it);
    renamed to ``path`` when the block ends normally, removed when it raises (an interrupted
    write never leaves a half-written file under the final name). The parent directory must exist."""
    final = check_replaceable(path)
    suffix = Path(os.fspath(path)).suffix  # the name asked for says the format, not a link's target
    parent = final.parent
    if not parent.is_dir():
        raise FileNotFoundError(f"no such directory: {str(parent)!r} (for {str(final)!r})")
    # not created here (mkstemp would make it private, mode 0600): the writer creates it as any file
    tmp_path = parent / f".{final.name}.{os.getpid()}-{secrets.token_hex(6)}{_PART}{suffix}"
    try:
        yield tmp_path
        os.replace(tmp_path, final)
    except BaseException as exc:
        with contextlib.suppress(OSError):
            tmp_path.unlink()
        if isinstance(exc, OSError) and exc.filename == str(tmp_path) and exc.errno is not None:
            # the same error, naming the file asked for rather than the temporary one
            raise type(exc)(exc.errno, exc.strerror, str(final)) from None
        if isinstance(exc, OSError) and exc.filename is None and exc.errno in _WRITE_ERRNOS:
            # a write that failed without a name (a full disk under a writer's buffers): this file's
            raise type(exc)(exc.errno, exc.strerror, str(final)) from exc
        raise


def write_atomic(path: str | os.PathLike[str], data: Any) -> None:
    """Write ``data`` (bytes or str) to ``path`` atomically."""
    raw = data.encode() if isinstance(data, str) else bytes(data)
    with atomic_path(path) as tmp:
        with open(tmp, "wb") as fh:
            fh.write(raw)
            fh.flush()
            os.fsync(fh.fileno())  # on disk before the rename: a crash leaves the old file or the new one


def is_temporary(path: str | os.PathLike[str]) -> bool:
    """Whether ``path`` is named as :func:`atomic_path`'s temporary files are."""
    name = Path(os.fspath(path)).name
    return name.startswith(".") and _PART + Path(name).suffix in name


def remove_temporaries(directory: str | os.PathLike[str]) -> int:
    """Remove the temporary files a killed writer left in ``directory``; returns how many.
    Only for directories that one writer owns (a live writer's temporary would go too)."""
    count = 0
    for p in Path(os.fspath(directory)).iterdir():
        if p.is_file() and is_temporary(p):
            with contextlib.suppress(FileNotFoundError):
                p.unlink()
                count += 1
    return count
