"""Laying regions out as a grid map (snakegrid_run) and scoring a layout (snakegrid_score).

Regions go in as (id, geometry) with the command line's per-feature checks and messages
(snakegrid_regions_add_feature); cells come out with every field the library says a grid layer
adds (snakegrid_field_info), so names, types and values are the command line's.
"""

import ctypes
import dataclasses
import math
import threading
from dataclasses import dataclass
from typing import Any, Dict, List, Optional

from . import _abi, _geometry, _library
from .options import set_options


def _dataclass_of(struct, doc):
    """A frozen dataclass with the fields of a ctypes mirror, so that a field the C struct gains
    needs no second edit here."""
    kinds = {ctypes.c_double: float, ctypes.c_size_t: int, ctypes.c_uint32: int}
    made = dataclasses.make_dataclass(
        struct.__name__, [(name, kinds[kind]) for name, kind in struct._fields_], frozen=True)
    made.__doc__ = doc
    made.__module__ = __name__
    return made


RegionMetrics = _dataclass_of(
    _abi.RegionMetrics, "How well one region is placed (snakegrid_region_metrics).")
LayoutMetrics = _dataclass_of(
    _abi.LayoutMetrics, "The layout's metrics, method.md section 8 (snakegrid_layout_metrics).")
GroupMetrics = _dataclass_of(
    _abi.GroupMetrics, "How a layout keeps its groups, method.md section 10 "
    "(snakegrid_group_metrics).")


def _copy(made, struct):
    return made(*(getattr(struct, name) for name, _ in struct._fields_))


@dataclass(frozen=True)
class Field:
    """A field a grid layer adds: its name, whether it holds whole numbers, what it means."""

    name: str
    integer: bool
    description: str


def fields(library=None):
    """The fields a grid layer adds after the source's, in order (grid_col, grid_row, ...)."""
    lib = library or _library.load()
    out = []
    for index in range(lib.c.snakegrid_field_count()):
        row = _abi.Field()
        lib.check(lib.c.snakegrid_field_info(index, ctypes.byref(row)))
        out.append(Field(row.name.decode(), row.integer, row.description.decode()))
    return out


@dataclass
class Cell:
    """Region `id`'s square (a shapely Polygon, or WKB when the regions were given as WKB), its
    added fields {name: value} in the library's order, its metrics, and what was wrong with its
    polygon if the library repaired it (None for a valid one)."""

    id: str
    geometry: Any
    fields: Dict[str, Any]
    metrics: Any  # RegionMetrics
    repair: Optional[str] = None


@dataclass
class GridMap:
    """A finished run: `cells[i]` belongs to the i-th region given. `notes` are the library's
    notes for the user (e.g. that an invalid polygon was repaired)."""

    cells: List[Cell]
    cell_size: float
    metrics: Any  # LayoutMetrics
    moved_outline: Any
    notes: List[str]
    #: The layout as HexJSON (Open Innovations' format, keyed and labelled by the ids) for
    #: hexagonal cells (option cell="hex"); None for squares.
    hexjson: Optional[str] = None
    #: How the layout keeps its groups (GroupMetrics, method.md section 10) when layout() was
    #: given groups; None without.
    group_metrics: Any = None

    def table(self):
        """The cells as columns, {"id": [...], <each added field>: [...], "geometry": [...]},
        which geopandas.GeoDataFrame and pandas.DataFrame take as they are."""
        columns = {"id": [cell.id for cell in self.cells]}
        for name in self.cells[0].fields if self.cells else ():
            columns[name] = [cell.fields[name] for cell in self.cells]
        columns["geometry"] = [cell.geometry for cell in self.cells]
        return columns


def id_text(value):
    """A region id as the library takes it: None for a missing value (None, NaN, pandas' NA),
    a float that is a whole number without its ".0" (pandas reads an integer column with
    missing values as floats; GDAL, and so the command line, writes 6.0 as "6"), else str()."""
    if value is None or type(value).__name__ == "NAType" or value != value:
        return None
    if isinstance(value, float) and value.is_integer():
        return str(int(value))
    return str(value)


