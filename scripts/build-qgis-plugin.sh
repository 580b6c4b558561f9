#!/usr/bin/env bash
# Builds the installable QGIS plugin zip: the release library without GDAL (the plugin reads and
# writes through QGIS, so the library links only the C runtime and loads beside any GDAL), then
# qgis-plugin/snakegrid/ with libsnakegrid.so beside its Python files, zipped as QGIS expects
# (one top folder, snakegrid/).
#
# Usage: scripts/build-qgis-plugin.sh [OUT.zip]     (default target/snakegrid-qgis-plugin.zip)
# Install it in QGIS with Plugins > Manage and Install Plugins > Install from ZIP.
set -euo pipefail

root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
out="${1:-$root/target/snakegrid-qgis-plugin.zip}"
mkdir -p "$(dirname "$out")"
out="$(realpath "$out")"

cargo build --manifest-path "$root/Cargo.toml" --release --lib --no-default-features
library="$root/target/release/libsnakegrid.so"
if ldd "$library" | grep -q gdal; then
    echo "build-qgis-plugin: $library links GDAL" >&2
    exit 1
fi

staging="$(mktemp -d)"
trap 'rm -rf "$staging"' EXIT
# The plugin's files only: no tests, no Python caches.
cp -r "$root/qgis-plugin/snakegrid" "$staging/snakegrid"
find "$staging" -name __pycache__ -type d -prune -exec rm -rf {} +
# Debug symbols are most of the library's size and of no use inside QGIS.
strip --strip-debug -o "$staging/snakegrid/libsnakegrid.so" "$library"

rm -f "$out"
(cd "$staging" && python3 -c '
import os, sys, zipfile
with zipfile.ZipFile(sys.argv[1], "w", zipfile.ZIP_DEFLATED) as z:
    for folder, _, files in sorted(os.walk("snakegrid")):
        for name in sorted(files):
            path = os.path.join(folder, name)
            z.write(path, path)
' "$out")
echo "$out"
