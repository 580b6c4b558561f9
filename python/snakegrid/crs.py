"""The library's working-CRS rule (snakegrid_working_crs): the method is planar, so a layer in
longitude and latitude is projected first, to the equal-area CRS the library chooses, as the
command line does. This module only asks; the rule itself lives in the library."""

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
    boxes = [_geometry.bounds(region) for region in regions]
    numbers = (ctypes.c_double * (4 * len(boxes)))(*(v for box in boxes for v in box))
    handle = ctypes.c_void_p()
    lib.check(lib.c.snakegrid_working_crs(numbers, len(boxes), ctypes.byref(handle)))
    try:
        return WorkingCrs(*(
            lib.text(getattr(lib.c, f"snakegrid_crs_{part}"), handle)
            for part in ("wkt", "name", "note")))
    finally:
        lib.c.snakegrid_crs_free(handle)
