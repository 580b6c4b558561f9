"""Geometries in and out: WKB bytes always work; shapely geometries work when shapely is
installed (it is optional, and imported only when a caller uses it)."""

_BINARY = (bytes, bytearray, memoryview)


def to_wkb(geometry):
    """WKB bytes for a shapely geometry or WKB; None (a null geometry) stays None."""
    if geometry is None or isinstance(geometry, _BINARY):
        return None if geometry is None else bytes(geometry)
    wkb = getattr(geometry, "wkb", None)
    if wkb is None:
        raise TypeError(
            f"expected a shapely geometry or WKB bytes, got {type(geometry).__name__}")
    return wkb


def is_wkb(geometry):
    return isinstance(geometry, _BINARY)


def from_wkb(wkb, as_shapely):
    """`wkb` as a shapely geometry when `as_shapely`, else as the bytes."""
    if not as_shapely:
        return wkb
    import shapely.wkb

    return shapely.wkb.loads(wkb)


def box(region):
    """A (west, south, east, north) box given as four numbers, or None for a geometry."""
    if region is None or is_wkb(region) or hasattr(region, "wkb"):
        return None
    box = tuple(float(v) for v in region)
    if len(box) != 4:
        raise TypeError(f"a box is four numbers (west, south, east, north), got {len(box)}")
    return box
