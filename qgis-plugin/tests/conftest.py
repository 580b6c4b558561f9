"""One headless QGIS for the whole session, with Processing and the snakegrid provider, and the
snakegrid wheel installed as the plugin tells users to install it.

Run with Debian's /usr/bin/python3 (python3-qgis) by scripts/test-qgis-plugin.sh, which builds
the wheel ($SNAKEGRID_WHEEL), both plugin zips and the command line. The wheel goes in with the
plugin's own command, `/usr/bin/python3 -m pip install --user --break-system-packages WHEEL`,
under a temporary PYTHONUSERBASE, so the tests leave the user's site-packages as they were.
"""

import atexit
import gc
import glob
import os
import shutil
import subprocess
import sys
import tempfile

import pytest

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
PLUGIN_PARENT = os.path.join(ROOT, "qgis-plugin")
DATA = os.environ.get("SNAKEGRID_DATA_DIR", os.path.join(os.path.dirname(ROOT), "shared", "data"))
BAD = os.path.join(ROOT, "tests", "data", "bad")
CLI = os.environ.get("SNAKEGRID_CLI", os.path.join(ROOT, "target", "release", "snakegrid"))
WHEEL = os.environ.get("SNAKEGRID_WHEEL") or max(
    glob.glob(os.path.join(ROOT, "target", "wheels", "snakegrid-*.whl")), default="")
PYTHON = "/usr/bin/python3"


def install_wheel(user_base):
    """Installs the wheel into `user_base` with the command the plugin states; returns the
    site-packages folder it went to."""
    env = dict(os.environ, PYTHONUSERBASE=user_base, PIP_DISABLE_PIP_VERSION_CHECK="1")
    subprocess.run([PYTHON, "-m", "pip", "install", "-q", "--user", "--break-system-packages",
                    WHEEL], env=env, check=True)
    return subprocess.run([PYTHON, "-m", "site", "--user-site"], env=env, check=True,
                          capture_output=True, text=True).stdout.strip()


USER_BASE = tempfile.mkdtemp(prefix="snakegrid-userbase-")
atexit.register(shutil.rmtree, USER_BASE, True)
os.environ.setdefault("QT_QPA_PLATFORM", "offscreen")
# The wheel's own library, as a user has it.
os.environ.pop("SNAKEGRID_LIBRARY", None)
sys.path[:0] = [install_wheel(USER_BASE), PLUGIN_PARENT, "/usr/share/qgis/python/plugins"]

from qgis.core import QgsApplication  # noqa: E402 (after the path set-up)


@pytest.fixture(scope="session")
def qgis_app(tmp_path_factory):
    # A private profile, so that the tests neither read nor change the user's settings.
    os.environ["QGIS_CUSTOM_CONFIG_PATH"] = str(tmp_path_factory.mktemp("profile"))
    app = QgsApplication([], False)
    app.initQgis()
    from processing.core.Processing import Processing

    from snakegrid_qgis.provider import SnakegridProvider

    Processing.initialize()
    provider = SnakegridProvider()
    QgsApplication.processingRegistry().addProvider(provider)
    yield app
    QgsApplication.processingRegistry().removeProvider(provider)
    # exitQgis crashes while Python still holds layers: the tests keep none past their end,
    # and this collects what a failed assertion's traceback left behind.
    gc.collect()
    app.exitQgis()
