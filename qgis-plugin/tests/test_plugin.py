"""The snakegrid QGIS plugin under a headless QGIS: provider, algorithms, errors, qgis_process."""

import os
import re
import subprocess
import threading
import time
import zipfile

import _ctypes
import pytest
from qgis.core import (
    QgsApplication,
    QgsCoordinateReferenceSystem,
    QgsFeature,
    QgsFeatureRequest,
    QgsField,
    QgsGeometry,
    QgsPointXY,
    QgsProcessingFeatureSourceDefinition,
    QgsProcessingException,
    QgsProcessingFeedback,
    QgsProject,
    QgsRectangle,
    QgsVectorLayer,
)
from qgis.PyQt.QtCore import QVariant

from conftest import CLI, DATA, PLUGIN_PARENT

US_STATES = os.path.join(DATA, "us_states.gpkg")
GRID_FIELDS = ["grid_col", "grid_row", "cell_disp", "nbr_kept", "orient_err"]
METRICS = ["C_LOCATION", "C_ADJACENT", "C_ORIENTATION", "C_SHAPE"]


def run(algorithm, **parameters):
    import processing

    feedback = parameters.pop("feedback", None) or QgsProcessingFeedback()
    return processing.run(f"snakegrid:{algorithm}", parameters, feedback=feedback)


def layout(layer, id_field="id"):
    """{id: (grid_col, grid_row)} of a grid layer (a QgsVectorLayer or a path)."""
    if isinstance(layer, str):
        layer = QgsVectorLayer(layer, "grid", "ogr")
    return {str(f[id_field]): (f["grid_col"], f["grid_row"]) for f in layer.getFeatures()}


