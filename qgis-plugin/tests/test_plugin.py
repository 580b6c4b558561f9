"""The snakegrid QGIS plugin under a headless QGIS: provider, parameters from the library's
table, layouts against the command line, CRS, cancelling, errors, notes, qgis_process, and the
repository build."""

import configparser
import csv
import json
import os
import re
import subprocess
import sys
import threading
import zipfile

import _ctypes
import pytest
from qgis.core import (
    QgsApplication,
    QgsCoordinateReferenceSystem,
    QgsCoordinateTransformContext,
    QgsFeature,
    QgsFeatureRequest,
    QgsField,
    QgsGeometry,
    QgsProcessingAlgRunnerTask,
    QgsProcessingContext,
    QgsProcessingException,
    QgsProcessingFeatureSourceDefinition,
    QgsProcessingFeedback,
    QgsProcessingParameterString,
    QgsProject,
    QgsRectangle,
    QgsVectorFileWriter,
    QgsVectorLayer,
)
from qgis.PyQt.QtCore import QVariant

from conftest import BAD, CLI, DATA, PYTHON, WHEEL, install_wheel

US_STATES = os.path.join(DATA, "us_states.gpkg")
US_COUNTIES = os.path.join(DATA, "us_counties.gpkg")
ANTIMERIDIAN = os.path.join(BAD, "antimeridian.geojson")
ANTIMERIDIAN_STEPPING = os.path.join(BAD, "antimeridian_stepping.geojson")
METRICS = ["C_LOCATION", "C_ADJACENT", "C_ORIENTATION", "C_SHAPE"]


class Log(QgsProcessingFeedback):
    """A feedback that keeps what the algorithm said."""

    def __init__(self):
        super().__init__()
        self.lines = []
        self.texts = []

    def pushInfo(self, info):  # noqa: N802 (QGIS's names)
        self.lines.append(info)

    def pushWarning(self, warning):  # noqa: N802
        self.lines.append(warning)

    def setProgressText(self, text):  # noqa: N802
        self.texts.append(text)

    def reportError(self, error, fatalError=False):  # noqa: N802
        self.lines.append(f"error: {error}")


def run(algorithm, **parameters):
    import processing

    feedback = parameters.pop("feedback", None) or QgsProcessingFeedback()
    return processing.run(f"snakegrid:{algorithm}", parameters, feedback=feedback)


def layout(layer, id_field="id"):
    """{id: (grid_col, grid_row)} of a grid layer (a QgsVectorLayer or a path)."""
    if isinstance(layer, str):
        layer = QgsVectorLayer(layer, "grid", "ogr")
    return {str(f[id_field]): (f["grid_col"], f["grid_row"]) for f in layer.getFeatures()}


def cli(out, source, *arguments, id_field="id"):
    """The command line's grid map of `source`, written to `out` (a path, returned)."""
    subprocess.run([CLI, "-q", "--id", id_field, *arguments, out, source], check=True)
    return out


