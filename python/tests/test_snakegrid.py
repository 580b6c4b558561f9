"""The installed snakegrid package against the command line: same cells and fields, the same
parameter table, the same messages, the same working CRS."""

import csv
import json
import os
import re
import signal
import subprocess
import sys
import threading

import pyogrio
import pytest
import shapely
import shapely.affinity

import snakegrid

from conftest import BAD, CLI, ROOT, US_STATES, cells_of, cli_grid, python_cells, squares_wkb


@pytest.fixture(scope="module")
def us_states():
    return pyogrio.read_dataframe(US_STATES)


def test_us_states_gives_the_command_line_cells_and_fields(us_states, us_states_cli):
    grid = snakegrid.layout(us_states.geometry, us_states["id"])
    assert python_cells(grid) == cells_of(us_states_cli)
    names = [f.name for f in snakegrid.fields()]
    assert names == list(us_states_cli.columns[-len(names) - 1:-1])  # before the geometry
    cli = us_states_cli.set_index("id")
    for cell in grid.cells:
        assert list(cell.fields) == names
        for name, value in cell.fields.items():
            assert value == pytest.approx(cli.loc[cell.id, name], abs=1e-9), (cell.id, name)
        assert isinstance(cell.geometry, shapely.Polygon)
        assert cell.geometry.equals_exact(cli.loc[cell.id, "geometry"], 1e-6)
    assert isinstance(grid.moved_outline, shapely.MultiPolygon)
    table = grid.table()
    assert list(table) == ["id", *names, "geometry"] and len(table["id"]) == len(us_states)


def test_hexagons_give_the_command_line_cells_and_a_hexjson(us_states, tmp_path):
    grid = snakegrid.layout(us_states.geometry, us_states["id"], cell="hex",
                            hex_orientation="flat")
    cli = cli_grid(str(tmp_path / "hex.gpkg"), US_STATES, "-cell", "hex",
                   "-hex_orientation", "flat")
    assert python_cells(grid) == cells_of(cli)
    assert all(len(cell.geometry.exterior.coords) == 7 for cell in grid.cells)
    hexes = json.loads(grid.hexjson)
    assert hexes["layout"] in ("odd-q", "even-q")
    assert sorted(hexes["hexes"]) == sorted(us_states["id"])
    assert hexes["hexes"]["06"]["n"] == "06"
    # Squares have no HexJSON.
    assert snakegrid.layout(us_states.geometry, us_states["id"]).hexjson is None


def test_groups_give_the_command_line_cells_and_group_metrics(us_states, tmp_path):
    # Two groups, the states west and east of the median centroid, a cell apart.
    frame = us_states.copy()
    x = frame.geometry.centroid.x
    frame["half"] = ["west" if v < x.median() else "east" for v in x]
    source = str(tmp_path / "halves.gpkg")
    pyogrio.write_dataframe(frame, source)
    grid = snakegrid.layout(frame.geometry, frame["id"], groups=frame["half"], group_gap=1)
    cli = cli_grid(str(tmp_path / "grouped.gpkg"), source, "-group", "half", "-group_gap", "1")
    assert python_cells(grid) == cells_of(cli)
    metrics = grid.group_metrics
    assert (metrics.groups, metrics.contacts, metrics.reach) == (2, 0, 2)
    assert [c.fields["grid_group"] for c in grid.cells] == list(cli["grid_group"])
    assert snakegrid.layout(us_states.geometry, us_states["id"]).group_metrics is None
    with pytest.raises(ValueError, match="one group per region"):
        snakegrid.layout(us_states.geometry, us_states["id"], groups=["west"])


#: The NYT's hand-made us_states cells for five states (issue 18), columns from the west, rows
#: from the top.
NYT = {"WA": (1, 2), "FL": (7, 7), "ME": (11, 0), "CA": (0, 4), "TX": (3, 6)}