def _add_features(lib, handle, geometries, ids, labels):
    """Adds every feature with the command line's checks; `labels` name them in messages until
    their ids are known (default "index k"). A GeoDataFrame stands for its geometry column
    (listed, a frame gives its column names)."""
    if hasattr(geometries, "columns") and hasattr(geometries, "geometry"):
        geometries = geometries.geometry
    geometries = list(geometries)
    ids = [str(k) for k in range(len(geometries))] if ids is None else list(ids)
    labels = [f"index {k}" for k in range(len(geometries))] if labels is None else list(labels)
    if not len(ids) == len(labels) == len(geometries):
        raise ValueError(
            f"{len(geometries)} geometries, {len(ids)} ids and {len(labels)} labels: give one "
            "of each per region")
    for geometry, region_id, label in zip(geometries, ids, labels):
        wkb = _geometry.to_wkb(geometry)
        region_id = id_text(region_id)
        lib.check(lib.c.snakegrid_regions_add_feature(
            handle, _library.c_text(str(label), "the label"),
            None if region_id is None else _library.c_text(region_id, f"{label}: the id"),
            wkb, 0 if wkb is None else len(wkb)))
    return geometries


def layout(geometries, ids=None, *, labels=None, groups=None, pins=None, progress=None,
           library=None, **options):
    """Lays out regions as a grid map: one cell per region (squares, or hexagons with cell="hex").

    `geometries`: shapely polygons or multipolygons, or their WKB (a GeoSeries, or a
    GeoDataFrame for its geometry column), in a planar CRS (project a
    lon/lat layer first, e.g. to working_crs(...); a GeoSeries in a geographic CRS is laid out
    as given, with a note saying so). `ids`: one unique id per region (default
    the positions). `groups`: one group per region (any values, compared as id_text() gives
    them; None: a group of its own), whose regions keep together in one block of cells per
    landmass; option group_gap=1 keeps the blocks a cell apart. `pins`: per region None (free)
    or its cell's (column, row), whole numbers as the grid layer numbers them (rows from the
    top); with pins every cell is numbered in the pins' frame (see edit_pins for a re-layout
    after hand edits). `options`: the method's parameters by name (see options()), e.g.
    ``alpha=2, refine=False, shifts=[(0, 0), (0.5, 0.5)]``. `progress(fraction, message)` is
    called during the run, possibly from another thread; returning False cancels the run,
    which then raises Cancelled. Bad input or options raise SnakegridError with the library's
    message, which names the region or option.
    """
    lib = library or _library.load()
    crs = getattr(geometries, "crs", None)  # a GeoSeries' CRS
    callback_error = []
    interrupted = threading.Event()

    def report(fraction, message, _user_data):
        if interrupted.is_set():
            return 1
        if progress is None:
            return 0
        try:
            go_on = progress(fraction, message.decode("utf-8", "replace"))
        except BaseException as e:  # never let an exception unwind into the library
            callback_error.append(e)
            return 1
        return 1 if go_on is False else 0

    # The ctypes callback must outlive the run: it is kept in this frame. It is always given,
    # so that Ctrl-C can cancel the run through it (see _interruptible).
    c_progress = _abi.PROGRESS(report)
    with lib.handle("regions") as regions, lib.handle("options") as handle:
        geometries = _add_features(lib, regions, geometries, ids, labels)
        if groups is not None:
            for k, group in enumerate(_per_region(groups, geometries, "groups", "group")):
                name = id_text(group)
                lib.check(lib.c.snakegrid_regions_set_group(
                    regions, k,
                    None if name is None else _library.c_text(name, f"index {k}: the group")))
        if pins is not None:
            for k, pin in enumerate(_per_region(pins, geometries, "pins", "pin (or None)")):
                col, row = _pin(pin, k)
                lib.check(lib.c.snakegrid_regions_set_pin(regions, k, col, row))
        set_options(lib, handle, options)
        result = ctypes.c_void_p()

        def run():
            status = lib.c.snakegrid_run(regions, handle, c_progress, None, ctypes.byref(result))
            # Read on the thread of the call: the library keeps its message per thread.
            try:
                lib.check(status)
            except _library.SnakegridError as e:
                return e
            return None

        try:
            failure = _interruptible(run, interrupted)
            if callback_error:
                raise callback_error[0]
            if failure is not None:
                raise failure
            as_shapely = bool(geometries) and not _geometry.is_wkb(geometries[0])
            grid = _read(lib, result, as_shapely)
            if getattr(crs, "is_geographic", False):
                grid.notes.append(
                    f"the geometries' CRS {crs.to_string()} is geographic: they were laid out "
                    "as if degrees were planar units (east-west stretched away from the "
                    "equator); project them first, e.g. to snakegrid.working_crs(...), as the "
                    "command line does")
            return grid
        finally:
            lib.c.snakegrid_result_free(result)


