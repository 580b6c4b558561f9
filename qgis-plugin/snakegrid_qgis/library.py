"""The plugin's way to the snakegrid Python package and its library, and what to tell the user
when either is missing: the exact command that installs the wheel into the Python QGIS uses."""

import os

from qgis.core import QgsProcessingException

#: The project's home (to be confirmed by the owner before publishing).
HOME = "https://github.com/snakegrid/snakegrid"
RELEASES = f"{HOME}/releases"
#: The platform scripts/build-wheel.sh builds for (a test checks the wheel it writes).
WHEEL_PLATFORM = "manylinux_2_28_x86_64"


def plugin_version():
    """The version in metadata.txt, so that there is one place to change it (Cargo.toml's)."""
    path = os.path.join(os.path.dirname(__file__), "metadata.txt")
    with open(path, encoding="utf-8") as f:
        for line in f:
            if line.startswith("version="):
                return line.split("=", 1)[1].strip()
    return "unknown"


def wheel_name():
    return f"snakegrid-{plugin_version()}-py3-none-{WHEEL_PLATFORM}.whl"


def install_hint():
    wheel = wheel_name()
    return (
        f"Download {wheel} from {RELEASES} (or build it from the source with "
        "scripts/build-wheel.sh), install it into the Python QGIS uses, then restart QGIS. "
        "On Debian 12 and Ubuntu, where that Python is /usr/bin/python3 and externally "
        f"managed: /usr/bin/python3 -m pip install --user --break-system-packages {wheel} "
        "(needs the python3-pip package). Or install the offline plugin zip, which bundles it."
    )


def problem():
    """None when the package and its library load, else a sentence saying what to do."""
    try:
        import snakegrid
    except ImportError:
        return f"The snakegrid Python package is not installed. {install_hint()}"
    try:
        snakegrid.load()
    except snakegrid.LibraryError as e:
        return f"{e} {install_hint()}"
    return None


def package():
    """The snakegrid package with its library loaded; a missing one is a QgsProcessingException
    whose message says how to install it, which QGIS and qgis_process show as the error."""
    message = problem()
    if message:
        raise QgsProcessingException(message)
    import snakegrid

    return snakegrid
