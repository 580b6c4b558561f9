#!/usr/bin/python3
"""Writes the corpus of bad and awkward inputs in tests/data/bad/ and its manifest, cases.tsv.

Each case is one small layer (GeoJSON, written as text so NaN, unclosed rings and the like
survive exactly; one Shapefile for non-UTF-8 text) and one manifest line:

    file <TAB> id field <TAB> ok|error <TAB> text the message (error) or a note (ok) must hold

("-" when there is no id field or nothing to check). tests/bad_inputs.rs and
tests/c/test_bad_inputs.c run every line through the library, the command line and the C API.
The comments beside each case here (and the `why` comments in cases.tsv) say why it has the
outcome it has.

Usage: /usr/bin/python3 scripts/make-bad-inputs.py   (needs python3-gdal, for the Shapefile)
"""

import json
import math
import os
import shutil

from osgeo import ogr, osr

OUT = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "tests", "data", "bad")
UTM33 = "urn:ogc:def:crs:EPSG::32633"


def square(x, y, side):
    return [[[x, y], [x + side, y], [x + side, y + side], [x, y + side], [x, y]]]


def block(nx, ny, side=1000.0, x0=500000.0, y0=5000000.0, prefix="r"):
    """nx × ny touching squares named r00, r01, … row by row."""
    return [
        feature(f"{prefix}{j}{i}", "Polygon", square(x0 + i * side, y0 + j * side, side))
        for j in range(ny)
        for i in range(nx)
    ]


def feature(code, kind, coordinates, **properties):
    geometry = None if kind is None else {"type": kind, "coordinates": coordinates}
    return {
        "type": "Feature",
        "properties": {"code": code, "name": f"region {code}", **properties},
        "geometry": geometry,
    }


def geojson(name, features, crs=UTM33):
    """GDAL takes a GeoJSON file without "crs" for WGS 84, so planar layers name theirs."""
    layer = {"type": "FeatureCollection", "name": name.split(".")[0], "features": features}
    if crs:
        layer["crs"] = {"type": "name", "properties": {"name": crs}}
    # allow_nan writes NaN and Infinity, which GDAL's GeoJSON reader accepts.
    with open(os.path.join(OUT, name), "w", encoding="utf-8") as f:
        json.dump(layer, f, allow_nan=True, indent=None, separators=(",", ":"))
        f.write("\n")


def non_utf8_shapefile(name):
    """A Shapefile whose .cpg says UTF-8 but whose names are Latin-1, so GDAL hands the bytes
    over unchanged: the invalid UTF-8 a mislabelled file gives."""
    path = os.path.join(OUT, name)
    driver = ogr.GetDriverByName("ESRI Shapefile")
    if os.path.exists(path):
        driver.DeleteDataSource(path)
    srs = osr.SpatialReference()
    srs.ImportFromEPSG(32633)
    source = driver.CreateDataSource(path)
    layer = source.CreateLayer(name[:-4], srs, ogr.wkbPolygon, options=["ENCODING=UTF-8"])
    for field in ("code", "name"):
        layer.CreateField(ogr.FieldDefn(field, ogr.OFTString))
    for f in block(3, 2):
        out = ogr.Feature(layer.GetLayerDefn())
        out.SetField("code", f["properties"]["code"])
        out.SetField("name", "Zurich " + f["properties"]["code"])
        out.SetGeometry(ogr.CreateGeometryFromJson(json.dumps(f["geometry"])))
        layer.CreateFeature(out)
    source = None
    dbf = path[:-4] + ".dbf"
    with open(dbf, "rb") as f:
        data = f.read()
    # Same length, so the .dbf stays well formed: "ü" as the single Latin-1 byte 0xFC.
    data = data.replace(b"Zurich r00", b"Z\xfcrich r00").replace(b"Zurich", b"Z\xfcrich")
    with open(dbf, "wb") as f:
        f.write(data)


