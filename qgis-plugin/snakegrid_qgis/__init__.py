"""snakegrid QGIS plugin: grid maps (tile maps) in the Processing toolbox."""


def classFactory(iface):  # noqa: N802 (QGIS's name)
    """QGIS calls this to load the plugin."""
    from .plugin import SnakegridPlugin

    return SnakegridPlugin(iface)
