#!/usr/bin/env bash
# Runs the QGIS plugin's tests with Debian's QGIS, headless: builds the release library and
# command line and the plugin zip, then pytest on qgis-plugin/tests with Debian's /usr/bin/python3
# (the one python3-qgis is for). The qgis_process tests install the plugin from that zip.
# Installs nothing; needs the Debian packages
#   qgis python3-qgis qgis-providers python3-pytest xvfb
# Ends with pytest's summary line. Extra arguments go to pytest (e.g. -k metrics).
set -euo pipefail

root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
cargo build --manifest-path "$root/Cargo.toml" --release --lib --bin snakegrid
export SNAKEGRID_PLUGIN_ZIP="$("$root/scripts/build-qgis-plugin.sh")"
export SNAKEGRID_LIBRARY="$root/target/release/libsnakegrid.so"
export QT_QPA_PLATFORM=offscreen
export XDG_RUNTIME_DIR="${XDG_RUNTIME_DIR:-$(mktemp -d)}"
cd "$root/qgis-plugin"
exec /usr/bin/python3 -m pytest -p no:cacheprovider -ra "$@" tests
