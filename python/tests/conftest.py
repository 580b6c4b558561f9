"""Paths the tests share. The package under test is the installed one (scripts/test-python.sh
installs the wheel into a fresh venv); the repository gives the header, the bundled sample, the
bad-input corpus and the command line to compare with."""

import os
import subprocess

import pytest

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
HEADER = os.path.join(ROOT, "include", "snakegrid.h")
US_STATES = os.path.join(ROOT, "data", "us_states.gpkg")
BAD = os.path.join(ROOT, "tests", "data", "bad")
CLI = os.environ.get("SNAKEGRID_CLI", os.path.join(ROOT, "target", "release", "snakegrid"))


def cli_grid(out, *arguments):
    """The command line's grid map of `arguments` (SRC and options, ids from the field "id"),
    written to `out` and read back as a GeoDataFrame."""
    import pyogrio

    subprocess.run([CLI, "-q", "--id", "id", out, *arguments], check=True)
    return pyogrio.read_dataframe(out)


def cells_of(frame):
    """{id: (grid_col, grid_row)} of a grid layer read as a (Geo)DataFrame."""
    return {i: (c, r) for i, c, r in zip(frame["id"], frame["grid_col"], frame["grid_row"])}


def python_cells(grid):
    return {c.id: (c.fields["grid_col"], c.fields["grid_row"]) for c in grid.cells}


@pytest.fixture(scope="session")
def us_states_cli(tmp_path_factory):
    return cli_grid(str(tmp_path_factory.mktemp("cli") / "us.gpkg"), US_STATES)


def squares_wkb(count, side=1000.0, cols=3):
    """WKB squares in a block `cols` wide, made with the standard library only."""
    import struct

    out = []
    for k in range(count):
        x, y = side * (k % cols), side * (k // cols)
        ring = [(x, y), (x + side, y), (x + side, y + side), (x, y + side), (x, y)]
        out.append(struct.pack("<BIII", 1, 3, 1, len(ring))
                   + b"".join(struct.pack("<dd", *p) for p in ring))
    return out
