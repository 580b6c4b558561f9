"""The plugin's only link to the snakegrid library: ctypes over the C API (include/snakegrid.h).

The library is found through the SNAKEGRID_LIBRARY environment variable, else next to this file
(the plugin zip bundles it). It is loaded once, on first use, and checked: its major version must
be the one this binding was written for and every function used here must be exported, so an old
or foreign library gives a LibraryError with a sentence for the user instead of a crash later.

Every failing call raises SnakegridError carrying the library's own message
(snakegrid_last_error_message), which names the function and the region or option at fault.
"""

import ctypes
import os
import sys
from dataclasses import dataclass

#: The C API's major version this binding speaks (SNAKEGRID_VERSION_MAJOR in the header).
EXPECTED_MAJOR = 0

#: snakegrid_status values the binding treats specially.
STATUS_CANCELLED = 7

#: File name of the library on this platform.
LIBRARY_NAME = {"win32": "snakegrid.dll", "darwin": "libsnakegrid.dylib"}.get(
    sys.platform, "libsnakegrid.so"
)


class LibraryError(Exception):
    """The library cannot be used: not found, not loadable, or of an incompatible version."""


class SnakegridError(Exception):
    """A library call failed: `status` is the snakegrid_status, str() the library's message."""

    def __init__(self, status, message):
        super().__init__(message)
        self.status = status

    @property
    def cancelled(self):
        return self.status == STATUS_CANCELLED


class _RegionMetrics(ctypes.Structure):
    _fields_ = [
        ("displacement", ctypes.c_double),
        ("neighbours_kept", ctypes.c_double),
        ("orientation_error", ctypes.c_double),
    ]


class _LayoutMetrics(ctypes.Structure):
    _fields_ = [
        (name, ctypes.c_double)
        for name in (
            "location",
            "location_raw",
            "location_moved",
            "adjacent",
            "adjacent_rook",
            "orientation",
            "misdirected",
            "shape",
        )
    ]


_PROGRESS = ctypes.CFUNCTYPE(ctypes.c_int, ctypes.c_double, ctypes.c_char_p, ctypes.c_void_p)

_P = ctypes.c_void_p
_SIZE = ctypes.c_size_t
_OUT_P = ctypes.POINTER(ctypes.c_void_p)
_OUT_SIZE = ctypes.POINTER(ctypes.c_size_t)
_OUT_I32 = ctypes.POINTER(ctypes.c_int32)
_OUT_BYTES = ctypes.POINTER(ctypes.POINTER(ctypes.c_uint8))
_STATUS = ctypes.c_uint32

#: Every function the binding uses: name -> (restype, argtypes).
_SIGNATURES = {
    "snakegrid_version": (ctypes.c_char_p, []),
    "snakegrid_last_error_message": (ctypes.c_char_p, []),
    "snakegrid_options_new": (_STATUS, [_OUT_P]),
    "snakegrid_options_free": (None, [_P]),
    "snakegrid_options_set": (_STATUS, [_P, ctypes.c_char_p, ctypes.c_char_p]),
    "snakegrid_regions_new": (_STATUS, [_OUT_P]),
    "snakegrid_regions_free": (None, [_P]),
    "snakegrid_regions_add": (_STATUS, [_P, ctypes.c_char_p, ctypes.c_char_p, _SIZE]),
    "snakegrid_run": (_STATUS, [_P, _P, _PROGRESS, _P, _OUT_P]),
    "snakegrid_result_free": (None, [_P]),
    "snakegrid_result_count": (_STATUS, [_P, _OUT_SIZE]),
    "snakegrid_result_cell_size": (_STATUS, [_P, ctypes.POINTER(ctypes.c_double)]),
    "snakegrid_result_region_id": (_STATUS, [_P, _SIZE, ctypes.POINTER(ctypes.c_char_p)]),
    "snakegrid_result_cell": (_STATUS, [_P, _SIZE, _OUT_I32, _OUT_I32]),
    "snakegrid_result_cell_wkb": (_STATUS, [_P, _SIZE, _OUT_BYTES, _OUT_SIZE]),
    "snakegrid_result_region_metrics": (_STATUS, [_P, _SIZE, ctypes.POINTER(_RegionMetrics)]),
    "snakegrid_result_layout_metrics": (_STATUS, [_P, ctypes.POINTER(_LayoutMetrics)]),
    "snakegrid_result_moved_outline_wkb": (_STATUS, [_P, _OUT_BYTES, _OUT_SIZE]),
    "snakegrid_score": (
        _STATUS,
        [_P, _P, ctypes.POINTER(_LayoutMetrics), ctypes.POINTER(_RegionMetrics), _SIZE],
    ),
}