def test_pins_give_the_command_line_cells(us_states, tmp_path):
    frame = us_states.copy()
    frame["pc"] = [NYT.get(a, (None, None))[0] for a in frame["abbr"]]
    frame["pr"] = [NYT.get(a, (None, None))[1] for a in frame["abbr"]]
    source = str(tmp_path / "pinned.gpkg")
    pyogrio.write_dataframe(frame, source)
    grid = snakegrid.layout(frame.geometry, frame["id"],
                            pins=[NYT.get(a) for a in frame["abbr"]])
    cli = cli_grid(str(tmp_path / "pinned-grid.gpkg"), source, "-pin_col", "pc", "-pin_row", "pr")
    assert python_cells(grid) == cells_of(cli)
    by_abbr = dict(zip(frame["id"], frame["abbr"]))
    got = {by_abbr[c.id]: (c.fields["grid_col"], c.fields["grid_row"]) for c in grid.cells}
    assert {a: got[a] for a in NYT} == NYT
    with pytest.raises(snakegrid.SnakegridError, match="not a whole number"):
        snakegrid.layout(frame.geometry, frame["id"], pins=[(0.5, 1)] + [None] * (len(frame) - 1))


@pytest.fixture(scope="module")
def us_grid(us_states):
    return snakegrid.layout(us_states.geometry, us_states["abbr"])


def columns(grid):
    """The cells, ids, grid_q and grid_r of `grid`, as lists to edit."""
    return ([c.geometry for c in grid.cells], [c.id for c in grid.cells],
            [c.fields["grid_q"] for c in grid.cells], [c.fields["grid_r"] for c in grid.cells])


def test_a_relayout_keeps_the_moved_and_kept_cells(us_states, us_grid):
    grid = us_grid
    cells, ids, q, r = columns(grid)
    # By hand: Texas three cells down, Maine two right; Ohio ticked to keep.
    moves = {"TX": (0, -3), "ME": (2, 0)}
    for k, region in enumerate(ids):
        if region in moves:
            dx, dy = moves[region]
            cells[k] = shapely.affinity.translate(cells[k], dx * grid.cell_size,
                                                  dy * grid.cell_size)
    pins = snakegrid.edit_pins(cells, ids, q, r, keep=[i == "OH" for i in ids])
    pinned = {i: p for i, p in zip(ids, pins) if p}
    at = {c.id: (c.fields["grid_col"], c.fields["grid_row"]) for c in grid.cells}
    assert pinned == {"TX": (at["TX"][0], at["TX"][1] + 3, True),
                      "ME": (at["ME"][0] + 2, at["ME"][1], True),
                      "OH": (*at["OH"], False)}
    again = snakegrid.layout(us_states.geometry, us_states["abbr"],
                             pins=[pinned[i][:2] if i in pinned else None for i in ids])
    cells_again = {c.id: (c.fields["grid_col"], c.fields["grid_row"]) for c in again.cells}
    assert {i: cells_again[i] for i in pinned} == {i: p[:2] for i, p in pinned.items()}
    assert len(set(cells_again.values())) == len(ids)


def test_edit_pins_refuses_positions_it_cannot_read(us_grid):
    cells, ids, q, r = columns(us_grid)
    # Too few values were filled with zeros (nearly every cell "moved"), a short keep list with
    # False, and a NULL, NaN or a 2**40 failed in int() or wrapped without naming the cell.
    with pytest.raises(ValueError, match="49 geometries and 48 grid_q values"):
        snakegrid.edit_pins(cells, ids, q[:-1], r)
    with pytest.raises(ValueError, match="49 geometries and 3 keep values"):
        snakegrid.edit_pins(cells, ids, q, r, keep=[True] * 3)
    labels = [f"FID {k}" for k in range(len(cells))]
    for bad, message in ((None, "FID 2: grid_r is empty"),
                         (float("nan"), "FID 2: grid_r nan is not a whole number"),
                         (2**40, "FID 2: grid_r 1099511627776 is not a whole number"),
                         ("x", "FID 2: grid_r 'x' is not a number")):
        edited = list(r)
        edited[2] = bad
        with pytest.raises(ValueError, match=message):
            snakegrid.edit_pins(cells, ids, q, edited, labels=labels)


@pytest.mark.parametrize("with_progress", [False, True])
def test_ctrl_c_cancels_a_run(us_states, with_progress):
    # Without a progress callback the interrupt waited for the whole run; with one it fell
    # inside the callback, where ctypes swallowed it, and the run went on to the end. This run
    # would take minutes (the parameter table's most refinement moves).
    seen = []
    # Python's own handler, as in a terminal: a shell's background job (CI) inherits SIGINT
    # ignored, and Python then installs none.
    previous = signal.signal(signal.SIGINT, signal.default_int_handler)
    timer = threading.Timer(1.0, os.kill, (os.getpid(), signal.SIGINT))
    timer.start()
    try:
        with pytest.raises(KeyboardInterrupt):
            snakegrid.layout(us_states.geometry, us_states["abbr"],
                             progress=(lambda done, _: seen.append(done)) if with_progress
                             else None,
                             refine_moves_per_region=1000000)
    finally:
        timer.cancel()
        signal.signal(signal.SIGINT, previous)
    if with_progress:
        assert seen and max(seen) < 1.0, "the run went on to the end"
    again = snakegrid.layout(us_states.geometry, us_states["abbr"], refine=False)
    assert len(again.cells) == len(us_states)


