#!/usr/bin/env python3
"""Generated layers for benchmarks and quality runs: what the shared layers do not show.

    make-test-layers.py voronoi N SEED OUT.gpkg     random Voronoi cells (a tessellation like
                                                    administrative regions), N regions
    make-test-layers.py islands SEED OUT.gpkg       three far-apart landmasses of Voronoi cells,
                                                    each with a few islands off its coast
    make-test-layers.py archipelago N ISLANDS SEED OUT.gpkg
                                                    a mainland of N Voronoi cells and ISLANDS
                                                    one-region islands scattered round it
    make-test-layers.py isles COUNT N SEED OUT.gpkg COUNT round islands scattered over the
                                                    square, each of N Voronoi cells (an island
                                                    nation's municipalities: many landmasses
                                                    that count for the wrong-landmass share)
    make-test-layers.py river N SEED OUT.gpkg       Voronoi cells cut by a river-like gap, the
                                                    outline's two banks close together
    make-test-layers.py strip N SEED OUT.gpkg       a long thin country (Chile, Norway, Vietnam):
                                                    Voronoi cells of a tilted strip 0.7 cells
                                                    wide, N regions
    make-test-layers.py ring N WIDTH SEED OUT.gpkg  a country round a lake (or an atoll): Voronoi
                                                    cells of a ring WIDTH cells wide, N regions
    make-test-layers.py apart SRC CELLS OUT.gpkg    SRC with every region narrowed by CELLS cells
                                                    (a cell: the square root of the mean region
                                                    area), so that neighbours stand 2 x CELLS
                                                    apart: regions drawn or simplified one by one;
                                                    a negative CELLS widens them, so that
                                                    neighbours overlap along their borders
    make-test-layers.py simplify SRC CELLS OUT.gpkg SRC with every region simplified alone by
                                                    CELLS cells (Douglas-Peucker), as ogr2ogr
                                                    -simplify does: slivers between neighbours
    make-test-layers.py provinces SRC N SEED OUT.gpkg
                                                    SRC with every region cut into Voronoi
                                                    cells, about N in all, each region's share
                                                    following the square root of its area
                                                    (small countries cut finer for their size,
                                                    as administrative layers are): borders
                                                    shared exactly, densities far apart
    make-test-layers.py densify SRC VERTICES OUT.gpkg
                                                    SRC with every edge subdivided, to about
                                                    VERTICES vertices in all, with a small wiggle
                                                    that both neighbours of a shared edge share
                                                    (so adjacency is kept exactly)
    make-test-layers.py star VERTICES OUT.gpkg      one region: a star with VERTICES vertices
    make-test-layers.py square VERTICES OUT.gpkg    one region: a square densified to VERTICES

Every layer is a GeoPackage with one layer named like the file and a text field `id`, in
EPSG:3857 (metres) for the generated ones and in the source's CRS for those made from SRC. The
same arguments give the same file. Needs shapely, numpy, pyogrio and pyproj.
"""

import math
import os
import sys

import numpy as np
import pyogrio.raw
import pyproj
import shapely
import shapely.affinity

SIDE = 1_000_000.0  # metres: the square the generated layers fill


def write(path, ids, geometries, crs="EPSG:3857"):
    """A GeoPackage of `geometries` (shapely) with ids, one layer named like the file."""
    if os.path.exists(path):
        os.remove(path)
    layer = os.path.splitext(os.path.basename(path))[0]
    multi = [g if g.geom_type == "MultiPolygon" else shapely.MultiPolygon([g]) for g in geometries]
    pyogrio.raw.write(
        path,
        geometry=shapely.to_wkb(np.array(multi, dtype=object)),
        field_data=[np.array(ids, dtype=object)],
        fields=["id"],
        crs=crs,
        layer=layer,
        driver="GPKG",
        geometry_type="MultiPolygon",
        # GeoPackage 1.3, which every GDAL since 3.0 reads without a warning.
        dataset_options={"VERSION": "1.3"},
    )


def random_points(rng, n, frame):
    """`n` points spread over `frame`, at least a hundredth of the mean spacing apart."""
    minx, miny, maxx, maxy = frame.bounds
    gap = 0.01 * math.sqrt(frame.area / n)
    points = []
    while len(points) < n:
        x, y = rng.uniform(minx, maxx), rng.uniform(miny, maxy)
        if frame.contains(shapely.Point(x, y)) and all(
            abs(x - px) > gap or abs(y - py) > gap for px, py in points[-50:]
        ):
            points.append((x, y))
    return points


