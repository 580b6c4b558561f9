"""The library's working-CRS rule (snakegrid_working_crs): the method is planar, so a layer in
longitude and latitude is projected first, to the equal-area CRS the library chooses, as the
command line does; and what the command line tells the user about a layer laid out in its own
CRS (snakegrid_projected_crs_note, snakegrid_looks_like_degrees). This module only asks; the
rules themselves live in the library."""

import ctypes
from dataclasses import dataclass

from . import _geometry, _library


@dataclass(frozen=True)
class WorkingCrs:
    """A CRS to lay a lon/lat layer out in: named WKT2 (pyproj, GDAL, QGIS read it), its name,
    and what to tell the user about the choice."""

    wkt: str
    name: str
    note: str


def working_crs(regions, library=None):
    """The working CRS for regions in longitude and latitude (degrees): `regions` holds one
    shapely geometry or one (west, south, east, north) box per region. Give one per region,
    not one for the whole layer, so that a layer across the antimeridian is centred on it."""
    lib = library or _library.load()
    numbers, count = _boxes(regions)
    handle = ctypes.c_void_p()
    lib.check(lib.c.snakegrid_working_crs(numbers, count, ctypes.byref(handle)))
    try:
        return WorkingCrs(*(
            lib.text(getattr(lib.c, f"snakegrid_crs_{part}"), handle)
            for part in ("wkt", "name", "note")))
    finally:
        lib.c.snakegrid_crs_free(handle)


def projected_crs_note(projection, crs, library=None):
    """What to tell the user about laying a layer out in its own projected CRS, or None: a
    Mercator projection draws areas larger towards the poles, and the regions' areas set the
    cell size. `projection` is the CRS's projection method as GDAL, PROJ or QGIS name it
    ("Mercator_1SP", "merc"; pyproj: `CRS.to_dict()["proj"]`), `crs` names it in the note."""
    lib = library or _library.load()
    out = ctypes.c_char_p()
    lib.check(lib.c.snakegrid_projected_crs_note(
        projection.encode("utf-8"), crs.encode("utf-8"), ctypes.byref(out)))
    return None if out.value is None else out.value.decode("utf-8", "replace")


def looks_like_degrees(regions, library=None):
    """Whether regions given without a CRS could be in longitude and latitude (every coordinate
    within ±180 and ±90, the layer wider than a hundredth of a degree): then the user may want
    to give them a geographic CRS first. `regions` as for working_crs."""
    lib = library or _library.load()
    numbers, count = _boxes(regions)
    out = ctypes.c_bool()
    lib.check(lib.c.snakegrid_looks_like_degrees(numbers, count, ctypes.byref(out)))
    return out.value


def _boxes(regions):
    """The regions' (west, south, east, north) boxes as the C API takes them, and their count."""
    boxes = [_geometry.bounds(region) for region in regions]
    return (ctypes.c_double * (4 * len(boxes)))(*(v for box in boxes for v in box)), len(boxes)
