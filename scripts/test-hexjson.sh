#!/usr/bin/env bash
# Checks a HexJSON file against the grid layer it describes, with d3-hexjson itself: the centres
# d3-hexjson's renderHexJSON computes for the hexes must be the layer's cell centroids up to one
# similarity transform (and SVG's y flip); see scripts/check-hexjson-centres.py.
#
#   scripts/test-hexjson.sh FILE.hexjson GRID.gpkg KEYFIELD [LAYER]
#
# KEYFIELD is the layer's field holding the HexJSON keys. d3-hexjson (pinned below, with its one
# dependency d3-array) is installed from npm into HEXJSON_NODE_DIR (default target/hexjson-node)
# the first time only. Needs Node >= 18 with npm (apt-get install -y nodejs npm), and Python 3
# with numpy, shapely and pyogrio. Exits non-zero when the centres do not match.
set -euo pipefail

D3_HEXJSON=1.1.1 # the last release (2024); its src/render.js is what the check relies on
D3_ARRAY=1.2.4   # the newest d3-array 1.x, which d3-hexjson 1.1.1 asks for ("d3-array": "1")

if [ $# -lt 3 ] || [ $# -gt 4 ]; then
    echo "usage: scripts/test-hexjson.sh FILE.hexjson GRID.gpkg KEYFIELD [LAYER]" >&2
    exit 2
fi
hexjson=$1
grid=$2
key_field=$3
layer=${4:-}
for f in "$hexjson" "$grid"; do
    [ -f "$f" ] || { echo "no such file: $f" >&2; exit 2; }
done

root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
cache="${HEXJSON_NODE_DIR:-$root/target/hexjson-node}"

command -v node >/dev/null || { echo "node not found (apt-get install -y nodejs npm)" >&2; exit 2; }
node_major=$(node -p 'process.versions.node.split(".")[0]')
if [ "$node_major" -lt 18 ]; then
    echo "Node >= 18 needed, found $(node --version)" >&2
    exit 2
fi

installed=$(HEXJSON_CACHE="$cache" node -p \
    "try { require(process.env.HEXJSON_CACHE + '/node_modules/d3-hexjson/package.json').version } catch (e) { '' }")
if [ "$installed" != "$D3_HEXJSON" ]; then
    command -v npm >/dev/null || { echo "npm not found (apt-get install -y npm)" >&2; exit 2; }
    echo "installing d3-hexjson@$D3_HEXJSON into $cache" >&2
    mkdir -p "$cache"
    npm install --prefix "$cache" --no-audit --no-fund --ignore-scripts --loglevel=error \
        "d3-hexjson@$D3_HEXJSON" "d3-array@$D3_ARRAY" >&2
fi

work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
# The drawing's size does not matter (the fit takes out the scale); 1000 x 1000 pixels.
node "$root/tests/hexjson/centres.mjs" "$hexjson" 1000 1000 "$cache/node_modules" >"$work/centres.json"
python3 "$root/scripts/check-hexjson-centres.py" "$work/centres.json" "$grid" "$key_field" ${layer:+"$layer"}
