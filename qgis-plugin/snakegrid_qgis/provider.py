"""The Processing provider "snakegrid": its algorithms, icon and version."""

import os

from qgis.core import QgsProcessingProvider
from qgis.PyQt.QtGui import QIcon

from . import binding
from .algorithms.gridmap import GridMapAlgorithm
from .algorithms.metrics import GridMetricsAlgorithm

ICON = os.path.join(os.path.dirname(__file__), "icon.svg")


def plugin_version():
    """The version in metadata.txt, so that there is one place to change it."""
    with open(os.path.join(os.path.dirname(__file__), "metadata.txt"), encoding="utf-8") as f:
        for line in f:
            if line.startswith("version="):
                return line.split("=", 1)[1].strip()
    return "unknown"


class SnakegridProvider(QgsProcessingProvider):
    def id(self):
        return "snakegrid"

    def name(self):
        return "snakegrid"

    def longName(self):  # noqa: N802 (QGIS's name)
        return f"snakegrid grid maps {plugin_version()}"

    def icon(self):
        return QIcon(ICON)

    def svgIconPath(self):  # noqa: N802
        return ICON

    def versionInfo(self):  # noqa: N802
        try:
            library = f"library {binding.load().version}"
        except binding.LibraryError:
            library = "library not found"
        return f"{plugin_version()} ({library})"

    def warningMessage(self):  # noqa: N802
        # Shown by QGIS above the algorithm dialogs: a missing library is said up front.
        try:
            binding.load()
        except binding.LibraryError as e:
            return str(e)
        return ""

    def loadAlgorithms(self):  # noqa: N802
        self.addAlgorithm(GridMapAlgorithm())
        self.addAlgorithm(GridMetricsAlgorithm())
