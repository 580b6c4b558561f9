"""The library's working-CRS rule (snakegrid_working_crs): the method is planar, so a layer in
longitude and latitude is projected first, to the equal-area CRS the library chooses, as the
command line does; and what the command line tells the user about a layer laid out in its own
CRS (snakegrid_projected_crs_note, snakegrid_looks_like_degrees). This module only asks; the
rules themselves live in the library."""

import ctypes
import weakref
from dataclasses import dataclass, field

from . import _geometry, _library


class _Handle:
    """A library CRS handle, freed with the last WorkingCrs that holds it."""

    def __init__(self, lib, handle):
        self.lib, self.handle = lib, handle
        weakref.finalize(self, lib.c.snakegrid_crs_free, handle)


@dataclass(frozen=True)
class WorkingCrs:
    """A CRS to lay a lon/lat layer out in: named WKT2 (pyproj, GDAL, QGIS read it), its name,
    and what to tell the user about the choice. Project each region after `cut`."""

    wkt: str
    name: str
    note: str
    _handle: _Handle = field(compare=False, repr=False, default=None)

    def cut(self, geometry):
        """`geometry` (lon/lat; shapely or WKB) ready to be projected to this CRS
        (snakegrid_crs_cut): a region drawn across ±180° is carried across, and one across the
        meridian opposite the centre is cut there, its pieces on either edge of the map;
        projected as drawn, it would become a band round the globe. Nearly every region comes
        back as it was given, the same object; round a pole (a CRS centred on it) every region
        does."""
        wkb = _geometry.to_wkb(geometry)
        if wkb is None:
            return geometry
        lib = self._handle.lib
        data = ctypes.POINTER(ctypes.c_uint8)()
        length = ctypes.c_size_t()
        lib.check(lib.c.snakegrid_crs_cut(
            self._handle.handle, _bytes(wkb), len(wkb), ctypes.byref(data), ctypes.byref(length)))
        if not data:
            return geometry
        return _geometry.from_wkb(ctypes.string_at(data, length.value),
                                  not _geometry.is_wkb(geometry))


def working_crs(regions, library=None):
    """The working CRS for regions in longitude and latitude (degrees): `regions` holds one
    shapely geometry, WKB, or (west, south, east, north) box per region. Give geometries, so
    that a region drawn across ±180° is read right (snakegrid_lon_lat_boxes), or one box per
    region, not one for the whole layer, so that a layer across the antimeridian is centred on
    it."""
    lib = library or _library.load()
    numbers, count = _boxes(regions, lib)
    handle = ctypes.c_void_p()
    lib.check(lib.c.snakegrid_working_crs(numbers, count, ctypes.byref(handle)))
    owner = _Handle(lib, handle)
    return WorkingCrs(*(
        lib.text(getattr(lib.c, f"snakegrid_crs_{part}"), handle)
        for part in ("wkt", "name", "note")), _handle=owner)


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
    numbers, count = _boxes(regions, lib)
    out = ctypes.c_bool()
    lib.check(lib.c.snakegrid_looks_like_degrees(numbers, count, ctypes.byref(out)))
    return out.value


def _bytes(wkb):
    return (ctypes.c_uint8 * len(wkb)).from_buffer_copy(wkb)


def _boxes(regions, lib):
    """The regions' (west, south, east, north) boxes as the C API takes them, and their count:
    a box as given, a geometry's from the library, one per polygon."""
    numbers = []
    for region in regions:
        box = _geometry.box(region)
        if box is not None:
            numbers.extend(box)
            continue
        wkb = _geometry.to_wkb(region)
        if wkb is None:
            continue
        found = ctypes.POINTER(ctypes.c_double)()
        count = ctypes.c_size_t()
        lib.check(lib.c.snakegrid_lon_lat_boxes(
            _bytes(wkb), len(wkb), ctypes.byref(found), ctypes.byref(count)))
        numbers.extend(found[:4 * count.value])
    return (ctypes.c_double * len(numbers))(*numbers), len(numbers) // 4
