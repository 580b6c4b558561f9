#!/usr/bin/env python3
"""Whether a change of settings improves the layouts, judged over several seeds.

One seed's layout is one draw: on virginia_counties the default's adjacency ranges from 0.843 to
0.864 over seeds 0-3, more than most changes move it. This runs the command line with settings A
and with settings B on the shared layers (but us_counties) and on generated ones
(make-test-layers.py: Voronoi layers of 150, 300 and 600 regions, islands, two river layers, a
thin country), for seeds 0..N-1, judges every layout with the shared judge (method.md §8), and
prints per layer the mean of B minus the mean of A, then the mean over the layers. A default changes only when B
wins on the means without losing a shared layer's bar (QUALITY.md at seed 0 is what the issues
hold; BENCHMARKS.md "Settings tried over seeds" has the sweeps so far).

    compare-params.py [--seeds N] [--a "OPTIONS"] --b "OPTIONS" [--both "OPTIONS"]

    --a, --b   snakegrid options as one string, e.g. --b "-refine_temperature 1.5"
    --both     options for both runs, e.g. --both "-cell hex"

About 9 s per seed and setting on 2 cores (34 s for 2 seeds of A and B). Needs a release build, and Python 3 with shapely,
numpy, pyogrio and pyproj (the judge's and make-test-layers.py's needs).
"""

import argparse
import json
import os
import shlex
import subprocess
import sys
import tempfile
from concurrent.futures import ThreadPoolExecutor

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
DATA = os.environ.get("SNAKEGRID_DATA", os.path.join(ROOT, "..", "shared", "data"))
JUDGE = os.path.join(ROOT, "..", "shared", "eval", "gridmap_eval.py")
CLI = os.path.join(ROOT, "target", "release", "snakegrid")
SHARED = ["us_states", "nc_counties", "virginia_counties", "world_countries"]
GENERATED = [
    ("v150", ["voronoi", "150", "7"]),
    ("v300", ["voronoi", "300", "1"]),
    ("v600", ["voronoi", "600", "8"]),
    ("islands", ["islands", "3"]),
    ("river", ["river", "300", "4"]),
    ("river33", ["river", "33", "6"]),
    ("strip", ["strip", "40", "9"]),
]
# The judge's figures compared, with the sign that makes a positive delta an improvement.
METRICS = [
    ("adjacency_kept_queen", "adj", 1),
    ("orientation_deg", "orient °", -1),
    ("location_cells", "location", -1),
    ("location_p90_cells", "loc p90", -1),
    ("location_max_cells", "loc max", -1),
    ("shape_fd", "shape", 1),
    ("gap_cells", "notches", -1),
    ("components_cells", "pieces", -1),
]


def judged(source, options, seed, grid):
    subprocess.run(
        [CLI, "-q", "-id", "id", "-seed", str(seed), *shlex.split(options), grid, source],
        check=True,
    )
    out = subprocess.run(
        [sys.executable, JUDGE, "--regions", source, "--grid", grid, "--id", "id"],
        check=True,
        capture_output=True,
        text=True,
    ).stdout
    os.remove(grid)
    return json.loads(out)


def mean(xs):
    return sum(xs) / len(xs)


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--seeds", type=int, default=4)
    parser.add_argument("--a", default="")
    parser.add_argument("--b", required=True)
    parser.add_argument("--both", default="")
    args = parser.parse_args()
    if not os.access(CLI, os.X_OK):
        sys.exit(f"no release build at {CLI}: cargo build --release")
    with tempfile.TemporaryDirectory() as work:
        layers = [(name, os.path.join(DATA, name + ".gpkg")) for name in SHARED]
        for name, how in GENERATED:
            path = os.path.join(work, name + ".gpkg")
            subprocess.run(
                [sys.executable, os.path.join(ROOT, "scripts", "make-test-layers.py"), *how, path],
                check=True,
            )
            layers.append((name, path))
        settings = {"A": f"{args.both} {args.a}", "B": f"{args.both} {args.b}"}
        jobs = [
            (name, which, seed, source)
            for name, source in layers
            for which in settings
            for seed in range(args.seeds)
        ]
        with ThreadPoolExecutor(max_workers=2) as pool:
            results = list(
                pool.map(
                    lambda k: judged(
                        jobs[k][3], settings[jobs[k][1]], jobs[k][2], os.path.join(work, f"{k}.gpkg")
                    ),
                    range(len(jobs)),
                )
            )
    means = {}
    for (name, which, _, _), result in zip(jobs, results):
        for key, _, _ in METRICS:
            means.setdefault((name, which, key), []).append(float(result[key]))
    print(f"A: {settings['A'].strip() or 'the defaults'}; B: {settings['B'].strip()}; "
          f"seeds 0-{args.seeds - 1}; B − A, per layer (positive: B better)")
    print("| layer | " + " | ".join(label for _, label, _ in METRICS) + " |")
    print("|---|" + "---:|" * len(METRICS))
    overall = {key: [] for key, _, _ in METRICS}
    for name, _ in layers:
        cells = []
        for key, _, sign in METRICS:
            delta = sign * (mean(means[(name, "B", key)]) - mean(means[(name, "A", key)]))
            overall[key].append(delta)
            cells.append(f"{delta:+.3f}")
        print(f"| {name} | " + " | ".join(cells) + " |")
    print("| **mean** | " + " | ".join(f"{mean(overall[k]):+.3f}" for k, _, _ in METRICS) + " |")


if __name__ == "__main__":
    main()
