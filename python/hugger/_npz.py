"""The one reader of the project's .npz files (trajectory files and dataset shards): NumPy's
format read member by member, refusing what a damaged or crafted file could make ``np.load`` do
(unpickle objects, allocate what a header declares, unpack a decompression bomb)."""
from __future__ import annotations

import struct
import tokenize
import zipfile
import zlib
from typing import IO, Any

import numpy as np

#: What reading a damaged zip/npy can raise. (numpy parses a .npy header with ``tokenize`` and
#: ``ast``: a damaged one raises TokenError or SyntaxError; zipfile raises RuntimeError for a
#: member whose flags, damaged, say it is encrypted, and NotImplementedError and RecursionError are
#: RuntimeErrors too.)
READ_ERRORS = (OSError, ValueError, TypeError, EOFError, zipfile.BadZipFile, zipfile.LargeZipFile, KeyError,
               IndexError, zlib.error, RuntimeError, struct.error, OverflowError, UnicodeError,
               MemoryError, tokenize.TokenError, SyntaxError)

#: A member unpacking to more than this (bytes) and more than BOMB_RATIO times its packed size is
#: refused unread: a plan's numbers pack two to ten times, a crafted run of zeros a thousand times,
#: and a small file must not make the reader allocate gigabytes.
BOMB_BYTES = 64 << 20
BOMB_RATIO = 100


class ArchiveError(ValueError):
    """A member of an archive that cannot be read as a plain array (the message names it)."""


def refuse_bomb(what: str, size: int, packed: int) -> None:
    """``what`` (a member, or all of them: a bomb split into many members is one too), unpacking
    to ``size`` bytes from ``packed``, is refused past BOMB_BYTES and BOMB_RATIO."""
    if size > BOMB_BYTES and size > BOMB_RATIO * max(packed, 1):
        raise ArchiveError(f"{what}: {size} bytes packed into {packed}, over {BOMB_RATIO} times smaller: refused "
                           f"unread, as a decompression bomb (no plan's numbers pack so well)")


def _read_member(zf: zipfile.ZipFile, info: zipfile.ZipInfo, key: str) -> np.ndarray:
    """One .npy member, refusing pickled objects, declared sizes the member lacks (a damaged
    header must not make numpy allocate gigabytes) and decompression bombs."""
    fmt = np.lib.format
    refuse_bomb(key, info.file_size, info.compress_size)
    with zf.open(info) as member:
        version = fmt.read_magic(member)
        if version == (1, 0):
            shape, _, dtype = fmt.read_array_header_1_0(member)
        elif version in ((2, 0), (3, 0)):
            shape, _, dtype = fmt.read_array_header_2_0(member)
        else:
            raise ArchiveError(f"{key}: unsupported .npy format version {version}")
        if dtype.hasobject:
            raise ArchiveError(f"{key} holds pickled Python objects ({dtype}); refused, never unpickled")
        declared = int(np.prod(shape, dtype=object)) * dtype.itemsize
        if declared != info.file_size - member.tell():
            raise ArchiveError(f"{key}: its header declares {declared} bytes of data but the file holds "
                               f"{info.file_size - member.tell()}")
    with zf.open(info) as member:
        array = fmt.read_array(member, allow_pickle=False)
        # On to the member's end, where zipfile checks its CRC-32 (reading just the array's bytes
        # can stop short of it in a compressed member): a damaged member is refused rather than
        # read as other numbers. Nothing is left to read but the end of the stream.
        if member.read(1):
            raise ArchiveError(f"{key}: data beyond its array")
    return array


class Archive:
    """The arrays of an open .npz file, each read (and checked) when first asked for, as
    ``np.load``'s NpzFile: ``files`` names them, ``archive[key]`` reads one (``KeyError`` if there
    is none, ``ArchiveError`` if it cannot be read). Opening refuses a file whose members together
    are a decompression bomb. ``fh``: a binary file open for reading, left open on closing."""

    def __init__(self, fh: IO[bytes]) -> None:
        self._zf = zipfile.ZipFile(fh)
        try:
            self._members = {i.filename[:-4]: i for i in self._zf.infolist()
                             if i.filename.endswith(".npy") and not i.is_dir()}
            refuse_bomb("its members", sum(i.file_size for i in self._members.values()),
                        sum(i.compress_size for i in self._members.values()))
        except BaseException:
            self._zf.close()
            raise
        self.files = list(self._members)

    def __contains__(self, key: object) -> bool:
        return key in self._members

    def __getitem__(self, key: str) -> np.ndarray:
        info = self._members[key]
        try:
            return _read_member(self._zf, info, key)
        except ArchiveError:
            raise
        except READ_ERRORS as exc:
            raise ArchiveError(f"{key}: {type(exc).__name__}: {exc}") from None

    def read_all(self) -> dict[str, np.ndarray]:
        return {key: self[key] for key in self.files}

    def close(self) -> None:
        self._zf.close()

    def __enter__(self) -> Archive:
        return self

    def __exit__(self, *exc: Any) -> None:
        self.close()
