"""The Processing provider "snakegrid": its algorithms, icon and version."""

import os

from qgis.core import QgsProcessingProvider
from qgis.PyQt.QtGui import QIcon

from . import library
from .algorithms.gridmap import GridMapAlgorithm, RelayoutAlgorithm
from .algorithms.metrics import GridMetricsAlgorithm

ICON = os.path.join(os.path.dirname(__file__), "icon.svg")


class SnakegridProvider(QgsProcessingProvider):
    def id(self):
        return "snakegrid"

    def name(self):
        return "snakegrid"

    def longName(self):  # noqa: N802 (QGIS's name)
        return f"snakegrid grid maps {library.plugin_version()}"

    def icon(self):
        return QIcon(ICON)

    def svgIconPath(self):  # noqa: N802
        return ICON

    def versionInfo(self):  # noqa: N802
        if library.problem():
            return f"{library.plugin_version()} (snakegrid package not found)"
        import snakegrid

        return f"{library.plugin_version()} (library {snakegrid.library_version()})"

    def warningMessage(self):  # noqa: N802
        # Shown by QGIS above the algorithm dialogs: a missing package is said up front.
        return library.problem() or ""

    def loadAlgorithms(self):  # noqa: N802
        self.addAlgorithm(GridMapAlgorithm())
        self.addAlgorithm(GridMetricsAlgorithm())
        self.addAlgorithm(RelayoutAlgorithm())