def squares_layer(ids, crs="EPSG:3857", side=1000.0, cols=3):
    """A memory layer of squares in a block `cols` wide, ids from `ids`."""
    layer = QgsVectorLayer(f"Polygon?crs={crs}", "squares", "memory")
    provider = layer.dataProvider()
    provider.addAttributes([QgsField("code", QVariant.String)])
    layer.updateFields()
    features = []
    for k, region_id in enumerate(ids):
        x, y = side * (k % cols), side * (k // cols)
        feature = QgsFeature(layer.fields())
        feature.setAttributes([region_id])
        feature.setGeometry(QgsGeometry.fromRect(QgsRectangle(x, y, x + side, y + side)))
        features.append(feature)
    provider.addFeatures(features)
    return layer


def assert_square_cells(layer, count):
    assert layer.featureCount() == count
    areas = []
    for feature in layer.getFeatures():
        geometry = feature.geometry()
        assert geometry.isGeosValid()
        assert geometry.constGet().nCoordinates() == 5  # a closed square ring
        box = geometry.boundingBox()
        assert box.width() == pytest.approx(box.height(), rel=1e-9)
        assert geometry.area() == pytest.approx(box.width() * box.height(), rel=1e-9)
        areas.append(geometry.area())
    assert max(areas) == pytest.approx(min(areas), rel=1e-9)
    cells = {(f["grid_col"], f["grid_row"]) for f in layer.getFeatures()}
    assert len(cells) == count, "two regions share a cell"


@pytest.fixture(scope="module")
def cli_layout(tmp_path_factory):
    return layout(cli(str(tmp_path_factory.mktemp("cli") / "out.gpkg"), US_STATES))


@pytest.fixture(scope="module")
def us_run(qgis_app):
    return run("gridmap", INPUT=US_STATES, ID_FIELD="id", OUTPUT="memory:",
               OUTLINE="memory:")


@pytest.fixture(scope="module")
def us_states_lonlat(qgis_app, tmp_path_factory):
    import processing

    path = str(tmp_path_factory.mktemp("lonlat") / "us_states_4326.gpkg")
    processing.run("native:reprojectlayer", {
        "INPUT": US_STATES, "TARGET_CRS": QgsCoordinateReferenceSystem("EPSG:4326"),
        "OUTPUT": path})
    return path


def algorithm(name):
    return QgsApplication.processingRegistry().algorithmById(f"snakegrid:{name}")


def test_provider_and_algorithms_are_registered_and_findable(qgis_app):
    provider = QgsApplication.processingRegistry().providerById("snakegrid")
    assert provider is not None and not provider.icon().isNull()
    assert re.match(r"^\d+\.\d+\.\d+ \(library \d+\.\d+\.\d+\)$", provider.versionInfo())
    assert provider.warningMessage() == ""
    for name in ("gridmap", "gridmetrics", "relayout"):
        alg = algorithm(name)
        assert alg.canExecute() == (True, "")
        assert alg.group() and alg.groupId()
        assert {"tile map", "cartogram", "hexagon"} <= set(alg.tags())
        assert not alg.icon().isNull()
        assert alg.helpUrl().startswith("https://github.com/snakegrid/snakegrid/")
        help_text = alg.shortHelpString()
        assert len(help_text) > 300 and not re.search(r"<\w+>", help_text), "HTML in the help"


def states_with(path, fields, values):
    """us_states' ids and geometries with `fields` added, each feature's `values(feature)`,
    written to the GeoPackage `path`."""
    layer = QgsVectorLayer(US_STATES, "us_states", "ogr")
    copy = QgsVectorLayer("MultiPolygon?crs=" + layer.crs().authid(), "copy", "memory")
    provider = copy.dataProvider()
    provider.addAttributes([QgsField("id", QVariant.String), *fields])
    copy.updateFields()
    for feature in layer.getFeatures():
        out = QgsFeature(copy.fields())
        out.setAttributes([feature["id"], *values(feature)])
        out.setGeometry(feature.geometry())
        provider.addFeature(out)
    options = QgsVectorFileWriter.SaveVectorOptions()
    options.driverName = "GPKG"
    QgsVectorFileWriter.writeAsVectorFormatV3(copy, path, QgsCoordinateTransformContext(),
                                              options)


def test_a_group_field_gives_the_command_line_layout_and_group_outputs(qgis_app, tmp_path):
    # The states west and east of the middle of the layer, as two groups a cell apart.
    middle = QgsVectorLayer(US_STATES, "us_states", "ogr").extent().center().x()
    source = str(tmp_path / "halves.gpkg")

    def half(feature):
        return ["west" if feature.geometry().centroid().asPoint().x() < middle else "east"]

    states_with(source, [QgsField("half", QVariant.String)], half)
    result = run("gridmap", INPUT=source, ID_FIELD="id", GROUP_FIELD="half", GROUP_GAP=1,
                 OUTPUT="memory:")
    expected = layout(cli(str(tmp_path / "cli.gpkg"), source, "-group", "half",
                          "-group_gap", "1"))
    assert layout(result["OUTPUT"]) == expected
    assert result["GROUP_CONTACTS"] == 0 and result["GROUPS_WHOLE"] == 1.0
    blocks = {f["half"]: f["grid_group"] for f in result["OUTPUT"].getFeatures()}
    assert sorted(blocks.values()) == [1, 2]


#: The NYT's hand-made us_states cells for five states by FIPS id (issue 18): WA, FL, ME, CA, TX.
NYT = {"53": (1, 2), "12": (7, 7), "23": (11, 0), "06": (0, 4), "48": (3, 6)}


def test_pin_fields_give_the_command_line_layout(qgis_app, tmp_path):
    source = str(tmp_path / "pinned.gpkg")
    states_with(source, [QgsField("pc", QVariant.Int), QgsField("pr", QVariant.Double)],
                lambda feature: list(NYT.get(feature["id"], (None, None))))
    result = run("gridmap", INPUT=source, ID_FIELD="id", PIN_COL_FIELD="pc", PIN_ROW_FIELD="pr",
                 OUTPUT="memory:")
    cells = layout(result["OUTPUT"])
    assert cells == layout(cli(str(tmp_path / "cli.gpkg"), source, "-pin_col", "pc",
                               "-pin_row", "pr"))
    assert {i: cells[i] for i in NYT} == NYT
    with pytest.raises(QgsProcessingException, match="set both fields or neither"):
        run("gridmap", INPUT=source, ID_FIELD="id", PIN_COL_FIELD="pc", OUTPUT="memory:")


def _moved(grid, moves, keep=()):
    """A copy of grid layer `grid` with the cells of `moves` (id: (dx, dy) in cells, y up)
    moved and a boolean field keep, true for the ids in `keep`."""
    edited = grid.materialize(QgsFeatureRequest())
    edited.startEditing()
    edited.addAttribute(QgsField("keep", QVariant.Bool))
    edited.updateFields()
    side = next(edited.getFeatures()).geometry().area() ** 0.5
    for feature in edited.getFeatures():
        if feature["id"] in moves:
            dx, dy = moves[feature["id"]]
            geometry = feature.geometry()
            geometry.translate(dx * side, dy * side)
            edited.changeGeometry(feature.id(), geometry)
        edited.changeAttributeValue(feature.id(), edited.fields().lookupField("keep"),
                                    feature["id"] in keep)
    edited.commitChanges()
    return edited


def test_a_relayout_keeps_moved_and_ticked_cells(us_run):
    grid = us_run["OUTPUT"]
    before = layout(grid)
    # By hand: Texas (48) three cells down, Maine (23) two right; Ohio (39) ticked to keep.
    edited = _moved(grid, {"48": (0, -3), "23": (2, 0)}, keep=("39",))
    log = Log()
    result = run("relayout", INPUT=US_STATES, ID_FIELD="id", EDITED=edited, KEEP_FIELD="keep",
                 OUTPUT="memory:", feedback=log)
    after = layout(result["OUTPUT"])
    assert after["48"] == (before["48"][0], before["48"][1] + 3)
    assert after["23"] == (before["23"][0] + 2, before["23"][1])
    assert after["39"] == before["39"]
    assert len(set(after.values())) == 49 == result["OUTPUT"].featureCount()
    assert any("2 moved cells and 1 kept regions pinned" in line for line in log.lines)
    # Texas dragged onto Oklahoma's cell (40): refused, naming both.
    (tc, tr), (oc, orow) = before["48"], before["40"]
    onto = _moved(grid, {"48": (oc - tc, tr - orow)})
    with pytest.raises(QgsProcessingException, match="feature (48|40): .*feature (40|48)"):
        run("relayout", INPUT=US_STATES, ID_FIELD="id", EDITED=onto, OUTPUT="memory:")


def _edited_attributes(grid, values):
    """A copy of grid layer `grid` with `values` ({field: {id: value}}) set, a text field keep
    added."""
    edited = grid.materialize(QgsFeatureRequest())
    edited.startEditing()
    edited.addAttribute(QgsField("keep", QVariant.String))
    edited.updateFields()
    for feature in edited.getFeatures():
        for field, by_id in values.items():
            if feature["id"] in by_id:
                edited.changeAttributeValue(feature.id(), edited.fields().lookupField(field),
                                            by_id[feature["id"]])
    edited.commitChanges()
    return edited


def test_a_relayout_reads_text_keep_values_and_names_a_cell_without_its_position(us_run):
    grid = us_run["OUTPUT"]
    # A text keep field: "false" and "0" were kept (bool("false") is True in Python).
    texts = {"keep": {"39": "yes", "48": "false", "23": "0", "06": " FALSE "}}
    log = Log()
    run("relayout", INPUT=US_STATES, ID_FIELD="id", EDITED=_edited_attributes(grid, texts),
        KEEP_FIELD="keep", OUTPUT="memory:", feedback=log)
    assert any("0 moved cells and 1 kept regions pinned" in line for line in log.lines)
    unclear = _edited_attributes(grid, {"keep": {"39": "maybe"}})
    with pytest.raises(QgsProcessingException, match="the keep value 'maybe' is neither"):
        run("relayout", INPUT=US_STATES, ID_FIELD="id", EDITED=unclear, KEEP_FIELD="keep",
            OUTPUT="memory:")
    # A NULL grid_q failed with a Python traceback (int() of None).
    blank = _edited_attributes(grid, {"grid_q": {"39": None}})
    with pytest.raises(QgsProcessingException, match="FID [0-9]+: grid_q is empty"):
        run("relayout", INPUT=US_STATES, ID_FIELD="id", EDITED=blank, OUTPUT="memory:")


def test_an_empty_selection_is_named(us_states_lonlat):
    # In longitude and latitude it failed seeking a working CRS: "no coordinates to centre a
    # projection on".
    layer = QgsVectorLayer(us_states_lonlat, "states", "ogr")
    layer.removeSelection()
    QgsProject.instance().addMapLayer(layer)
    try:
        source = QgsProcessingFeatureSourceDefinition(layer.id(), selectedFeaturesOnly=True)
        with pytest.raises(QgsProcessingException, match="none is selected"):
            run("gridmap", INPUT=source, ID_FIELD="id", OUTPUT="memory:")
    finally:
        QgsProject.instance().removeMapLayer(layer.id())


def test_a_field_the_layer_lacks_is_refused_by_name(qgis_app):
    # qgis_process and processing.run take any text for a field: a typo laid the map out by
    # feature ids, or without groups or pins, and said nothing.
    for field in ("ID_FIELD", "GROUP_FIELD"):
        with pytest.raises(QgsProcessingException,
                           match=r"the layer has no field 'nope' \(its fields: .*id, name, abbr"):
            run("gridmap", INPUT=US_STATES, OUTPUT="memory:", **{field: "nope"})
    with pytest.raises(QgsProcessingException, match="no field 'nope'"):
        run("gridmap", INPUT=US_STATES, OUTPUT="memory:", PIN_COL_FIELD="nope",
            PIN_ROW_FIELD="id")


def test_parameters_are_the_library_table_in_upper_case(qgis_app):
    import snakegrid

    alg = algorithm("gridmap")
    table = snakegrid.options()
    method = [p for p in alg.parameterDefinitions()
              if p.name() not in ("INPUT", "ID_FIELD", "GROUP_FIELD", "LABEL_FIELD",
                                  "TARGET_CRS", "PIN_COL_FIELD", "PIN_ROW_FIELD", "OUTPUT",
                                  "OUTLINE", "HEXJSON")]
    assert [p.name() for p in method] == [o.name.upper() for o in table]
    assert all(p.name() == p.name().upper() for p in alg.parameterDefinitions())
    for option, parameter in zip(table, method):
        assert option.help in parameter.help() and option.range in parameter.help()
        assert bool(parameter.flags() & parameter.FlagAdvanced) == option.advanced
        assert parameter.name() in alg.shortHelpString()
        if isinstance(parameter, QgsProcessingParameterString):
            assert parameter.defaultValue() == option.default
        elif option.kind in ("real", "integer"):
            if option.minimum is not None:
                assert parameter.minimum() == option.minimum, option.name
            if option.maximum is not None:
                assert parameter.maximum() == option.maximum, option.name
            if option.default != "none":
                assert parameter.defaultValue() == float(option.default), option.name
        elif option.kind == "bool":
            assert parameter.defaultValue() == (option.default == "true")
        else:
            assert parameter.options() == list(option.choices)
            assert parameter.defaultValue() == option.default
    # The 64-bit seed keeps every value: it is text the library checks.
    seed = alg.parameterDefinition("SEED")
    assert isinstance(seed, QgsProcessingParameterString)


def test_us_states_gives_the_command_line_layout(us_run, cli_layout):
    import snakegrid

    grid = us_run["OUTPUT"]
    assert_square_cells(grid, 49)
    names = grid.fields().names()
    source = QgsVectorLayer(US_STATES, "src", "ogr")
    added = [f.name for f in snakegrid.fields()]
    assert names == source.fields().names() + added
    assert grid.crs().authid() == "EPSG:5070"
    assert layout(grid) == cli_layout
    outline = list(us_run["OUTLINE"].getFeatures())
    assert len(outline) == 1 and outline[0].geometry().isGeosValid()
    assert outline[0]["regions"] == 49


def test_named_progress_stages_reach_the_log(qgis_app):
    import snakegrid

    layer = squares_layer([f"r{k}" for k in range(9)])
    stages = []
    ids = [f["code"] for f in layer.getFeatures()]
    snakegrid.layout([bytes(f.geometry().asWkb()) for f in layer.getFeatures()], ids,
                     progress=lambda fraction, message: stages.append(message))
    log = Log()
    run("gridmap", INPUT=layer, ID_FIELD="code", OUTPUT="memory:", feedback=log)
    # The outline's stages run side by side, and its messages name those still running when
    # one ends, which depends on the threads: each message is compared by the stage it names.
    def named(messages):
        return {m.split(":")[0] for m in messages}

    assert "outline" in named(stages)
    assert named(stages) <= named(log.texts)


def test_selected_features_only(qgis_app):
    layer = QgsVectorLayer(US_STATES, "us_states", "ogr")
    layer.selectByExpression("\"id\" IN ('06','41','53','32','16')")
    # A selection lives on a layer of the project: the source is named by the layer's id.
    QgsProject.instance().addMapLayer(layer)
    try:
        source = QgsProcessingFeatureSourceDefinition(layer.id(), selectedFeaturesOnly=True)
        result = run("gridmap", INPUT=source, ID_FIELD="id", OUTPUT="memory:")
        assert sorted(layout(result["OUTPUT"])) == ["06", "16", "32", "41", "53"]
    finally:
        QgsProject.instance().removeMapLayer(layer.id())


def test_a_memory_layer_works(qgis_app):
    layer = squares_layer([f"r{k}" for k in range(9)])
    result = run("gridmap", INPUT=layer, ID_FIELD="code", OUTPUT="memory:")
    grid = result["OUTPUT"]
    assert_square_cells(grid, 9)
    # A 3 x 3 block of equal squares is already a grid map: it is kept as it is.
    assert result["C_ADJACENT"] == pytest.approx(1.0)
    assert layout(grid, "code") == {f"r{k}": (k % 3, 2 - k // 3) for k in range(9)}


def test_a_lon_lat_layer_gets_the_librarys_named_crs(us_states_lonlat, tmp_path):
    import snakegrid

    log = Log()
    grid = run("gridmap", INPUT=us_states_lonlat, ID_FIELD="id", OUTPUT="memory:",
               feedback=log)["OUTPUT"]
    assert_square_cells(grid, 49)
    assert layout(grid) == layout(cli(str(tmp_path / "cli.gpkg"), us_states_lonlat))
    # The name QGIS shows is the one the library gives the layer's regions, up to its first
    # "°": QGIS 3.22's fromWkt reads WKT as Latin-1, so every non-ASCII character becomes a
    # replacement character (GDAL's GeoPackage writer does the same to the command line's).
    source = QgsVectorLayer(us_states_lonlat, "source", "ogr")
    boxes = [f.geometry().boundingBox() for f in source.getFeatures()]
    chosen = snakegrid.working_crs(
        [(b.xMinimum(), b.yMinimum(), b.xMaximum(), b.yMaximum()) for b in boxes])
    name = grid.crs().description()
    assert name and name.startswith(chosen.name.split("°")[0])
    assert len(name) == len(chosen.name)
    out = str(tmp_path / "grid.gpkg")
    run("gridmap", INPUT=us_states_lonlat, ID_FIELD="id", OUTPUT=out)
    assert QgsVectorLayer(out, "grid", "ogr").crs().description() == name


def test_the_librarys_notes_on_the_layers_crs(us_states_lonlat, tmp_path):
    import processing

    # A layer in Web Mercator is weighed by its drawn areas; the log says so as the CLI does.
    mercator = str(tmp_path / "us_states_3857.gpkg")
    processing.run("native:reprojectlayer", {
        "INPUT": US_STATES, "TARGET_CRS": QgsCoordinateReferenceSystem("EPSG:3857"),
        "OUTPUT": mercator})
    log = Log()
    run("gridmap", INPUT=mercator, ID_FIELD="id", OUTPUT="memory:", feedback=log)
    assert any("EPSG:3857 is a Mercator projection" in line for line in log.lines), log.lines
    log = Log()
    run("gridmap", INPUT=US_STATES, ID_FIELD="id", OUTPUT="memory:", feedback=log)
    assert not any("Mercator" in line for line in log.lines), log.lines
    # Squares a degree wide without a CRS: the log suggests setting one; a kilometre wide, not.
    for side, hinted in [(1.0, True), (1000.0, False)]:
        bare = squares_layer([f"r{k}" for k in range(9)], crs="", side=side)
        assert not bare.crs().isValid()
        log = Log()
        run("gridmap", INPUT=bare, ID_FIELD="code", OUTPUT="memory:", feedback=log)
        warned = [line for line in log.lines if "has no CRS" in line]
        assert warned and ("set the layer's CRS" in warned[0]) == hinted, log.lines


def test_target_crs_gives_square_cells_in_it(us_states_lonlat, tmp_path):
    result = run("gridmap", INPUT=us_states_lonlat, ID_FIELD="id", OUTPUT="memory:",
                 TARGET_CRS="EPSG:3857")
    grid = result["OUTPUT"]
    assert grid.crs().authid() == "EPSG:3857"
    assert_square_cells(grid, 49)
    expected = cli(str(tmp_path / "cli.gpkg"), us_states_lonlat, "--t_srs", "EPSG:3857")
    assert layout(grid) == layout(expected)


def test_cancel_ends_the_run_as_cancelled_with_no_layer(qgis_app):
    """As the dialog runs it: a task, and the Cancel button cancels the feedback. QGIS 3.22's
    task reports any run whose feedback was cancelled as not successful (the dialog then adds
    its own "Execution failed after" line); the algorithm's part is to end at once, say
    "Cancelled", report no error and leave no output to load."""
    alg = algorithm("gridmap")
    context = QgsProcessingContext()
    context.setProject(QgsProject.instance())
    log = Log()
    started = threading.Event()

    def progress(value):
        if value > 10.5:  # reading done, the library is at work
            started.set()

    log.progressChanged.connect(progress)
    task = QgsProcessingAlgRunnerTask(
        alg, {"INPUT": US_COUNTIES, "ID_FIELD": "id", "OUTPUT": "TEMPORARY_OUTPUT"},
        context, log)
    outcome = []
    task.executed.connect(lambda ok, results: outcome.append((ok, results)))
    QgsApplication.taskManager().addTask(task)
    while not started.is_set() and not outcome:
        QgsApplication.processEvents()
        started.wait(0.05)
    log.cancel()
    while not outcome:
        QgsApplication.processEvents()
        threading.Event().wait(0.05)
    _, results = outcome[0]
    assert "OUTPUT" not in results
    assert not [line for line in log.lines if line.startswith("error:")], log.lines
    assert not context.layersToLoadOnCompletion()
    assert log.lines[-1] == "Cancelled"


def test_cancel_from_a_script_returns_no_output(qgis_app):
    log = Log()
    threading.Timer(0.5, log.cancel).start()
    results = run("gridmap", INPUT=US_COUNTIES, ID_FIELD="id", OUTPUT="memory:", feedback=log)
    assert "OUTPUT" not in results and "Cancelled" in log.lines


def bad_cases():
    with open(os.path.join(BAD, "cases.tsv"), encoding="utf-8") as f:
        rows = [r for r in csv.reader(f, delimiter="\t") if r and not r[0].startswith("#")]
    return [r for r in rows if r[2] == "invalid_input" and r[1] != "-"]


@pytest.mark.parametrize("case", bad_cases(), ids=lambda r: r[0])
def test_bad_input_gives_the_command_line_message(qgis_app, case, tmp_path):
    name, id_field, _, expected = case
    path = os.path.join(BAD, name)
    done = subprocess.run([CLI, "-q", "--id", id_field, str(tmp_path / "o.gpkg"), path],
                          capture_output=True, text=True)
    cli_message = done.stderr.strip().removeprefix("snakegrid: ERROR: ")
    assert done.returncode == 1 and expected in cli_message
    with pytest.raises(QgsProcessingException) as error:
        run("gridmap", INPUT=path, ID_FIELD=id_field, OUTPUT="memory:")
    assert str(error.value).split(": ", 1)[1] == cli_message


def test_hexagons_give_the_command_line_layout_and_a_hexjson_file(qgis_app, tmp_path):
    hexjson = str(tmp_path / "us.hexjson")
    result = run("gridmap", INPUT=US_STATES, ID_FIELD="id", OUTPUT="memory:", CELL="hex",
                 HEX_ORIENTATION="flat", HEXJSON=hexjson)
    grid = result["OUTPUT"]
    expected = layout(cli(str(tmp_path / "cli.gpkg"), US_STATES, "-cell", "hex",
                          "-hex_orientation", "flat"))
    assert layout(grid) == expected
    for feature in grid.getFeatures():
        assert feature.geometry().constGet().nCoordinates() == 7  # a closed hexagon
    assert result["HEXJSON"] == hexjson
    with open(hexjson, encoding="utf-8") as f:
        document = json.load(f)
    assert document["layout"] in ("odd-q", "even-q")
    assert sorted(document["hexes"]) == sorted(expected)
    # Squares have no HexJSON: refused before the layout.
    ok, message = algorithm("gridmap").checkParameterValues(
        {"INPUT": US_STATES, "OUTPUT": "memory:", "HEXJSON": hexjson}, QgsProcessingContext())
    assert not ok and "hex" in message


def test_a_bad_option_is_refused_by_name_before_reading(qgis_app):
    layer = squares_layer(["a", "b", "c"])
    alg = algorithm("gridmap")
    ok, message = alg.checkParameterValues(
        {"INPUT": layer, "ID_FIELD": "code", "OUTPUT": "memory:", "SHIFTS": "2:2"},
        QgsProcessingContext())
    assert not ok and "shifts" in message
    with pytest.raises(QgsProcessingException, match="shifts"):
        run("gridmap", INPUT=layer, ID_FIELD="code", OUTPUT="memory:", SHIFTS="2:2")
    ok, message = alg.checkParameterValues(
        {"INPUT": layer, "OUTPUT": "memory:", "SEED": str(2**64)}, QgsProcessingContext())
    assert not ok and "seed" in message


def test_a_64_bit_seed_runs(qgis_app):
    result = run("gridmap", INPUT=squares_layer(list("abcdef")), ID_FIELD="code",
                 OUTPUT="memory:", SEED=str(2**64 - 1))
    assert result["OUTPUT"].featureCount() == 6


def test_the_library_notes_are_logged(qgis_app):
    log = Log()
    run("gridmap", INPUT=os.path.join(BAD, "bowtie.geojson"), ID_FIELD="code",
        OUTPUT="memory:", feedback=log)
    assert any("feature bowtie: invalid polygon repaired" in line for line in log.lines)


def test_curved_polygons_are_linearised_as_the_command_line_does(qgis_app, tmp_path):
    source = os.path.join(BAD, "curved.csv")
    expected = layout(cli(str(tmp_path / "cli.gpkg"), source), "id")
    log = Log()
    result = run("gridmap", INPUT=source, ID_FIELD="id", OUTPUT="memory:", feedback=log)
    assert layout(result["OUTPUT"]) == expected
    assert any("feature a: curved geometry (CURVEPOLYGON) linearised" in line
               for line in log.lines)


def test_metrics_rescore_the_layout_and_see_an_edit(us_run):
    grid = us_run["OUTPUT"]
    scored = run("gridmetrics", REGIONS=US_STATES, REGION_ID="id", GRID=grid,
                 OUTPUT="memory:")
    for name in METRICS:
        assert scored[name] == pytest.approx(us_run[name], abs=1e-9), name
    assert scored["OUTPUT"].featureCount() == 49
    by_id = {f["id"]: f for f in scored["OUTPUT"].getFeatures()}
    for feature in grid.getFeatures():
        for field in ("cell_disp", "nbr_kept", "orient_err"):
            assert by_id[feature["id"]][field] == pytest.approx(feature[field]), field

    # Swap the cells of Maine and California: a worse layout, scored as such.
    edited = grid.materialize(QgsFeatureRequest())
    cells = {f["id"]: f for f in edited.getFeatures()}
    edited.startEditing()
    edited.changeGeometry(cells["23"].id(), cells["06"].geometry())
    edited.changeGeometry(cells["06"].id(), cells["23"].geometry())
    edited.commitChanges()
    worse = run("gridmetrics", REGIONS=US_STATES, REGION_ID="id", GRID=edited,
                OUTPUT="memory:")
    assert worse["C_ADJACENT"] < scored["C_ADJACENT"]
    assert worse["C_LOCATION"] > scored["C_LOCATION"]


def test_metrics_refuse_a_missing_cell_naming_it(us_run):
    grid = us_run["OUTPUT"].materialize(
        QgsFeatureRequest().setFilterExpression("\"id\" <> '06'"))
    with pytest.raises(QgsProcessingException, match="snakegrid_score: feature 06: "):
        run("gridmetrics", REGIONS=US_STATES, REGION_ID="id", GRID=grid, OUTPUT="memory:")


def test_a_missing_package_or_foreign_library_is_explained(qgis_app, monkeypatch):
    from snakegrid_qgis import library

    monkeypatch.setitem(sys.modules, "snakegrid", None)  # import snakegrid now fails
    alg = algorithm("gridmap")
    ok, message = alg.canExecute()
    command = f"{PYTHON} -m pip install --user --break-system-packages {library.wheel_name()}"
    assert not ok and command in message and library.RELEASES in message
    assert QgsApplication.processingRegistry().providerById("snakegrid").warningMessage() \
        == message
    with pytest.raises(QgsProcessingException, match=re.escape(command)):
        run("gridmap", INPUT=squares_layer(["a", "b"]), OUTPUT="memory:")
    monkeypatch.undo()
    # Any shared library without snakegrid's functions: Python's own ctypes module will do.
    monkeypatch.setenv("SNAKEGRID_LIBRARY", _ctypes.__file__)
    ok, message = alg.canExecute()
    assert not ok and "not a snakegrid library" in message and command in message


def test_the_plugin_names_the_wheel_that_is_built():
    from snakegrid_qgis import library

    assert library.wheel_name() == os.path.basename(WHEEL)


# --- the plugin installed from its zips, run by qgis_process ---------------------------------

def plugin_env(tmp_path_factory, archive, user_base):
    """An environment in which qgis_process finds the plugin unpacked from `archive`, with
    `user_base` as the user's Python site (empty: no snakegrid package)."""
    plugins = tmp_path_factory.mktemp("plugins")
    with zipfile.ZipFile(archive) as z:
        z.extractall(plugins)
    env = dict(os.environ, QT_QPA_PLATFORM="offscreen", QGIS_PLUGINPATH=str(plugins),
               PYTHONUSERBASE=user_base,
               QGIS_CUSTOM_CONFIG_PATH=str(tmp_path_factory.mktemp("qgis_process_profile")))
    env.pop("SNAKEGRID_LIBRARY", None)  # the plugin must find its library on its own
    subprocess.run(["/usr/bin/qgis_process.bin", "plugins", "enable", "snakegrid_qgis"],
                   env=env, check=True, capture_output=True)
    return env


@pytest.fixture(scope="module")
def offline_plugin(tmp_path_factory):
    return plugin_env(tmp_path_factory, os.environ["SNAKEGRID_PLUGIN_ZIP"],
                      str(tmp_path_factory.mktemp("empty_user_base")))


@pytest.fixture(scope="module")
def repository_plugin_without_wheel(tmp_path_factory):
    return plugin_env(tmp_path_factory, os.environ["SNAKEGRID_PLUGIN_REPOSITORY_ZIP"],
                      str(tmp_path_factory.mktemp("empty_user_base")))


@pytest.fixture(scope="module")
def repository_plugin_with_wheel(tmp_path_factory):
    user_base = str(tmp_path_factory.mktemp("user_base"))
    install_wheel(user_base)
    return plugin_env(tmp_path_factory, os.environ["SNAKEGRID_PLUGIN_REPOSITORY_ZIP"],
                      user_base)


def qgis_process(env, *arguments):
    return subprocess.run(["/usr/bin/qgis_process.bin", *arguments], env=env,
                          capture_output=True, text=True, timeout=300)


@pytest.mark.parametrize("plugin", ["offline_plugin", "repository_plugin_with_wheel"])
def test_qgis_process_runs_the_algorithm(plugin, request, cli_layout, tmp_path):
    env = request.getfixturevalue(plugin)
    out, outline = str(tmp_path / "grid.gpkg"), str(tmp_path / "outline.gpkg")
    done = qgis_process(env, "run", "snakegrid:gridmap", "--", f"INPUT={US_STATES}",
                        "ID_FIELD=id", "LABEL_FIELD=abbr", "MAX_STEPS=30", f"OUTPUT={out}",
                        f"OUTLINE={outline}")
    assert done.returncode == 0, done.stdout + done.stderr
    assert re.search(r"C_ADJACENT:\s+0\.\d+", done.stdout)
    assert layout(out) == cli_layout
    assert QgsVectorLayer(outline, "outline", "ogr").featureCount() == 1


# Squares across ±180°, split there, and drawn with rings that step across it (as d3's
# world-atlas draws Russia): both are one small layer, laid out in the same CRS as the CLI's.
@pytest.mark.parametrize("source", [ANTIMERIDIAN, ANTIMERIDIAN_STEPPING])
def test_qgis_process_lays_out_the_antimeridian_layer_as_the_command_line(
        offline_plugin, tmp_path, source):
    out = str(tmp_path / "grid.gpkg")
    done = qgis_process(offline_plugin, "run", "snakegrid:gridmap", "--",
                        f"INPUT={source}", "ID_FIELD=code", f"OUTPUT={out}")
    assert done.returncode == 0, done.stdout + done.stderr
    assert "Lambert azimuthal equal-area centred on the layer" in done.stdout
    expected = cli(str(tmp_path / "cli.gpkg"), source, id_field="code")
    assert layout(out, "code") == layout(expected, "code")
    grid = QgsVectorLayer(out, "grid", "ogr")
    assert grid.crs().description() == QgsVectorLayer(expected, "cli", "ogr").crs().description()


def test_qgis_process_help_is_plain_text(offline_plugin):
    done = qgis_process(offline_plugin, "help", "snakegrid:gridmap")
    assert done.returncode == 0
    assert "snake model" in done.stdout and "MAX_STEPS" in done.stdout
    assert not re.search(r"<(p|b|i|ul|li)>", done.stdout)


def test_qgis_process_without_the_package_says_how_to_install_it(
        repository_plugin_without_wheel, tmp_path):
    from snakegrid_qgis import library

    command = f"{PYTHON} -m pip install --user --break-system-packages {library.wheel_name()}"
    helped = qgis_process(repository_plugin_without_wheel, "help", "snakegrid:gridmap")
    assert command in helped.stdout
    done = qgis_process(repository_plugin_without_wheel, "run", "snakegrid:gridmap", "--",
                        f"INPUT={US_STATES}", f"OUTPUT={tmp_path / 'grid.gpkg'}")
    assert done.returncode != 0
    assert command in done.stdout + done.stderr


# --- the repository build ---------------------------------------------------------------------

#: First bytes of compiled files: ELF, PE (MZ), Mach-O (both byte orders, 32 and 64 bit, fat).
MAGIC = (b"\x7fELF", b"MZ", b"\xfe\xed\xfa\xce", b"\xfe\xed\xfa\xcf", b"\xce\xfa\xed\xfe",
         b"\xcf\xfa\xed\xfe", b"\xca\xfe\xba\xbe")
COMPILED = (".so", ".dll", ".dylib", ".pyd", ".pyc", ".pyo", ".exe")
#: What plugins.qgis.org requires in metadata.txt (and what we promise: tags, homepage).
REQUIRED = ("name", "qgisMinimumVersion", "description", "about", "version", "author", "email",
            "repository", "tracker", "homepage", "tags", "changelog")


def test_the_repository_build_is_pure_python_with_complete_metadata():
    with zipfile.ZipFile(os.environ["SNAKEGRID_PLUGIN_REPOSITORY_ZIP"]) as z:
        names = z.namelist()
        assert all(n.startswith("snakegrid_qgis/") for n in names)
        for name in names:
            assert not name.lower().endswith(COMPILED), name
            assert not z.read(name).startswith(MAGIC), name
        metadata = configparser.ConfigParser(interpolation=None)
        metadata.read_string(z.read("snakegrid_qgis/metadata.txt").decode("utf-8"))
        licence = z.read("snakegrid_qgis/LICENSE").decode("utf-8")
    general = metadata["general"]
    for field in REQUIRED:
        assert general.get(field, "").strip(), f"metadata.txt lacks {field}"
    assert "example.org" not in str(dict(general))
    assert os.path.basename(WHEEL) in general["about"]
    assert general["version"] in os.path.basename(WHEEL)
    assert licence.startswith("MIT License")