def test_text_with_a_nul_character_is_refused_by_name(us_states):
    # ctypes cut it at the NUL: ids "a", NUL, "x" and "a", NUL, "y" both read as "a", an option
    # name "alpha", NUL, "x" as alpha.
    geometries = list(us_states.geometry[:2])
    with pytest.raises(ValueError, match="index 0: the id 'a\\\\x00x' holds a NUL"):
        snakegrid.layout(geometries, ["a\0x", "a\0y"])
    with pytest.raises(ValueError, match="the option name 'alpha\\\\x00x' holds a NUL"):
        snakegrid.layout(geometries, ["a", "b"], **{"alpha\0x": 2})


def test_a_geodataframe_numpy_options_and_bad_pins_are_taken_as_meant(us_states):
    # A whole GeoDataFrame was read as its column names ("expected a shapely geometry, got
    # str"), a numpy array of shifts as its repr, and a pin of three numbers failed with
    # "too many values to unpack".
    import numpy

    framed = snakegrid.layout(us_states, us_states["abbr"], refine=False,
                              shifts=numpy.array([[0.0, 0.0]]))
    plain = snakegrid.layout(us_states.geometry, us_states["abbr"], refine=False,
                             shifts=[(0.0, 0.0)])
    assert python_cells(framed) == python_cells(plain)
    pins = [None] * len(us_states)
    for bad in ((0, 0, 0), ("a", "b"), 5):
        pins[3] = bad
        with pytest.raises(ValueError, match="index 3: the pin .* is not None or a"):
            snakegrid.layout(us_states.geometry, us_states["abbr"], pins=pins)


def test_a_geoseries_in_degrees_gets_a_note(us_states):
    lonlat = us_states.geometry.to_crs("EPSG:4326")
    grid = snakegrid.layout(lonlat, us_states["abbr"], refine=False)
    assert any("EPSG:4326 is geographic" in note for note in grid.notes), grid.notes
    planar = snakegrid.layout(us_states.geometry, us_states["abbr"], refine=False)
    assert not any("geographic" in note for note in planar.notes), planar.notes


def test_options_are_the_command_line_parameters():
    help_text = subprocess.run([CLI, "--help"], check=True, capture_output=True,
                               text=True).stdout
    listed = {name: (text, default) for name, text, default in re.findall(
        r"--(\w+) <VALUE>\n\s+(.*?) \[default: ([^\]]*)\]", help_text, re.S)}
    table = snakegrid.options()
    assert [o.name for o in table] == list(listed)
    for option in table:
        text, default = listed[option.name]
        unit = f", {option.unit}" if option.unit else ""
        assert " ".join(text.split()) == f"{option.summary}; {option.range}{unit}", option.name
        assert default == option.default, option.name


def test_options_are_checked_by_the_library_naming_the_option():
    with pytest.raises(snakegrid.SnakegridError, match="alpha") as error:
        snakegrid.layout(squares_wkb(4), alpha=1e308)
    assert error.value.status == 5  # SNAKEGRID_INVALID_OPTION


def test_a_64_bit_seed_and_lists_are_accepted():
    grid = snakegrid.layout(squares_wkb(6), seed=2**64 - 1, shifts=[(0, 0), (0.5, 0.5)],
                            noise_levels=[0.02], refine=False)
    assert len(grid.cells) == 6


def test_wkb_in_gives_wkb_out_without_shapely():
    # A fresh interpreter: importing the package and laying out WKB never imports shapely.
    code = (
        "import sys, snakegrid\n"
        "from conftest import squares_wkb\n"
        "grid = snakegrid.layout(squares_wkb(9), [f'r{k}' for k in range(9)])\n"
        "assert all(isinstance(c.geometry, bytes) for c in grid.cells)\n"
        "assert 'shapely' not in sys.modules, 'shapely was imported'\n"
        "print(sorted(c.fields['grid_col'] for c in grid.cells))\n")
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                          cwd=os.path.dirname(__file__))
    assert done.returncode == 0, done.stderr
    # A 3 x 3 block of squares is already a grid map.
    assert done.stdout.strip() == "[0, 0, 0, 1, 1, 1, 2, 2, 2]"


