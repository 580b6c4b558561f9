"""Finding, loading and checking the snakegrid library, and turning its statuses into exceptions.

The library is $SNAKEGRID_LIBRARY when that is set (an explicit path, for a library built
elsewhere), else the one the wheel ships beside this file. It is loaded once, on first use, and
checked: its major version must be the one this package speaks and every function in
_abi.SIGNATURES must be exported, so an old or foreign library gives a LibraryError with a
sentence for the user instead of a crash later.
"""

import contextlib
import ctypes
import os
import sys

from . import _abi

#: The C API's major version this package speaks (SNAKEGRID_VERSION_MAJOR in the header).
EXPECTED_MAJOR = 0

#: File name of the library on this platform.
LIBRARY_NAME = {"win32": "snakegrid.dll", "darwin": "libsnakegrid.dylib"}.get(
    sys.platform, "libsnakegrid.so"
)


class LibraryError(Exception):
    """The library cannot be used: not found, not loadable, or of an incompatible version."""


class SnakegridError(Exception):
    """A library call failed: `status` is the snakegrid_status, str() the library's message,
    which names the function and the region or option at fault."""

    def __init__(self, status, message):
        super().__init__(message)
        self.status = status


class Cancelled(SnakegridError):
    """The progress callback asked to stop; the run produced nothing."""


def c_text(text, what):
    """`text` as the library takes a string (UTF-8, ending at its first NUL), else ValueError
    naming `what`: a NUL inside would cut it short without a word (ids "a\\0x" and "a\\0y"
    both read as "a")."""
    if "\0" in text:
        raise ValueError(f"{what} {text!r} holds a NUL character, which the library cannot take")
    return text.encode()


def library_path():
    """Where the library is looked for: $SNAKEGRID_LIBRARY, else beside this file."""
    return os.environ.get("SNAKEGRID_LIBRARY") or os.path.join(
        os.path.dirname(os.path.abspath(__file__)), LIBRARY_NAME
    )


class Library:
    """A loaded, checked library: `c` holds its functions with their signatures set."""

    def __init__(self, path):
        if not os.path.isfile(path):
            raise LibraryError(
                f"The snakegrid library was not found at {path}. Install the snakegrid wheel, "
                f"which ships it, or set SNAKEGRID_LIBRARY to the path of {LIBRARY_NAME}."
            )
        try:
            c = ctypes.CDLL(path)
        except OSError as e:
            raise LibraryError(f"The snakegrid library at {path} cannot be loaded: {e}") from e
        if not hasattr(c, "snakegrid_version"):
            raise LibraryError(f"{path} is not a snakegrid library (no snakegrid_version).")
        c.snakegrid_version.restype = ctypes.c_char_p
        self.version = c.snakegrid_version().decode()
        missing = [name for name in _abi.SIGNATURES if not hasattr(c, name)]
        if int(self.version.split(".")[0]) != EXPECTED_MAJOR or missing:
            raise LibraryError(
                f"The snakegrid library at {path} is version {self.version}; this package needs "
                f"version {EXPECTED_MAJOR}.x with {', '.join(missing) or 'the same ABI'}. "
                "Install the package and the library from the same release."
            )
        for name, (restype, argtypes) in _abi.SIGNATURES.items():
            function = getattr(c, name)
            function.restype = restype
            function.argtypes = argtypes
        self.path = path
        self.c = c

    def check(self, status):
        """Raises the library's error for a failed call (Cancelled for SNAKEGRID_CANCELLED)."""
        if status != 0:
            message = self.c.snakegrid_last_error_message().decode("utf-8", "replace")
            kind = Cancelled if status == _abi.STATUS_CANCELLED else SnakegridError
            raise kind(status, message)

    @contextlib.contextmanager
    def handle(self, kind):
        """A new snakegrid_<kind> handle (options, regions), freed on leaving the block."""
        handle = ctypes.c_void_p()
        self.check(getattr(self.c, f"snakegrid_{kind}_new")(ctypes.byref(handle)))
        try:
            yield handle
        finally:
            getattr(self.c, f"snakegrid_{kind}_free")(handle)

    def text(self, accessor, *arguments):
        """A string owned by a handle, decoded; None where the library gives NULL (a region's
        repair, for a valid polygon)."""
        out = ctypes.c_char_p()
        self.check(accessor(*arguments, ctypes.byref(out)))
        return None if out.value is None else out.value.decode("utf-8", "replace")

    def bytes(self, accessor, *arguments):
        """A WKB buffer owned by a result, copied out."""
        data = ctypes.POINTER(ctypes.c_uint8)()
        length = ctypes.c_size_t()
        self.check(accessor(*arguments, ctypes.byref(data), ctypes.byref(length)))
        return ctypes.string_at(data, length.value)


_loaded = {}


def load(path=None):
    """The library at `path` (default: library_path()), loaded and checked once per path.
    Raises LibraryError with a sentence for the user when it cannot be used."""
    path = path or library_path()
    if path not in _loaded:
        _loaded[path] = Library(path)
    return _loaded[path]
