"""snakegrid: grid maps (tile maps) from polygon layers, by the snake model.

    import snakegrid
    grid = snakegrid.layout(geometries, ids, alpha=2)      # shapely or WKB, planar
    grid.cells[0].fields["grid_col"], grid.metrics.adjacent, grid.notes

A binding over the library's C API (include/snakegrid.h) with ctypes. The parameter table,
the working-CRS rule, the input checks and the added fields all come from the library.
"""

from ._library import Cancelled, LibraryError, SnakegridError, library_path, load
from .crs import WorkingCrs, looks_like_degrees, projected_crs_note, working_crs
from .layout import (
    Cell, Field, GridMap, GroupMetrics, LayoutMetrics, RegionMetrics, edit_pins, fields, id_text,
    layout, score)
from .options import Option, check_options, options


def library_version():
    """The version of the library loaded ("MAJOR.MINOR.PATCH")."""
    return load().version


__all__ = [
    "Cancelled", "Cell", "Field", "GridMap", "GroupMetrics", "LayoutMetrics", "LibraryError",
    "Option", "RegionMetrics", "SnakegridError", "WorkingCrs", "check_options", "edit_pins", "fields",
    "id_text",
    "layout", "library_path", "library_version", "load", "looks_like_degrees", "options",
    "projected_crs_note", "score", "working_crs",
]