def _interruptible(call, interrupted):
    """Runs `call`, a run of the library whose progress callback cancels it once `interrupted`
    is set, and returns what `call` returns, so that Ctrl-C stops the run. Python raises
    KeyboardInterrupt only in the main thread and only between bytecodes: during the library's
    call the interrupt waited for the whole run, and when it fell inside a progress callback,
    ctypes swallowed it. So from the main thread the call runs on a worker thread while this
    one waits, interruptibly; on Ctrl-C the callback cancels the run (the library stops within
    0.2 s), and KeyboardInterrupt is raised once the worker is done with the handles it uses."""
    if threading.current_thread() is not threading.main_thread():
        return call()
    outcome = []

    def work():
        try:
            outcome.append((call(), None))
        except BaseException as e:  # handed to the waiting thread
            outcome.append((None, e))

    worker = threading.Thread(target=work, name="snakegrid run", daemon=True)
    worker.start()
    try:
        while worker.is_alive():
            worker.join(0.05)
    except KeyboardInterrupt:
        interrupted.set()
        # The handles stay alive until the run has returned, whatever else is pressed.
        while worker.is_alive():
            try:
                worker.join()
            except KeyboardInterrupt:
                pass
        raise
    status, error = outcome[0]
    if error is not None:
        raise error
    return status


def _pin(pin, k):
    """Region `k`'s pin as the library takes it: (column, row), NaN for a free one or a free
    axis (None), else ValueError naming the region; the library checks the numbers."""
    if pin is None:
        return math.nan, math.nan
    try:
        col, row = pin
        return tuple(math.nan if v is None else float(v) for v in (col, row))
    except (TypeError, ValueError):
        raise ValueError(f"index {k}: the pin {pin!r} is not None or a (column, row) pair of "
                         "numbers") from None


def _per_region(values, geometries, name, one):
    """`values` as a list, one per geometry, else ValueError."""
    values = list(values)
    if len(values) != len(geometries):
        raise ValueError(f"{len(geometries)} geometries and {len(values)} {name}: give one "
                         f"{one} per region")
    return values


def _read(lib, result, as_shapely):
    c = lib.c
    count, size = ctypes.c_size_t(), ctypes.c_double()
    lib.check(c.snakegrid_result_count(result, ctypes.byref(count)))
    lib.check(c.snakegrid_result_cell_size(result, ctypes.byref(size)))
    layout_metrics = _abi.LayoutMetrics()
    lib.check(c.snakegrid_result_layout_metrics(result, ctypes.byref(layout_metrics)))
    added = fields(lib)
    cells = []
    value = ctypes.c_double()
    for i in range(count.value):
        metrics = _abi.RegionMetrics()
        lib.check(c.snakegrid_result_region_metrics(result, i, ctypes.byref(metrics)))
        values = {}
        for f, field in enumerate(added):
            lib.check(c.snakegrid_result_field(result, i, f, ctypes.byref(value)))
            values[field.name] = int(value.value) if field.integer else value.value
        cells.append(Cell(
            id=lib.text(c.snakegrid_result_region_id, result, i),
            geometry=_geometry.from_wkb(lib.bytes(c.snakegrid_result_cell_wkb, result, i),
                                        as_shapely),
            fields=values,
            metrics=_copy(RegionMetrics, metrics),
            repair=lib.text(c.snakegrid_result_region_repair, result, i)))
    notes_count = ctypes.c_size_t()
    lib.check(c.snakegrid_result_note_count(result, ctypes.byref(notes_count)))
    return GridMap(
        cells=cells,
        cell_size=size.value,
        metrics=_copy(LayoutMetrics, layout_metrics),
        moved_outline=_geometry.from_wkb(
            lib.bytes(c.snakegrid_result_moved_outline_wkb, result), as_shapely),
        notes=[lib.text(c.snakegrid_result_note, result, i) for i in range(notes_count.value)],
        hexjson=_hexjson(lib, result),
        group_metrics=_group_metrics(lib, result))


