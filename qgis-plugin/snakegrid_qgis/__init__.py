"""snakegrid QGIS plugin: grid maps (tile maps) in the Processing toolbox.

The folder is snakegrid_qgis, not snakegrid: QGIS imports a plugin under its folder's name, and
the plugin imports the `snakegrid` Python package, which a plugin named snakegrid would hide.
"""

import os
import sys

# The offline zip vendors the snakegrid package (with its library) in vendor/; it goes first, so
# that the plugin runs the package it was built with. The repository build has no vendor/ and
# uses the package installed in QGIS's Python.
_VENDOR = os.path.join(os.path.dirname(os.path.abspath(__file__)), "vendor")
if os.path.isdir(_VENDOR) and _VENDOR not in sys.path:
    sys.path.insert(0, _VENDOR)


def classFactory(iface):  # noqa: N802 (QGIS's name)
    """QGIS calls this to load the plugin."""
    from .plugin import SnakegridPlugin

    return SnakegridPlugin(iface)