def voronoi(n, seed):
    rng = np.random.default_rng(seed)
    frame = shapely.box(0, 0, SIDE, SIDE)
    cells = voronoi_tiles(random_points(rng, n, frame), frame)
    return [f"v{k}" for k in range(n)], cells


def voronoi_tiles(points, frame):
    """Voronoi cells of many points: shapely's diagram at once, matched to points by an index."""
    diagram = shapely.voronoi_polygons(shapely.MultiPoint(points), extend_to=frame)
    polygons = list(diagram.geoms)
    tree = shapely.STRtree(polygons)
    cells = [None] * len(points)
    for k, p in enumerate(points):
        for j in tree.query(shapely.Point(p), predicate="intersects"):
            cells[k] = polygons[j].intersection(frame)
            break
    return cells


def islands(seed):
    """Three landmasses far apart (60, 30 and 12 regions), each with islands off its coast."""
    rng = np.random.default_rng(seed)
    ids, geometries = [], []
    for land, (count, x0, y0, size) in enumerate(
        [(60, 0, 0, 600_000), (30, 2_000_000, 300_000, 400_000), (12, 900_000, 1_800_000, 250_000)]
    ):
        frame = shapely.Point(x0 + size / 2, y0 + size / 2).buffer(size / 2, quad_segs=16)
        cells = voronoi_tiles(random_points(rng, count, frame), frame)
        for k, cell in enumerate(cells):
            ids.append(f"l{land}_{k}")
            geometries.append(cell)
        for k in range(3):
            angle = rng.uniform(0, 2 * math.pi)
            distance = size * rng.uniform(0.6, 0.8)
            cx = x0 + size / 2 + distance * math.cos(angle)
            cy = y0 + size / 2 + distance * math.sin(angle)
            ids.append(f"l{land}_island{k}")
            geometries.append(shapely.Point(cx, cy).buffer(size * 0.04, quad_segs=8))
    return ids, geometries


def archipelago(n, count, seed):
    """A mainland of n Voronoi cells in the middle of the square and `count` small round
    islands of one region each, scattered over the rest of it (an island nation's districts)."""
    rng = np.random.default_rng(seed)
    land = shapely.Point(SIDE / 2, SIDE / 2).buffer(SIDE * 0.3, quad_segs=32)
    ids, geometries = [], []
    for k, cell in enumerate(voronoi_tiles(random_points(rng, n, land), land)):
        ids.append(f"m{k}")
        geometries.append(cell)
    radius = SIDE * 0.3 / math.sqrt(n) / 2  # half a mainland region's size
    placed = [land.buffer(2 * radius)]
    # Islands sized after a mainland of few regions fill the square after a few dozen; a
    # thousand draws in a row with no room mean it is full.
    misses = 0
    while len(ids) < n + count:
        if misses > 1000:
            sys.exit(
                f"archipelago: only {len(ids) - n} of {count} islands, each half the size of one "
                f"of {n} mainland regions, fit around it; ask for fewer islands or more regions"
            )
        misses += 1
        p = shapely.Point(rng.uniform(0, SIDE), rng.uniform(0, SIDE))
        island = p.buffer(radius, quad_segs=8)
        if not any(g.intersects(island.buffer(radius)) for g in placed):
            misses = 0
            placed.append(island)
            ids.append(f"i{len(ids) - n}")
            geometries.append(island)
    return ids, geometries


