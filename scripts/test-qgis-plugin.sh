#!/usr/bin/env bash
# Runs the QGIS plugin's tests with Debian's QGIS, headless: builds the command line (to compare
# with), the snakegrid wheel and both plugin zips (offline and repository), then pytest on
# qgis-plugin/tests with Debian's /usr/bin/python3 (the one python3-qgis is for). The tests
# install the wheel under a temporary PYTHONUSERBASE and the plugin from the zips into temporary
# folders; they install nothing for good. Needs the Debian packages
#   qgis python3-qgis qgis-providers python3-pytest python3-pip python3-venv xvfb
# Ends with pytest's summary line. Extra arguments go to pytest (e.g. -k metrics).
set -euo pipefail

root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
cargo build --manifest-path "$root/Cargo.toml" --release --bin snakegrid
export SNAKEGRID_WHEEL="$("$root/scripts/build-wheel.sh")"
export SNAKEGRID_PLUGIN_ZIP="$("$root/scripts/build-qgis-plugin.sh")"
export SNAKEGRID_PLUGIN_REPOSITORY_ZIP="$("$root/scripts/build-qgis-plugin.sh" --repository)"
unset SNAKEGRID_LIBRARY
export QT_QPA_PLATFORM=offscreen
export XDG_RUNTIME_DIR="${XDG_RUNTIME_DIR:-$(mktemp -d)}"
cd "$root/qgis-plugin"
exec /usr/bin/python3 -m pytest -p no:cacheprovider -ra "$@" tests