def squares_layer(ids, crs="EPSG:3857", side=1000.0, cols=3, kind="Polygon"):
    """A memory layer of squares in a block `cols` wide, ids from `ids`."""
    layer = QgsVectorLayer(f"{kind}?crs={crs}", "squares", "memory")
    provider = layer.dataProvider()
    provider.addAttributes([QgsField("code", QVariant.String)])
    layer.updateFields()
    features = []
    for k, region_id in enumerate(ids):
        x, y = side * (k % cols), side * (k // cols)
        feature = QgsFeature(layer.fields())
        feature.setAttributes([region_id])
        if kind == "Polygon":
            feature.setGeometry(QgsGeometry.fromRect(QgsRectangle(x, y, x + side, y + side)))
        else:
            feature.setGeometry(QgsGeometry.fromPointXY(QgsPointXY(x, y)))
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
        areas.append(geometry.area())
    assert max(areas) == pytest.approx(min(areas), rel=1e-9)
    cells = {(f["grid_col"], f["grid_row"]) for f in layer.getFeatures()}
    assert len(cells) == count, "two regions share a cell"


@pytest.fixture(scope="module")
def cli_layout(tmp_path_factory):
    out = str(tmp_path_factory.mktemp("cli") / "out.gpkg")
    subprocess.run([CLI, "-q", out, US_STATES, "--id", "id"], check=True)
    return layout(out)


@pytest.fixture(scope="module")
def us_run(qgis_app):
    return run("gridmap", INPUT=US_STATES, ID_FIELD="id", OUTPUT="memory:",
               OUTLINE="memory:")


def test_provider_and_algorithms_are_registered(qgis_app):
    registry = QgsApplication.processingRegistry()
    provider = registry.providerById("snakegrid")
    assert provider is not None
    assert not provider.icon().isNull()
    assert re.match(r"^\d+\.\d+\.\d+ \(library \d+\.\d+\.\d+\)$", provider.versionInfo())
    assert provider.warningMessage() == ""
    for algorithm in ("gridmap", "gridmetrics"):
        alg = registry.algorithmById(f"snakegrid:{algorithm}")
        assert alg is not None
        assert alg.canExecute() == (True, "")
        assert len(alg.shortHelpString()) > 300


def test_defaults_and_help_follow_the_command_line(qgis_app):
    from snakegrid.algorithms.gridmap import METHOD_PARAMETERS

    help_text = subprocess.run([CLI, "--help"], check=True, capture_output=True,
                               text=True).stdout
    cli = dict(re.findall(r"--(\w+) <VALUE>\n\s+.*?\[default: ([^\]]+)\]", help_text, re.S))
    table = {row[0]: row for row in METHOD_PARAMETERS}
    assert set(table) == set(cli), "the table and the command line list different parameters"

    def numbers(text):
        return [float(n) for n in re.split("[,:]", text)]

    alg = QgsApplication.processingRegistry().algorithmById("snakegrid:gridmap")
    for name, (_, _, kind, default, advanced, text) in table.items():
        expected = cli[name]
        if default is None or kind in ("bool", "enum"):
            assert str(default).lower() == expected, name
        else:
            assert numbers(str(default)) == numbers(expected), name
        parameter = alg.parameterDefinition(name)
        assert parameter is not None and parameter.help() == text
        assert bool(parameter.flags() & parameter.FlagAdvanced) == advanced
        assert f"({name}, default" in alg.shortHelpString()


def test_us_states_gives_the_command_line_layout(us_run, cli_layout):
    grid = us_run["OUTPUT"]
    assert_square_cells(grid, 49)
    names = grid.fields().names()
    source = QgsVectorLayer(US_STATES, "src", "ogr")
    assert names[: len(source.fields())] == source.fields().names()
    assert names[-5:] == GRID_FIELDS
    assert grid.crs().authid() == "EPSG:5070"
    assert layout(grid) == cli_layout
    assert 0 <= us_run["C_ADJACENT"] <= 1 and 0 <= us_run["C_SHAPE"] <= 1
    assert us_run["C_LOCATION"] >= 0 and 0 <= us_run["C_ORIENTATION"] <= 180
    outline = list(us_run["OUTLINE"].getFeatures())
    assert len(outline) == 1 and outline[0].geometry().isGeosValid()
    assert outline[0]["regions"] == 49


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


def test_a_geographic_layer_is_projected_like_the_command_line(qgis_app, tmp_path):
    import processing

    geographic = str(tmp_path / "us_states_4326.gpkg")
    processing.run("native:reprojectlayer", {
        "INPUT": US_STATES, "TARGET_CRS": QgsCoordinateReferenceSystem("EPSG:4326"),
        "OUTPUT": geographic})
    result = run("gridmap", INPUT=geographic, ID_FIELD="id", OUTPUT="memory:")
    grid = result["OUTPUT"]
    assert_square_cells(grid, 49)
    assert "+proj=laea" in grid.crs().toProj()
    out = str(tmp_path / "cli.gpkg")
    subprocess.run([CLI, "-q", out, geographic, "--id", "id"], check=True)
    assert layout(grid) == layout(out)


def test_cancelling_stops_the_run(qgis_app):
    feedback = QgsProcessingFeedback()
    # As the Cancel button does: another thread cancels the feedback during the run.
    threading.Timer(1.0, feedback.cancel).start()
    started = time.monotonic()
    with pytest.raises(QgsProcessingException, match="(?i)cancel"):
        run("gridmap", INPUT=US_STATES, ID_FIELD="id", OUTPUT="memory:", feedback=feedback,
            refine_moves=10_000_000)
    # Ten million refinement moves take far longer than this.
    assert time.monotonic() - started < 20


def test_a_point_layer_is_refused_readably(qgis_app):
    layer = squares_layer(["a", "b", "c"], kind="Point")
    with pytest.raises(QgsProcessingException) as error:
        run("gridmap", INPUT=layer, ID_FIELD="code", OUTPUT="memory:")
    assert "polygon" in str(error.value).lower()
    assert "Traceback" not in str(error.value)


def test_duplicate_ids_are_refused_naming_the_id(qgis_app):
    layer = squares_layer(["a", "b", "b", "c"])
    with pytest.raises(QgsProcessingException, match=r"snakegrid_run: .*\bb\b.*"):
        run("gridmap", INPUT=layer, ID_FIELD="code", OUTPUT="memory:")


def test_a_bad_option_gives_the_library_message(qgis_app):
    layer = squares_layer(["a", "b", "c"])
    with pytest.raises(QgsProcessingException, match="shifts"):
        run("gridmap", INPUT=layer, ID_FIELD="code", OUTPUT="memory:", shifts="2:2")


def test_metrics_rescore_the_layout_and_see_an_edit(us_run):
    grid = us_run["OUTPUT"]
    scored = run("gridmetrics", REGIONS=US_STATES, REGION_ID="id", GRID=grid,
                 OUTPUT="memory:")
    for name in METRICS:
        assert scored[name] == pytest.approx(us_run[name], abs=1e-9), name
    assert scored["OUTPUT"].featureCount() == 49
    by_id = {f["id"]: f for f in scored["OUTPUT"].getFeatures()}
    for feature in grid.getFeatures():
        assert by_id[feature["id"]]["nbr_kept"] == pytest.approx(feature["nbr_kept"])

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


def test_a_missing_or_foreign_library_is_explained(qgis_app, monkeypatch, tmp_path):
    from snakegrid import binding

    missing = str(tmp_path / "libsnakegrid.so")
    monkeypatch.setenv("SNAKEGRID_LIBRARY", missing)
    alg = QgsApplication.processingRegistry().algorithmById("snakegrid:gridmap")
    ok, message = alg.canExecute()
    assert not ok and missing in message and "SNAKEGRID_LIBRARY" in message
    provider = QgsApplication.processingRegistry().providerById("snakegrid")
    assert provider.warningMessage() == message
    with pytest.raises(QgsProcessingException, match="not found"):
        run("gridmap", INPUT=squares_layer(["a", "b"]), OUTPUT="memory:")
    # Any shared library without snakegrid's functions: Python's own ctypes module will do.
    with pytest.raises(binding.LibraryError, match="not a snakegrid library"):
        binding.Library(_ctypes.__file__)


@pytest.fixture(scope="module")
def installed_plugin(tmp_path_factory):
    """The plugin folder as QGIS installs it: from the zip when SNAKEGRID_PLUGIN_ZIP names one
    (scripts/test-qgis-plugin.sh builds it), else this source tree with $SNAKEGRID_LIBRARY."""
    archive = os.environ.get("SNAKEGRID_PLUGIN_ZIP")
    env = dict(os.environ, QT_QPA_PLATFORM="offscreen",
               QGIS_CUSTOM_CONFIG_PATH=str(tmp_path_factory.mktemp("qgis_process_profile")))
    if archive:
        plugins = tmp_path_factory.mktemp("plugins")
        with zipfile.ZipFile(archive) as z:
            assert "snakegrid/libsnakegrid.so" in z.namelist()
            assert "snakegrid/metadata.txt" in z.namelist()
            z.extractall(plugins)
        env.pop("SNAKEGRID_LIBRARY", None)  # the bundled library must be found on its own
        env["QGIS_PLUGINPATH"] = str(plugins)
    else:
        env["QGIS_PLUGINPATH"] = PLUGIN_PARENT
    subprocess.run(["/usr/bin/qgis_process.bin", "plugins", "enable", "snakegrid"],
                   env=env, check=True, capture_output=True)
    return env


def test_qgis_process_runs_the_algorithm(installed_plugin, cli_layout, tmp_path):
    out = str(tmp_path / "grid.gpkg")
    outline = str(tmp_path / "outline.gpkg")
    done = subprocess.run(
        ["/usr/bin/qgis_process.bin", "run", "snakegrid:gridmap", "--",
         f"INPUT={US_STATES}", "ID_FIELD=id", "LABEL_FIELD=abbr", f"OUTPUT={out}",
         f"OUTLINE={outline}"],
        env=installed_plugin, capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stdout + done.stderr
    assert re.search(r"C_ADJACENT:\s+0\.\d+", done.stdout)
    assert layout(out) == cli_layout
    assert QgsVectorLayer(outline, "outline", "ogr").featureCount() == 1


def test_qgis_process_lists_and_helps(installed_plugin):
    help_text = subprocess.run(
        ["/usr/bin/qgis_process.bin", "help", "snakegrid:gridmap"],
        env=installed_plugin, capture_output=True, text=True, check=True).stdout
    assert "snake model" in help_text and "max_steps" in help_text
