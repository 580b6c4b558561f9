#!/usr/bin/env python3
"""How low C_location can go on a layer's largest landmass, and what the layout pays for it.

    location-bound.py SRC.gpkg [RATIO ...]

Takes the regions whose area lies mostly on the largest part of the layer's union (its
largest landmass, method.md §6), and a square lattice over that part whose side s is the
largest at which the part holds a cell per region. For each RATIO (default 1.0 0.9 0.8 0.7),
cells of side RATIO x s are laid over the part and every region takes one by the optimal
assignment of squared distances between its area centroid and the cells' centres (the least
squares of the judge's fit). It prints C_location as the shared judge measures it (after the
fitted scale and shift, in cells), its 90th percentile, and the pieces (edge-connected) and
holes (empty patches the cells enclose) of the cells taken.

At RATIO 1 the cells fill the landmass's own outline: no layout that keeps the outline can
place the regions much nearer on average. Smaller cells let the regions stay nearer home at
the price of a layout that falls apart where the regions are large. No Snake, no refinement:
this is a yardstick for the core's figures, not a layout. Needs shapely, numpy, pyogrio,
scipy, and the shared judge beside the project (../shared/eval).
"""

import os
import sys

import numpy as np
import pyogrio
import shapely
from scipy import ndimage
from scipy.optimize import linear_sum_assignment

# The shared judge's own fit (../shared/eval beside the project), so C_location is its figure.
sys.path.insert(0, os.path.join(os.path.dirname(__file__), "..", "..", "shared", "eval"))
from gridmap_eval import fit_scale_translation  # noqa: E402


def lattice(part, side):
    """The centres of the lattice of `side` over `part`'s bounds, its shape, and which lie in
    `part`."""
    x0, y0, x1, y1 = part.bounds
    xs = np.arange(x0 + side / 2, x1, side)
    ys = np.arange(y0 + side / 2, y1, side)
    gx, gy = np.meshgrid(xs, ys)
    centres = np.c_[gx.ravel(), gy.ravel()]
    return centres, gx.shape, shapely.contains_xy(part, centres[:, 0], centres[:, 1])


def judged_location(region_centres, cell_centres, side):
    """C_location of method.md §8: cells fitted onto the regions by the judge's least-squares
    scale and shift, distances in fitted cells."""
    scale, shift = fit_scale_translation(cell_centres, region_centres)
    fitted = cell_centres * scale + shift
    return np.hypot(*(region_centres - fitted).T) / (side * abs(scale))


def main():
    source = sys.argv[1]
    ratios = [float(r) for r in sys.argv[2:]] or [1.0, 0.9, 0.8, 0.7]
    # Layers from elsewhere bring invalid rings (TopoJSON quantisation); GEOS needs them valid.
    geometries = shapely.make_valid(pyogrio.read_dataframe(source).geometry.values)
    union = shapely.union_all(geometries)
    part = max(getattr(union, "geoms", [union]), key=lambda p: p.area)
    on_part = [g for g in geometries if shapely.intersection(g, part).area > 0.5 * g.area]
    centres = np.array([[c.x, c.y] for c in shapely.centroid(on_part)])
    n = len(on_part)
    side = np.sqrt(part.area / n)
    while lattice(part, side)[2].sum() < n:
        side *= 0.995
    print(f"{source}: {n} regions on the largest landmass, filling side {side:.6g}")
    print("ratio  location   p90  pieces  holes")
    for ratio in ratios:
        cells, shape, inside = lattice(part, side * ratio)
        candidates = np.nonzero(inside)[0]
        costs = ((centres[:, None, :] - cells[candidates][None, :, :]) ** 2).sum(-1)
        regions, taken = linear_sum_assignment(costs)
        distances = judged_location(centres[regions], cells[candidates[taken]], side * ratio)
        occupied = np.zeros(shape, bool)
        occupied.ravel()[candidates[taken]] = True
        pieces = ndimage.label(occupied)[1]
        holes = ndimage.label(np.pad(~occupied, 1, constant_values=True))[1] - 1
        print(
            f"{ratio:5.2f}  {distances.mean():8.3f} {np.percentile(distances, 90):5.2f}"
            f"  {pieces:6d} {holes:6d}"
        )


if __name__ == "__main__":
    main()
