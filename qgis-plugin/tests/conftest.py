"""One headless QGIS for the whole session, with Processing and the snakegrid provider.

Run with Debian's /usr/bin/python3 (python3-qgis), e.g. scripts/test-qgis-plugin.sh. The library
is $SNAKEGRID_LIBRARY, else target/release/libsnakegrid.so of this repository.
"""

import gc
import os
import sys

import pytest

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
PLUGIN_PARENT = os.path.join(ROOT, "qgis-plugin")
DATA = os.environ.get("SNAKEGRID_DATA_DIR", os.path.join(os.path.dirname(ROOT), "shared", "data"))
CLI = os.environ.get("SNAKEGRID_CLI", os.path.join(ROOT, "target", "release", "snakegrid"))

os.environ.setdefault("QT_QPA_PLATFORM", "offscreen")
os.environ.setdefault(
    "SNAKEGRID_LIBRARY", os.path.join(ROOT, "target", "release", "libsnakegrid.so")
)
sys.path[:0] = [PLUGIN_PARENT, "/usr/share/qgis/python/plugins"]

from qgis.core import QgsApplication  # noqa: E402 (after the path set-up)


@pytest.fixture(scope="session")
def qgis_app(tmp_path_factory):
    # A private profile, so that the tests neither read nor change the user's settings.
    os.environ["QGIS_CUSTOM_CONFIG_PATH"] = str(tmp_path_factory.mktemp("profile"))
    app = QgsApplication([], False)
    app.initQgis()
    from processing.core.Processing import Processing

    from snakegrid.provider import SnakegridProvider

    Processing.initialize()
    provider = SnakegridProvider()
    QgsApplication.processingRegistry().addProvider(provider)
    yield app
    QgsApplication.processingRegistry().removeProvider(provider)
    # exitQgis crashes while Python still holds layers: the tests keep none past their end,
    # and this collects what a failed assertion's traceback left behind.
    gc.collect()
    app.exitQgis()