def _group_metrics(lib, result):
    """The result's GroupMetrics, or None for a layout without groups (which the library
    refuses)."""
    out = _abi.GroupMetrics()
    if lib.c.snakegrid_result_group_metrics(result, ctypes.byref(out)) != 0:
        return None
    return _copy(GroupMetrics, out)


def _hexjson(lib, result):
    """The result's HexJSON, or None for a layout of squares (which the library refuses)."""
    out = ctypes.c_char_p()
    if lib.c.snakegrid_result_hexjson(result, ctypes.byref(out)) != 0:
        return None
    return out.value.decode("utf-8")


def score(regions, region_ids, cells, cell_ids, *, region_labels=None, cell_labels=None,
          library=None):
    """Scores a layout made elsewhere (a grid layer edited by hand): `cells` holds one square
    per region under the region's id, in the regions' planar CRS. Returns the LayoutMetrics and
    one RegionMetrics per region, in the order of `regions`."""
    lib = library or _library.load()
    with lib.handle("regions") as region_handle, lib.handle("regions") as cell_handle:
        regions = _add_features(lib, region_handle, regions, region_ids, region_labels)
        _add_features(lib, cell_handle, cells, cell_ids, cell_labels)
        layout_metrics = _abi.LayoutMetrics()
        per_region = (_abi.RegionMetrics * len(regions))()
        lib.check(lib.c.snakegrid_score(
            region_handle, cell_handle, ctypes.byref(layout_metrics), per_region, len(regions)))
    return _copy(LayoutMetrics, layout_metrics), [_copy(RegionMetrics, m) for m in per_region]


def edit_pins(cells, cell_ids, q, r, *, keep=None, labels=None, library=None, **options):
    """The pins a grid layer edited by hand gives, for a re-layout: `cells` the layer's cell
    polygons (shapely or WKB) under their regions' ids, `q` and `r` their grid_q and grid_r
    fields as written (for squares grid_col and grid_row), `keep` (optional) whether each was
    ticked to keep, `labels` naming them in messages; `options` as for layout() (the cell shape
    counts). A cell more than a quarter
    cell from the position q, r name was moved, to the nearest lattice position. Returns per
    cell None (laid out again) or (col, row, moved): pass [(col, row) or None] as layout()'s
    `pins` with the source regions. Two cells on one position raise SnakegridError naming both.
    """
    lib = library or _library.load()
    cells = list(cells)
    count = len(cells)
    names = [f"index {k}" for k in range(count)] if labels is None else list(labels)
    positions = [
        [_grid_position(v, field, name)
         for v, name in zip(_per_region(values, cells, f"{field} values", field), names)]
        for values, field in ((q, "grid_q"), (r, "grid_r"))]
    as_array = (ctypes.c_int32 * count)
    with lib.handle("regions") as cell_handle, lib.handle("options") as handle:
        _add_features(lib, cell_handle, cells, cell_ids, labels)
        set_options(lib, handle, options)
        out = (_abi.EditPin * count)()
        keep_array = None if keep is None else (ctypes.c_bool * count)(
            *(bool(k) for k in _per_region(keep, cells, "keep values", "keep value")))
        lib.check(lib.c.snakegrid_edit_pins(
            cell_handle, as_array(*positions[0]), as_array(*positions[1]), keep_array, count,
            handle, out))
    return [(p.col, p.row, p.moved) if p.pinned else None for p in out]


def _grid_position(value, field, label):
    """A cell's grid_q or grid_r as written, as a whole number the C API takes (32 bits), else
    ValueError naming the cell."""
    if value is None:
        raise ValueError(f"{label}: {field} is empty: every cell of the grid layer needs its "
                         "position")
    try:
        number = float(value)
    except (TypeError, ValueError):
        raise ValueError(f"{label}: {field} {value!r} is not a number") from None
    if not number.is_integer() or not -2**31 <= number < 2**31:
        raise ValueError(f"{label}: {field} {value!r} is not a whole number from -2**31 to "
                         "2**31 - 1")
    return int(number)
