"""Screenshot of the "Grid map (snake model)" dialog for the docs, under a virtual display:

    xvfb-run -a -s "-screen 0 1280x900x24" /usr/bin/python3 qgis-plugin/tools/screenshot.py \
        docs/qgis-dialog.png

A stand-in for QGIS's main window (qgis.utils.iface) is enough for the algorithm dialog."""

import os
import sys
from unittest import mock

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
# The package from the source tree, with the library scripts/build-wheel.sh builds.
sys.path[:0] = [os.path.join(ROOT, "qgis-plugin"), os.path.join(ROOT, "python"),
                "/usr/share/qgis/python/plugins"]
os.environ.setdefault("SNAKEGRID_LIBRARY", os.path.join(
    ROOT, "target", "wheel", "x86_64-unknown-linux-gnu", "release", "libsnakegrid.so"))
DATA = os.environ.get("SNAKEGRID_DATA_DIR", os.path.join(os.path.dirname(ROOT), "shared", "data"))
from qgis.core import QgsApplication, QgsVectorLayer, QgsProject
from qgis.PyQt.QtCore import QTimer
app = QgsApplication([], True)
app.initQgis()
from processing.core.Processing import Processing
Processing.initialize()
from snakegrid_qgis.provider import SnakegridProvider
provider = SnakegridProvider()
QgsApplication.processingRegistry().addProvider(provider)
layer = QgsVectorLayer(os.path.join(DATA, "us_states.gpkg"), "us_states", "ogr")
QgsProject.instance().addMapLayer(layer)
from qgis.gui import QgsMapCanvas
import qgis.utils
canvas = QgsMapCanvas()
qgis.utils.iface = mock.Mock()
qgis.utils.iface.mainWindow.return_value = None
qgis.utils.iface.mapCanvas.return_value = canvas
import processing.tools.general
processing.tools.general.iface = qgis.utils.iface
import processing
dialog = processing.createAlgorithmDialog(
    "snakegrid:gridmap", {"INPUT": layer.id(), "ID_FIELD": "id", "LABEL_FIELD": "abbr"})
dialog.resize(1000, 780)
dialog.show()
def grab():
    dialog.grab().save(sys.argv[1])
    app.quit()
QTimer.singleShot(1500, grab)
app.exec_()