def isles(count, n, seed):
    """`count` round islands on a jittered grid over the square, none touching another, each
    cut into `n` Voronoi cells."""
    rng = np.random.default_rng(seed)
    side = math.ceil(math.sqrt(count))
    pitch = SIDE / side
    ids, geometries = [], []
    for k in range(count):
        cx = (k % side + 0.5 + rng.uniform(-0.2, 0.2)) * pitch
        cy = (k // side + 0.5 + rng.uniform(-0.2, 0.2)) * pitch
        island = shapely.Point(cx, cy).buffer(pitch * rng.uniform(0.15, 0.3), quad_segs=8)
        for j, cell in enumerate(voronoi_tiles(random_points(rng, n, island), island)):
            ids.append(f"i{k}_{j}")
            geometries.append(cell)
    return ids, geometries


def river(n, seed):
    """Voronoi cells with a winding gap through the middle (a river of a fiftieth of the side)."""
    rng = np.random.default_rng(seed)
    frame = shapely.box(0, 0, SIDE, SIDE)
    xs = np.linspace(-SIDE * 0.05, SIDE * 1.05, 200)
    course = shapely.LineString(
        [(x, SIDE / 2 + SIDE * 0.15 * math.sin(3 * math.pi * x / SIDE)) for x in xs]
    )
    land = frame.difference(course.buffer(SIDE / 100))
    cells = voronoi_tiles(random_points(rng, n, land), frame)
    pieces = []
    for cell in cells:
        piece = cell.intersection(land)
        # A cell the river cuts keeps its larger side: each region is one piece of land.
        if piece.geom_type == "MultiPolygon":
            piece = max(piece.geoms, key=lambda g: g.area)
        pieces.append(piece)
    return [f"r{k}" for k in range(n)], pieces


def strip(n, seed):
    """Voronoi cells of a strip tilted 15 degrees, SIDE long and SIDE / (2n) wide: a cell of the
    layout (area / n) has sides of 0.71 SIDE / n, so the strip is 0.7 cells wide. Convex, so
    every clipped cell is one piece."""
    rng = np.random.default_rng(seed)
    width = SIDE / (2 * n)
    land = shapely.affinity.rotate(shapely.box(-width / 2, 0, width / 2, SIDE), 15, origin=(0, 0))
    cells = voronoi_tiles(random_points(rng, n, land), land)
    return [f"s{k}" for k in range(n)], cells


def ring(n, width, seed):
    """Voronoi cells of a ring of radius SIDE / 2, `width` cells wide (a cell: the ring's area
    / n). Its points are drawn in polar coordinates, evenly over the ring's middle nine tenths
    across."""
    rng = np.random.default_rng(seed)
    radius = SIDE / 2
    # The ring's area 2πR·w holds n cells of side w / width.
    w = 2 * math.pi * radius * width**2 / n
    land = shapely.Point(0, 0).buffer(radius + w / 2, 4096).difference(
        shapely.Point(0, 0).buffer(radius - w / 2, 4096)
    )
    angle = rng.uniform(0, 2 * math.pi, n)
    r = np.sqrt(rng.uniform((radius - 0.45 * w) ** 2, (radius + 0.45 * w) ** 2, n))
    points = list(zip(r * np.cos(angle), r * np.sin(angle)))
    return [f"g{k}" for k in range(n)], voronoi_tiles(points, land)


def wiggled(a, b, pieces, straight):
    """The points between `a` and `b` (exclusive) on a wiggle that depends only on the segment,
    not on its direction: both regions beside a shared edge get the same vertices. A segment
    `straight` tells apart is only cut up."""
    if (a[0], a[1]) > (b[0], b[1]):
        return wiggled(b, a, pieces, straight)[::-1]
    (ax, ay), (bx, by) = a, b
    length = math.hypot(bx - ax, by - ay)
    if length == 0:
        return []
    nx, ny = -(by - ay) / length, (bx - ax) / length
    amplitude = 0.0 if straight(a, b) else 0.02 * length
    out = []
    for k in range(1, pieces):
        t = k / pieces
        w = amplitude * math.sin(math.pi * t) * math.sin(7 * math.pi * t)
        out.append((ax + t * (bx - ax) + w * nx, ay + t * (by - ay) + w * ny))
    return out


def densify_ring(coords, pieces, straight):
    coords = list(coords)
    out = []
    for a, b in zip(coords[:-1], coords[1:]):
        out.append(a)
        out.extend(wiggled(a, b, pieces, straight))
    out.append(coords[-1])
    return out


def densify_polygon(polygon, pieces, straight):
    return shapely.Polygon(
        densify_ring(polygon.exterior.coords, pieces, straight),
        [densify_ring(r.coords, pieces, straight) for r in polygon.interiors],
    )


def on_the_world_edge(a, b):
    """Whether a segment in longitude and latitude runs along the antimeridian or a pole's
    parallel: wiggled, it would leave the world."""
    near = lambda v, edge: abs(abs(v) - edge) < 1e-3  # a projected layer's edge, 4326 again
    return any(near(a[k], e) and near(b[k], e) for k, e in ((0, 180.0), (1, 90.0)))


def densify(src, vertices):
    info = pyogrio.read_info(src)
    _, _, wkb, fields = pyogrio.raw.read(src, columns=["id"])
    geometries = list(shapely.from_wkb(wkb))
    have = sum(shapely.get_num_coordinates(g) for g in geometries)
    pieces = max(1, round(vertices / have))
    geographic = info["crs"] is not None and pyproj.CRS(info["crs"]).is_geographic
    straight = on_the_world_edge if geographic else (lambda a, b: False)
    out = []
    for g in geometries:
        parts = g.geoms if g.geom_type == "MultiPolygon" else [g]
        out.append(shapely.MultiPolygon([densify_polygon(p, pieces, straight) for p in parts]))
    return [str(v) for v in fields[0]], out, info["crs"]


def apart(src, cells):
    info = pyogrio.read_info(src)
    _, _, wkb, fields = pyogrio.raw.read(src, columns=["id"])
    geometries = shapely.from_wkb(wkb)
    cell = math.sqrt(shapely.area(geometries).sum() / len(geometries))
    narrowed = shapely.buffer(geometries, -cells * cell, join_style="mitre")
    return [str(v) for v in fields[0]], list(narrowed), info["crs"]


def simplified(src, cells):
    """SRC with every region simplified alone (Douglas-Peucker, CELLS cells, each ring kept
    simple, so that no small region vanishes), as `ogr2ogr -simplify` does: slivers open between
    neighbours and their borders overlap."""
    info = pyogrio.read_info(src)
    _, _, wkb, fields = pyogrio.raw.read(src, columns=["id"])
    geometries = shapely.from_wkb(wkb)
    cell = math.sqrt(shapely.area(geometries).sum() / len(geometries))
    simple = shapely.simplify(geometries, cells * cell, preserve_topology=True)
    return [str(v) for v in fields[0]], list(simple), info["crs"]


def provinces(src, n, seed):
    rng = np.random.default_rng(seed)
    info = pyogrio.read_info(src)
    _, _, wkb, fields = pyogrio.raw.read(src, columns=["id"])
    geometries = shapely.from_wkb(wkb)
    weights = np.sqrt(shapely.area(geometries))
    counts = np.maximum(1, np.round(n * weights / weights.sum())).astype(int)
    ids, cells = [], []
    for region, geometry, count in zip(fields[0], geometries, counts):
        shapely.prepare(geometry)
        tiles = [geometry] if count == 1 else voronoi_tiles(
            random_points(rng, count, geometry), geometry
        )
        for k, tile in enumerate(tiles):
            parts = [g for g in shapely.get_parts(tile) if g.geom_type == "Polygon"]
            ids.append(f"{region}_{k}")
            cells.append(shapely.MultiPolygon(parts))
    return ids, cells, info["crs"]


def star(vertices):
    t = np.linspace(0, 2 * math.pi, vertices, endpoint=False)
    r = SIDE * (0.5 + 0.4 * np.where(np.arange(vertices) % 2 == 0, 1.0, 0.2))
    return shapely.Polygon(np.column_stack([r * np.cos(t), r * np.sin(t)]))


def square(vertices):
    per_side = max(1, vertices // 4)
    t = np.linspace(0, SIDE, per_side, endpoint=False)
    z, one = np.zeros(per_side), np.full(per_side, SIDE)
    ring = np.concatenate(
        [np.column_stack(c) for c in [(t, z), (one, t), (SIDE - t, one), (z, SIDE - t)]]
    )
    return shapely.Polygon(ring)


def main(argv):
    kind, args = argv[1], argv[2:]
    if kind == "voronoi":
        ids, geometries = voronoi(int(args[0]), int(args[1]))
        write(args[2], ids, geometries)
    elif kind == "islands":
        ids, geometries = islands(int(args[0]))
        write(args[1], ids, geometries)
    elif kind == "archipelago":
        ids, geometries = archipelago(int(args[0]), int(args[1]), int(args[2]))
        write(args[3], ids, geometries)
    elif kind == "isles":
        ids, geometries = isles(int(args[0]), int(args[1]), int(args[2]))
        write(args[3], ids, geometries)
    elif kind == "river":
        ids, geometries = river(int(args[0]), int(args[1]))
        write(args[2], ids, geometries)
    elif kind == "strip":
        ids, geometries = strip(int(args[0]), int(args[1]))
        write(args[2], ids, geometries)
    elif kind == "ring":
        ids, geometries = ring(int(args[0]), float(args[1]), int(args[2]))
        write(args[3], ids, geometries)
    elif kind == "apart":
        ids, geometries, crs = apart(args[0], float(args[1]))
        write(args[2], ids, geometries, crs)
    elif kind == "simplify":
        ids, geometries, crs = simplified(args[0], float(args[1]))
        write(args[2], ids, geometries, crs)
    elif kind == "provinces":
        ids, geometries, crs = provinces(args[0], int(args[1]), int(args[2]))
        write(args[3], ids, geometries, crs)
    elif kind == "densify":
        ids, geometries, crs = densify(args[0], int(float(args[1])))
        write(args[2], ids, geometries, crs)
    elif kind in ("star", "square"):
        shape = star if kind == "star" else square
        write(args[1], ["one"], [shape(int(float(args[0])))])
    else:
        sys.exit(__doc__)


if __name__ == "__main__":
    main(sys.argv)