def test_progress_names_stages_and_false_cancels():
    seen = []
    snakegrid.layout(squares_wkb(9), progress=lambda f, m: seen.append((f, m)))
    fractions = [f for f, _ in seen]
    assert fractions == sorted(fractions) and fractions[-1] == pytest.approx(1.0)
    assert all(m for _, m in seen)
    calls = []

    def stop(fraction, message):
        calls.append(fraction)
        return False

    with pytest.raises(snakegrid.Cancelled):
        snakegrid.layout(squares_wkb(9), progress=stop)
    assert len(calls) == 1  # the library calls no more once told to stop


def test_an_exception_in_the_callback_stops_the_run_and_is_raised():
    def broken(fraction, message):
        raise KeyError("from the callback")

    with pytest.raises(KeyError, match="from the callback"):
        snakegrid.layout(squares_wkb(4), progress=broken)


def bad_cases():
    with open(os.path.join(BAD, "cases.tsv"), encoding="utf-8") as f:
        rows = [r for r in csv.reader(f, delimiter="\t") if r and not r[0].startswith("#")]
    # GDAL's C API hands the command line GeoJSON's empty coordinates as a null geometry,
    # pyogrio as an empty one: the library names each as it is given, so the texts differ.
    skipped = {"empty_geometry.geojson"}
    return [r for r in rows if r[2] == "invalid_input" and r[1] != "-" and r[0] not in skipped]


@pytest.mark.parametrize("case", bad_cases(), ids=lambda r: r[0])
def test_bad_input_gives_the_command_line_message(case, tmp_path):
    name, id_field, _, expected = case
    path = os.path.join(BAD, name)
    done = subprocess.run([CLI, "-q", "--id", id_field, str(tmp_path / "o.gpkg"), path],
                          capture_output=True, text=True)
    cli_message = done.stderr.strip().removeprefix("snakegrid: ERROR: ")
    assert done.returncode == 1 and expected in cli_message
    # As a host reads a layer: null geometries as None, features named by FID.
    frame = pyogrio.read_dataframe(path, fid_as_index=True)
    with pytest.raises(snakegrid.SnakegridError) as error:
        snakegrid.layout(list(frame.geometry), list(frame[id_field]),
                         labels=[f"FID {fid}" for fid in frame.index])
    assert str(error.value).split(": ", 1)[1] == cli_message


def test_notes_say_what_the_library_repaired():
    frame = pyogrio.read_dataframe(os.path.join(BAD, "bowtie.geojson"))
    grid = snakegrid.layout(list(frame.geometry), list(frame["code"]))
    assert any("feature bowtie: invalid polygon repaired" in n for n in grid.notes), grid.notes
    repairs = {cell.id: cell.repair for cell in grid.cells}
    assert repairs["bowtie"].startswith("a ring intersects itself at (")
    assert repairs["r00"] is None


def test_working_crs_is_the_command_lines(tmp_path):
    # A lon/lat layer across the antimeridian: the CLI projects it by the same rule, and its
    # output's CRS carries the name.
    path = os.path.join(BAD, "antimeridian.geojson")
    frame = pyogrio.read_dataframe(path)
    crs = snakegrid.working_crs(frame.geometry)
    out = str(tmp_path / "am.gpkg")
    subprocess.run([CLI, "-q", "--id", "code", out, path], check=True)
    # pyogrio gives the output's CRS as WKT1 (the GeoPackage's definition).
    assert pyogrio.read_info(out)["crs"].startswith(f'PROJCS["{crs.name}"')
    assert crs.note and crs.wkt.startswith("PROJCRS[")
    # Boxes work as well as geometries; one box for the whole layer would centre it on 0°.
    assert snakegrid.working_crs([g.bounds for g in frame.geometry]) == crs
    assert snakegrid.working_crs([frame.total_bounds]).name != crs.name