def main():
    if os.path.isdir(OUT):
        shutil.rmtree(OUT)
    os.makedirs(OUT)
    cases = []

    def case(file, expect, text, id_field="code", why=None):
        """`why`, where the text holds a hand count, goes above the line as a comment."""
        if why:
            cases.append(("# " + why,))
        cases.append((file, id_field, expect, text))

    # GeoJSON keeps no schema without features, so no -id field either.
    geojson("empty_layer.geojson", [])
    case("empty_layer.geojson", "invalid_input", "the source layer has no features", id_field="-")

    geojson("points.geojson", [feature("p1", "Point", [500000, 5000000]), feature("p2", "Point", [501000, 5000000])])
    case("points.geojson", "invalid_input", "feature p1: the geometry is a POINT")

    geojson("lines.geojson", [feature("l1", "LineString", [[500000, 5000000], [501000, 5000000]])] + block(2, 1))
    case("lines.geojson", "invalid_input", "feature l1: the geometry is a LINESTRING")

    # A region drawn in two parts as a collection (some tools write one): its polygons are the
    # region. A collection that also holds a line is not a region.
    halves = [square(502000, 5000000 + k * 500, 500) for k in range(2)]
    parts = {"type": "GeometryCollection", "geometries": [{"type": "Polygon", "coordinates": h} for h in halves]}
    geojson("collection.geojson", block(2, 1) + [dict(feature("parts", None, None), geometry=parts)])
    case("collection.geojson", "ok", "-")
    line = {"type": "LineString", "coordinates": [[502000, 5000000], [503000, 5001000]]}
    mixed = {"type": "GeometryCollection", "geometries": [parts["geometries"][0], line]}
    geojson("mixed_collection.geojson", block(2, 1) + [dict(feature("mixed", None, None), geometry=mixed)])
    case("mixed_collection.geojson", "invalid_input", "feature mixed: the geometry is a GEOMETRYCOLLECTION that holds more than polygons")

    geojson("null_geometry.geojson", block(2, 2) + [feature("nothing", None, None)])
    case("null_geometry.geojson", "invalid_input", "feature nothing: the geometry is null")

    # GDAL reads a GeoJSON polygon without coordinates as no geometry at all.
    geojson("empty_geometry.geojson", block(2, 2) + [feature("hollow", "Polygon", [])])
    case("empty_geometry.geojson", "invalid_input", "feature hollow: the geometry is null")

    # A bow-tie: the ring crosses itself in the middle; repaired into its two triangles.
    x, y = 502000.0, 5000000.0
    bowtie = [[[x, y], [x + 1000, y + 1000], [x + 1000, y], [x, y + 1000], [x, y]]]
    geojson("bowtie.geojson", block(2, 1) + [feature("bowtie", "Polygon", bowtie)])
    case("bowtie.geojson", "ok", "feature bowtie: invalid polygon repaired")

    # The ring's last point is not its first: closed on reading, as every GIS does.
    open_ring = [square(502000, 5000000, 1000)[0][:-1]]
    geojson("unclosed_ring.geojson", block(2, 1) + [feature("open", "Polygon", open_ring)])
    case("unclosed_ring.geojson", "ok", "-")

    # Two distinct points: no area, whatever closes it.
    short = [[[502000, 5000000], [503000, 5000000], [502000, 5000000]]]
    geojson("short_ring.geojson", block(2, 1) + [feature("short", "Polygon", short)])
    case("short_ring.geojson", "invalid_input", "feature short:")

    dup = square(502000, 5000000, 1000)[0]
    dup = [dup[0], dup[1], dup[1], dup[1], dup[2], dup[3], dup[3], dup[4]]
    geojson("duplicate_vertices.geojson", block(2, 1) + [feature("stutter", "Polygon", [dup])])
    case("duplicate_vertices.geojson", "ok", "-")

    # A region that is a line traced there and back: zero area, nothing to repair.
    sliver = [[[502000, 5000000], [503000, 5000000], [504000, 5000000], [502000, 5000000]]]
    geojson("zero_area_sliver.geojson", block(2, 1) + [feature("sliver", "Polygon", sliver)])
    case("zero_area_sliver.geojson", "invalid_input", "feature sliver:")

    # A good square with a zero-width spike: repaired to the square.
    spiked = [[[502000, 5000000], [503000, 5000000], [503000, 5000500], [504000, 5000500],
               [503000, 5000500], [503000, 5001000], [502000, 5001000], [502000, 5000000]]]
    geojson("spike.geojson", block(2, 1) + [feature("spiked", "Polygon", spiked)])
    case("spike.geojson", "ok", "feature spiked: invalid polygon repaired")

    # Each of a row of squares overlaps the next by a fifth.
    overlapping = [feature(f"o{i}", "Polygon", square(500000 + 800 * i, 5000000, 1000)) for i in range(4)]
    geojson("overlapping.geojson", overlapping)
    case("overlapping.geojson", "ok", "regions overlap: 15.0 %",
         why="four 1 km squares, each overlapping the next by 0.2 km²: 0.6 of 4 km² counted twice")

    dupes = block(2, 2)
    dupes[3]["properties"]["code"] = "r00"
    geojson("duplicate_ids.geojson", dupes)
    case("duplicate_ids.geojson", "invalid_input", "feature r00: the id is not unique")

    nulls = block(2, 2)
    nulls[2]["properties"]["code"] = None
    geojson("null_ids.geojson", nulls)
    case("null_ids.geojson", "invalid_input", "feature FID 2: the id is null")

    geojson("one_region.geojson", block(1, 1))
    case("one_region.geojson", "ok", "-")

    geojson("two_regions.geojson", block(2, 1))
    case("two_regions.geojson", "ok", "-")

    islands = [feature(f"i{j}{i}", "Polygon", square(500000 + 3000 * i, 5000000 + 3000 * j, 1000))
               for j in range(3) for i in range(3)]
    geojson("all_islands.geojson", islands)
    case("all_islands.geojson", "ok", "-")

    # A 3 × 3 block whose middle is a hole of the ring around it, filled by its own region.
    outer = square(500000, 5000000, 3000)[0]
    hole = square(501000, 5001000, 1000)[0][::-1]
    geojson("enclave.geojson", [
        feature("ring", "Polygon", [outer, hole]),
        feature("enclave", "Polygon", square(501000, 5001000, 1000)),
        feature("east", "Polygon", square(503000, 5000000, 3000)),
    ])
    case("enclave.geojson", "ok", "-")

    geojson("large_coordinates.geojson", block(3, 3, side=100.0, x0=1.0e7, y0=1.0e7))
    case("large_coordinates.geojson", "ok", "-")

    geojson("small_coordinates.geojson", block(3, 3, side=1.0e-4, x0=1.0e-3, y0=1.0e-3))
    case("small_coordinates.geojson", "ok", "-")

    # Longitude/latitude squares from 176°E to 176°W, written as GeoJSON wants them (-180..180),
    # so the layer's bounding box spans the whole world.
    antimeridian = []
    for j in range(2):
        for i in range(4):
            lon = 176.0 + 2.0 * i
            lon = lon - 360.0 if lon >= 180.0 else lon
            antimeridian.append(feature(f"a{j}{i}", "Polygon", square(lon, -20.0 + 2.0 * j, 2.0)))
    geojson("antimeridian.geojson", antimeridian, crs="urn:ogc:def:crs:OGC:1.3:CRS84")
    case("antimeridian.geojson", "ok", "-")

    # The same across ±180° as d3's world-atlas draws Russia and Fiji: the middle column's
    # rings step from 178.5 to -178.5, so each of those regions' own box spans the world.
    def wrapped(lon):
        return lon - 360.0 if lon > 180.0 else lon

    stepping = []
    for j in range(2):
        for i in range(3):
            west, south = 175.5 + 3.0 * i, -20.0 + 3.0 * j
            ring = [[wrapped(west + dx), south + dy]
                    for dx, dy in ((0, 0), (3, 0), (3, 3), (0, 3), (0, 0))]
            stepping.append(feature(f"s{j}{i}", "Polygon", [ring]))
    geojson("antimeridian_stepping.geojson", stepping, crs="urn:ogc:def:crs:OGC:1.3:CRS84")
    case("antimeridian_stepping.geojson", "ok", "-")

    nan = square(502000, 5000000, 1000)
    nan[0][2] = [math.nan, 5001000]
    geojson("nan_coordinate.geojson", block(2, 1) + [feature("nan", "Polygon", nan)])
    case("nan_coordinate.geojson", "invalid_input", "feature nan: the geometry has a NaN or infinite coordinate")

    inf = square(502000, 5000000, 1000)
    inf[0][1] = [math.inf, 5000000]
    geojson("infinite_coordinate.geojson", block(2, 1) + [feature("inf", "Polygon", inf)])
    case("infinite_coordinate.geojson", "invalid_input", "feature inf: the geometry has a NaN or infinite coordinate")

    # Finite, but its square overflows: the areas would be infinite.
    huge = square(502000, 5000000, 1000)
    huge[0][2] = [1.0e300, 5001000]
    geojson("huge_coordinate.geojson", block(2, 1) + [feature("huge", "Polygon", huge)])
    case("huge_coordinate.geojson", "invalid_input", "feature huge: a coordinate (1.0e300) is beyond ±1e100")

    non_utf8_shapefile("non_utf8.shp")
    case("non_utf8.shp", "ok", "-")

    geojson("three_in_a_line.geojson", block(3, 1))
    case("three_in_a_line.geojson", "ok", "-")

    # A curved polygon beside a straight one, taken with its arcs linearised: GeoJSON holds no
    # curves, GDAL's CSV reader takes them as WKT.
    with open(os.path.join(OUT, "curved.csv"), "w", encoding="utf-8") as f:
        f.write('id,WKT\na,"CURVEPOLYGON(CIRCULARSTRING(0 0,1 1,2 0,1 -1,0 0))"\n'
                'b,"POLYGON((2 0,3 0,3 1,2 1,2 0))"\n')
    case("curved.csv", "ok", "feature a: curved geometry (CURVEPOLYGON) linearised", id_field="id")

    # A feature drawn over another.
    stacked = [feature(f"s{i}", "Polygon", square(500000 + 1000 * i, 5000000, 1000)) for i in range(2)] + [
        feature("s2", "Polygon", [[[500200, 5000200], [500800, 5000200], [500800, 5000800],
                                   [500200, 5000800], [500200, 5000200]]])]
    geojson("stacked.geojson", stacked)
    case("stacked.geojson", "ok",
         'regions overlap: 15.3 % of their total area is covered more than once ("s2" lies on "s0")',
         why="a feature drawn over another: 0.36 km² of 2.36 km² counted twice (15.3 %)")

    # A 2 × 2 block whose first square is drawn 30 more times: each of the 31 copies lies on
    # the 30 others and along r01 and r10.
    copies = block(2, 2) + [feature(f"c{k:02}", "Polygon", square(500000, 5000000, 1000))
                            for k in range(30)]
    geojson("stacked_many.geojson", copies)
    case("stacked_many.geojson", "invalid_input",
         "feature r00: 32 regions lie on it or along its border",
         why="a square drawn 31 times in a 2 × 2 block: 465 pairs among the copies, 62 with r01 "
             "and r10, 2 more in the block: 529 pairs, 31 neighbours per region on average "
             "(over 24); each copy has 32, r00 is the first")

    # A 3 × 3 block of 1 km squares drawn apart: each narrowed by 2 m, so neighbours stand 4 m
    # (a 250th of a cell) apart and share no border.
    apart = [feature(f"a{j}{i}", "Polygon",
                     square(500000 + 1000 * i + 2, 5000000 + 1000 * j + 2, 996))
             for j in range(3) for i in range(3)]
    geojson("apart.geojson", apart)
    case("apart.geojson", "ok", "borders not shared exactly: 12 pair(s) of regions share no border",
         why="a 3 × 3 block a hairline apart: its 12 rook pairs face each other across the gaps")

    # A 3 × 3 block of quadrilaterals (a lattice of 1 km with every vertex moved by up to 80 m,
    # so that no two borders are parallel) drawn over each other's borders: each widened by
    # 2 m, so neighbours overlap by 4 m along their borders and share none exactly.
    def corner(i, j):
        return [500000 + 1000 * i + 80 * math.sin(3.1 * i + 1.7 * j),
                5000000 + 1000 * j + 80 * math.cos(2.3 * i + 4.1 * j)]
    over = []
    for j in range(3):
        for i in range(3):
            ring = [corner(i, j), corner(i + 1, j), corner(i + 1, j + 1), corner(i, j + 1),
                    corner(i, j)]
            widened = ogr.CreateGeometryFromJson(
                json.dumps({"type": "Polygon", "coordinates": [ring]})).Buffer(2.0, 2)
            over.append(feature(f"w{j}{i}", "Polygon",
                                json.loads(widened.ExportToJson())["coordinates"]))
    geojson("over.geojson", over)
    case("over.geojson", "ok", "borders not shared exactly: 12 pair(s) of regions share no border",
         why="a 3 × 3 block overlapping by a hairline: its 12 rook pairs run along each other")

    with open(os.path.join(OUT, "cases.tsv"), "w", encoding="utf-8") as f:
        f.write("# file\tid field\texpected (ok, or the kind of error: invalid_input, io_error)\ttext the error message or a note must hold (- for none)\n")
        for c in cases:
            f.write("\t".join(c) + "\n")


if __name__ == "__main__":
    main()
