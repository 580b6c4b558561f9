#!/usr/bin/env bash
# Builds the QGIS plugin zip, one top folder snakegrid_qgis/ as QGIS expects:
# - by default the offline zip (target/snakegrid-qgis-plugin.zip): the plugin with the snakegrid
#   Python package vendored in snakegrid_qgis/vendor/, taken from the wheel that
#   scripts/build-wheel.sh builds (so its GDAL-free library is inside), for Install from ZIP;
# - with --repository, the build for plugins.qgis.org (target/snakegrid-qgis-plugin-repository.zip):
#   pure Python, no compiled file; it uses the snakegrid wheel installed in QGIS's Python and says
#   how to install it when it is missing.
#
# Usage: scripts/build-qgis-plugin.sh [--repository] [OUT.zip]     (prints the zip's path)
set -euo pipefail

root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
kind=offline
if [ "${1:-}" = "--repository" ]; then
    kind=repository
    shift
fi
default="$root/target/snakegrid-qgis-plugin.zip"
[ "$kind" = repository ] && default="$root/target/snakegrid-qgis-plugin-repository.zip"
out="${1:-$default}"
mkdir -p "$(dirname "$out")"
out="$(realpath "$out")"

staging="$(mktemp -d)"
trap 'rm -rf "$staging"' EXIT
# The plugin's files only: no tests, no Python caches.
cp -r "$root/qgis-plugin/snakegrid_qgis" "$staging/snakegrid_qgis"
find "$staging" -name __pycache__ -type d -prune -exec rm -rf {} +
if [ "$kind" = offline ]; then
    wheel="$("$root/scripts/build-wheel.sh")"
    python3 -c '
import sys, zipfile
with zipfile.ZipFile(sys.argv[1]) as z:
    z.extractall(sys.argv[2], [n for n in z.namelist() if n.startswith("snakegrid/")])
' "$wheel" "$staging/snakegrid_qgis/vendor"
fi

rm -f "$out"
(cd "$staging" && python3 -c '
import os, sys, zipfile
with zipfile.ZipFile(sys.argv[1], "w", zipfile.ZIP_DEFLATED) as z:
    for folder, _, files in sorted(os.walk("snakegrid_qgis")):
        for name in sorted(files):
            path = os.path.join(folder, name)
            z.write(path, path)
' "$out")
echo "$out"
