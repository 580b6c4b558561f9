#!/usr/bin/env bash
# Real layers the shared data does not have, from npm packages (the registry this machine can
# reach): d3's world-atlas (countries at 1:110m, 1:50m, 1:10m, in TopoJSON, with Russia and Fiji
# drawn by rings that step across ±180°) and Highcharts' map collection (the first-level
# divisions of countries, in TopoJSON in longitude and latitude: France with its overseas
# regions, Japan, Indonesia, the Philippines, Chile, Norway, Russia, ...). Each is written as a
# GeoPackage layer "regions" in EPSG:4326 with an id field `id` (world-atlas: the country name,
# its numeric code is missing for a few) and `name`. For trying snakegrid on countries and
# quirks it was not tuned on; the layers' licences are their packages' (Natural Earth's data,
# Highcharts' terms), so they are made here, not committed.
#
# Usage: scripts/make-npm-layers.sh [DIR] [all]   (default /tmp/npm-layers; needs npm and ogr2ogr)
#   all: also every country of Highcharts' collection, first-level divisions (DIR/hc/CC-all.gpkg)
#        and second-level ones where it has them (DIR/hc/CC-all-all.gpkg: Germany's districts,
#        the Netherlands' municipalities, the US counties, ...), for scripts/survey-layers.sh.
set -euo pipefail

out="${1:-/tmp/npm-layers}"
mkdir -p "$out/npm"
(cd "$out/npm" && npm install --silent --no-audit --no-fund @highcharts/map-collection world-atlas)
modules="$out/npm/node_modules"

for scale in 110m 50m 10m; do
    ogr2ogr -overwrite -f GPKG -a_srs EPSG:4326 -nln regions -nlt PROMOTE_TO_MULTI \
        -sql "SELECT name AS id, name FROM countries" \
        "$out/world$scale.gpkg" "$modules/world-atlas/countries-$scale.json"
done

collection="$modules/@highcharts/map-collection/countries"

# One of Highcharts' maps (TopoJSON) as a layer of regions. The second-level maps also hold
# separator lines (insets' frames) without a key: a layer of regions has none.
highcharts() {
    ogr2ogr -overwrite -f GPKG -a_srs EPSG:4326 -nln regions -nlt PROMOTE_TO_MULTI \
        -sql "SELECT \"hc-key\" AS id, name FROM \"default\" WHERE \"hc-key\" IS NOT NULL" \
        "$2" "$1"
}

countries="au br ca cl cn de dk es fr gb gr hr id in it jp mx no nz ph ru"
for country in $countries; do
    highcharts "$collection/$country/$country-all.topo.json" "$out/$country.gpkg"
done
echo "layers in $out: world110m world50m world10m $countries"

if [ "${2:-}" = all ]; then
    mkdir -p "$out/hc"
    for dir in "$collection"/*/; do
        country="$(basename "$dir")"
        for level in all all-all; do
            topo="$dir/$country-$level.topo.json"
            [ -f "$topo" ] || continue
            highcharts "$topo" "$out/hc/$country-$level.gpkg"
        done
    done
    echo "every country's divisions in $out/hc"
fi
