#!/usr/bin/env python3
"""Checks that d3-hexjson draws a HexJSON file's hexes where a grid layer has its cells.

    check-hexjson-centres.py CENTRES.json GRID.gpkg KEYFIELD [LAYER]

CENTRES.json is what tests/hexjson/centres.mjs prints ({key: [x, y]}, SVG pixels, y down);
GRID.gpkg has one polygon per hex whose KEYFIELD matches the HexJSON keys. The pixel centres
must map onto the polygons' centroids by ONE similarity transform (scale, rotation, translation)
composed with the reflection y -> -y that SVG's downward y needs against a map's upward y: a
proper rotation alone would only fit a mirror image, i.e. rows numbered the wrong way. Fitted
by least squares (in complex numbers: centroid ~ a * conj(pixel) + b); every residual must be
under 1e-6 cell sizes, the cell size being the square root of the median cell area. Exits 1
with the worst hexes listed when they are not. Needs numpy, shapely and pyogrio.
"""

import json
import sys

import numpy as np
import pyogrio.raw
import shapely

TOLERANCE = 1e-6  # in cell sizes


def fit(source, target):
    """Least-squares a, b of target ~ a * source + b (complex arrays); returns a, residuals."""
    s, t = source - source.mean(), target - target.mean()
    a = np.vdot(s, t) / np.vdot(s, s).real  # vdot conjugates its first argument
    return a, np.abs(t - a * s)


def main(argv):
    if len(argv) not in (4, 5):
        sys.exit(__doc__.split("\n\n")[1])
    centres_file, grid, key_field = argv[1:4]
    layer = argv[4] if len(argv) == 5 else None
    with open(centres_file, encoding="utf-8") as f:
        centres = json.load(f)

    fields = list(pyogrio.read_info(grid, layer=layer)["fields"])
    if key_field not in fields:
        sys.exit(f"{grid}: no field {key_field!r} (it has {', '.join(fields) or 'none'})")
    _, _, wkb, values = pyogrio.raw.read(grid, layer=layer, columns=[key_field])
    keys = [str(k) for k in values[0]]
    polygons = shapely.from_wkb(wkb)
    if len(set(keys)) != len(keys):
        sys.exit(f"{grid}: the values of {key_field} are not unique")
    missing = sorted(set(keys) - set(centres))
    extra = sorted(set(centres) - set(keys))
    if missing or extra:
        sys.exit(
            f"the keys differ: {len(missing)} in the layer only {missing[:5]}, "
            f"{len(extra)} in the HexJSON only {extra[:5]}"
        )
    if len(keys) < 3:
        sys.exit(f"only {len(keys)} hexes: too few to check a layout")

    xy = shapely.get_coordinates(shapely.centroid(polygons))
    target = xy[:, 0] + 1j * xy[:, 1]
    pixels = np.array([centres[k] for k in keys], dtype=float)
    source = pixels[:, 0] + 1j * pixels[:, 1]
    if np.ptp(pixels[:, 0]) == 0 and np.ptp(pixels[:, 1]) == 0:
        sys.exit("d3-hexjson drew every hex at one point: is the layout one it knows?")
    cell = float(np.sqrt(np.median(shapely.area(polygons))))

    a, residuals = fit(np.conj(source), target)  # the reflection, then a similarity
    worst = residuals.max() / cell
    print(
        f"{len(keys)} hexes; fit: scale {abs(a):.9g} map units per pixel, rotation "
        f"{np.degrees(np.angle(a)):.6f} deg (after y -> -y); largest residual {worst:.3g} cells"
    )
    if worst < TOLERANCE:
        print("OK: d3-hexjson's centres match the layer's cells")
        return 0

    print(
        f"MISMATCH: d3-hexjson does not draw the hexes where the layer has them "
        f"(largest residual {worst:.3g} cells, tolerance {TOLERANCE:g})",
        file=sys.stderr,
    )
    for i in np.argsort(-residuals)[:5]:
        print(f"  {keys[i]}: {residuals[i] / cell:.4f} cells off", file=sys.stderr)
    _, mirrored = fit(source, target)
    if mirrored.max() / cell < TOLERANCE:
        print("  (it matches the mirror image: r is counted the wrong way)", file=sys.stderr)
    else:
        print(
            "  (a wrong odd/even layout name, or q/r parities d3-hexjson reads differently)",
            file=sys.stderr,
        )
    return 1


if __name__ == "__main__":
    sys.exit(main(sys.argv))