def test_a_region_drawn_across_the_antimeridian_is_read_and_cut_right():
    # Chukotka as d3's world-atlas draws it: a ring stepping from 180 to -180. Its bounds span
    # the globe; the library reads it as the 20° it is, and cuts it for a world map.
    from shapely.geometry import Polygon

    chukotka = Polygon([(170, 60), (-170, 60), (-170, 70), (170, 70), (170, 60)])
    alone = snakegrid.working_crs([chukotka])
    assert alone.name == "Lambert azimuthal equal-area at 65.0N 180.0E (snakegrid)"
    assert alone.cut(chukotka).bounds == (170, 60, 190, 70)
    world = snakegrid.working_crs([(-180, -60, 180, 80)])
    pieces = world.cut(chukotka)
    assert sorted(p.bounds for p in pieces.geoms) == [(-180, 60, -170, 70), (170, 60, 180, 70)]
    assert abs(pieces.area - 200) < 1e-9
    assert isinstance(world.cut(chukotka.wkb), bytes)
    france = Polygon([(0, 45), (5, 45), (5, 50), (0, 50)])
    assert world.cut(france) is france
    # Round a pole nothing is split: a layer of the Antarctic is centred on the South Pole, and
    # a region across ±180° there is projected as drawn.
    antarctic = snakegrid.working_crs([(-180, -90, 180, -60)])
    assert antarctic.name == "Lambert azimuthal equal-area at 90.0S 0.0E (snakegrid)"
    ross = Polygon([(170, -80), (-170, -80), (-170, -70), (170, -70), (170, -80)])
    assert antarctic.cut(ross) is ross


def test_working_crs_refuses_what_cannot_be_degrees():
    with pytest.raises(snakegrid.SnakegridError, match="not longitudes and latitudes"):
        snakegrid.working_crs([(1e5, 1e5, 2e5, 2e5)])


def test_a_mercator_layer_gets_the_command_lines_note(tmp_path):
    # The CLI's note on the US states in Web Mercator, and the binding's, word for word.
    source = str(tmp_path / "states_3857.gpkg")
    subprocess.run(["ogr2ogr", "-t_srs", "EPSG:3857", source, US_STATES], check=True)
    run = subprocess.run([CLI, "--id", "id", str(tmp_path / "out.gpkg"), source],
                         check=True, capture_output=True, text=True)
    note = snakegrid.projected_crs_note("merc", "EPSG:3857 (WGS 84 / Pseudo-Mercator)")
    assert note is not None and note in run.stdout + run.stderr
    assert snakegrid.projected_crs_note("tmerc", "EPSG:32633") is None


def test_regions_without_a_crs_may_be_degrees():
    assert snakegrid.looks_like_degrees([(-17.0, -35.0, 51.0, 37.0)])
    assert not snakegrid.looks_like_degrees([(4e5, 4e6, 5e5, 4.1e6)])


def test_snakegrid_library_names_the_library(monkeypatch, tmp_path):
    wheel_library = snakegrid.load().path
    missing = str(tmp_path / "libsnakegrid.so")
    monkeypatch.setenv("SNAKEGRID_LIBRARY", missing)
    assert snakegrid.library_path() == missing
    with pytest.raises(snakegrid.LibraryError, match=re.escape(missing)):
        snakegrid.load()
    monkeypatch.setenv("SNAKEGRID_LIBRARY", wheel_library)
    assert snakegrid.load().path == wheel_library


def test_the_readme_example_runs_as_written_and_matches_the_command_line(tmp_path):
    readme = open(os.path.join(ROOT, "README.md"), encoding="utf-8").read()
    section = readme.split("## Python", 1)[1]
    example = re.search(r"```python\n(.*?)```", section, re.S).group(1)
    os.symlink(os.path.join(ROOT, "data"), tmp_path / "data")
    (tmp_path / "out").mkdir()
    done = subprocess.run([sys.executable, "-c", example], cwd=tmp_path, capture_output=True,
                          text=True)
    assert done.returncode == 0, done.stderr
    written = pyogrio.read_dataframe(str(tmp_path / "out" / "us_grid.gpkg"))
    # The example projects us_states to lon/lat first, as a user's layer would be: the
    # command line on that layer must agree.
    lonlat = str(tmp_path / "us_states_4326.gpkg")
    pyogrio.write_dataframe(pyogrio.read_dataframe(US_STATES).to_crs("EPSG:4326"), lonlat)
    assert cells_of(written) == cells_of(cli_grid(str(tmp_path / "cli.gpkg"), lonlat))