@dataclass
class RegionMetrics:
    displacement: float
    neighbours_kept: float
    orientation_error: float


@dataclass
class LayoutMetrics:
    location: float
    location_raw: float
    location_moved: float
    adjacent: float
    adjacent_rook: float
    orientation: float
    misdirected: float
    shape: float


@dataclass
class Cell:
    """Region `id`'s cell: column and row from the top left, the square as WKB, its metrics."""

    id: str
    col: int
    row: int
    wkb: bytes
    metrics: RegionMetrics


@dataclass
class GridMap:
    """A finished run: `cells[i]` belongs to the i-th region given."""

    cells: list
    cell_size: float
    metrics: LayoutMetrics
    moved_outline_wkb: bytes


def _layout(m):
    return LayoutMetrics(*(getattr(m, name) for name, _ in _LayoutMetrics._fields_))


def _region(m):
    return RegionMetrics(m.displacement, m.neighbours_kept, m.orientation_error)


def library_path():
    """Where the library is looked for: $SNAKEGRID_LIBRARY, else beside this file."""
    return os.environ.get("SNAKEGRID_LIBRARY") or os.path.join(
        os.path.dirname(os.path.abspath(__file__)), LIBRARY_NAME
    )


class Library:
    """A loaded, checked snakegrid library."""

    def __init__(self, path):
        if not os.path.isfile(path):
            raise LibraryError(
                f"The snakegrid library was not found at {path}. Install the plugin from the "
                "zip that bundles it, or set SNAKEGRID_LIBRARY to the path of "
                f"{LIBRARY_NAME}."
            )
        try:
            lib = ctypes.CDLL(path)
        except OSError as e:
            raise LibraryError(f"The snakegrid library at {path} cannot be loaded: {e}") from e
        missing = [name for name in _SIGNATURES if not hasattr(lib, name)]
        if "snakegrid_version" in missing:
            raise LibraryError(f"{path} is not a snakegrid library (no snakegrid_version).")
        lib.snakegrid_version.restype = ctypes.c_char_p
        self.version = lib.snakegrid_version().decode()
        major = int(self.version.split(".")[0])
        if major != EXPECTED_MAJOR or missing:
            raise LibraryError(
                f"The snakegrid library at {path} is version {self.version}; this plugin needs "
                f"version {EXPECTED_MAJOR}.x with {', '.join(missing) or 'the same ABI'}. "
                "Install the plugin and library from the same release."
            )
        for name, (restype, argtypes) in _SIGNATURES.items():
            function = getattr(lib, name)
            function.restype = restype
            function.argtypes = argtypes
        self.path = path
        self._lib = lib

    def _check(self, status):
        if status != 0:
            message = self._lib.snakegrid_last_error_message().decode("utf-8", "replace")
            raise SnakegridError(status, message)

    def _regions(self, regions):
        """A regions handle filled with (id, wkb) pairs; the caller frees it."""
        handle = ctypes.c_void_p()
        self._check(self._lib.snakegrid_regions_new(ctypes.byref(handle)))
        try:
            for region_id, wkb in regions:
                wkb = bytes(wkb)
                self._check(
                    self._lib.snakegrid_regions_add(handle, region_id.encode(), wkb, len(wkb))
                )
        except BaseException:
            self._lib.snakegrid_regions_free(handle)
            raise
        return handle

    def generate(self, regions, options=None, progress=None):
        """Makes a grid map of `regions` ((id, planar WKB) pairs) with `options` ({name: text},
        the C API's option names and syntax). `progress(fraction, message)` is called during the
        run, possibly from another thread; it returns False to cancel, which raises a
        SnakegridError whose `cancelled` is true."""
        lib = self._lib
        callback_error = []

        def report(fraction, message, _user_data):
            try:
                go_on = progress(fraction, message.decode("utf-8", "replace"))
            except BaseException as e:  # never let an exception unwind into the library
                callback_error.append(e)
                return 1
            return 0 if go_on else 1

        # The CFUNCTYPE object must stay alive for the whole run: it is kept in this frame.
        c_progress = _PROGRESS(report) if progress else _PROGRESS()
        handles = {}
        try:
            handles["regions"] = self._regions(regions)
            options_handle = ctypes.c_void_p()
            self._check(lib.snakegrid_options_new(ctypes.byref(options_handle)))
            handles["options"] = options_handle
            for name, value in (options or {}).items():
                self._check(
                    lib.snakegrid_options_set(options_handle, name.encode(), value.encode())
                )
            result = ctypes.c_void_p()
            status = lib.snakegrid_run(
                handles["regions"], options_handle, c_progress, None, ctypes.byref(result)
            )
            if callback_error:
                raise callback_error[0]
            self._check(status)
            handles["result"] = result
            return self._read(result)
        finally:
            lib.snakegrid_result_free(handles.get("result"))
            lib.snakegrid_options_free(handles.get("options"))
            lib.snakegrid_regions_free(handles.get("regions"))

    def _read(self, result):
        lib = self._lib
        count = ctypes.c_size_t()
        self._check(lib.snakegrid_result_count(result, ctypes.byref(count)))
        size = ctypes.c_double()
        self._check(lib.snakegrid_result_cell_size(result, ctypes.byref(size)))
        layout = _LayoutMetrics()
        self._check(lib.snakegrid_result_layout_metrics(result, ctypes.byref(layout)))
        cells = []
        for i in range(count.value):
            region_id = ctypes.c_char_p()
            col, row = ctypes.c_int32(), ctypes.c_int32()
            metrics = _RegionMetrics()
            self._check(lib.snakegrid_result_region_id(result, i, ctypes.byref(region_id)))
            self._check(lib.snakegrid_result_cell(result, i, ctypes.byref(col), ctypes.byref(row)))
            self._check(lib.snakegrid_result_region_metrics(result, i, ctypes.byref(metrics)))
            cells.append(
                Cell(
                    region_id.value.decode(),
                    col.value,
                    row.value,
                    self._bytes(lib.snakegrid_result_cell_wkb, result, i),
                    _region(metrics),
                )
            )
        outline = self._bytes(lib.snakegrid_result_moved_outline_wkb, result)
        return GridMap(cells, size.value, _layout(layout), outline)

    def _bytes(self, accessor, *arguments):
        """A WKB buffer owned by the result, copied out."""
        data = ctypes.POINTER(ctypes.c_uint8)()
        length = ctypes.c_size_t()
        self._check(accessor(*arguments, ctypes.byref(data), ctypes.byref(length)))
        return ctypes.string_at(data, length.value)

    def score(self, regions, cells):
        """Scores an existing layout: `cells` ((id, square WKB) pairs) against `regions` ((id,
        WKB) pairs), matched by id. Returns the LayoutMetrics and one RegionMetrics per region,
        in the order of `regions`."""
        lib = self._lib
        handles = []
        try:
            handles.append(self._regions(regions))
            handles.append(self._regions(cells))
            layout = _LayoutMetrics()
            per_region = (_RegionMetrics * len(regions))()
            self._check(
                lib.snakegrid_score(
                    handles[0], handles[1], ctypes.byref(layout), per_region, len(regions)
                )
            )
            return _layout(layout), [_region(m) for m in per_region]
        finally:
            for handle in handles:
                lib.snakegrid_regions_free(handle)


_loaded = {}


def load(path=None):
    """The library at `path` (default: library_path()), loaded and checked once per path.
    Raises LibraryError with a sentence for the user when it cannot be used."""
    path = path or library_path()
    if path not in _loaded:
        _loaded[path] = Library(path)
    return _loaded[path]
