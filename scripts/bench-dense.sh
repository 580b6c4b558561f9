#!/usr/bin/env bash
# How the command line's time and peak memory grow with the number of vertices (issue 12): the
# shared us_states and us_counties densified (scripts/make-test-layers.py densify: every edge
# cut up with a wiggle both neighbours share, so adjacency is kept) to 10^5, 10^6 and 10^7
# vertices, world_countries in longitude and latitude densified to 8 x 10^6 (issue 12's OSM world:
# a lon/lat layer, its regions' boundaries as long as a country's, one crossing itself), and one
# region of 200,000 vertices (a square and a star). Each is laid out with the
# defaults (or the options given); wall time is the median of 5 runs where one takes under a
# minute (else one run), peak resident memory from GNU time, and the growth exponent fitted to
# time ∝ vertices^k between successive sizes of one layer. Prints a Markdown table for
# BENCHMARKS.md.
#
# Usage: scripts/bench-dense.sh [LAYERS] [SNAKEGRID OPTIONS...]
#        LAYERS: comma-separated names, default all: us_states_1e5,...,us_counties_1e7,
#                world_lonlat_8e6,square,star
# Environment: SNAKEGRID_DATA (default ../shared/data), DENSE_DIR (where the generated layers
# are kept between runs, default /tmp/snakegrid-dense; the 10^7 ones take about a minute each to
# make). Needs GNU time (/usr/bin/time), GDAL's ogr2ogr, Python 3 with shapely, numpy, pyogrio
# and pyproj.
set -euo pipefail

root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
data="${SNAKEGRID_DATA:-$root/../shared/data}"
dense="${DENSE_DIR:-/tmp/snakegrid-dense}"
default_layers=us_states_1e5,us_states_1e6,us_states_1e7,us_counties_1e5,us_counties_1e6,us_counties_1e7,world_lonlat_8e6,square,star
layers="${1:-$default_layers}"
shift || true
cli="$root/target/release/snakegrid"
[ -x "$cli" ] || cargo build --manifest-path "$root/Cargo.toml" --release --bin snakegrid
make_layer="$root/scripts/make-test-layers.py"
mkdir -p "$dense"
# shellcheck source=scripts/timed-runs.sh
source "$root/scripts/timed-runs.sh"
work="$(mktemp -d)"
trap 'rm -rf "$work"' EXIT

# The layer file for a name, made on first use.
layer_file() {
    local name=$1 file="$dense/$1.gpkg"
    if [ ! -f "$file" ]; then
        case "$name" in
            square | star) python3 "$make_layer" "$name" 200000 "$file" ;;
            world_lonlat_*)
                ogr2ogr -overwrite -t_srs EPSG:4326 -nln world_lonlat "$dense/world_lonlat.gpkg" \
                    "$data/world_countries.gpkg"
                python3 "$make_layer" densify "$dense/world_lonlat.gpkg" "${name##*_}" "$file"
                ;;
            *) python3 "$make_layer" densify "$data/${name%_*}.gpkg" "${name##*_}" "$file" ;;
        esac
    fi
    echo "$file"
}

bench_header "$root" "$@"
echo "| layer | vertices | runs | median wall (s) | peak memory (MB) | growth k (time ∝ vertices^k) |"
echo "|---|---:|---:|---:|---:|---:|"
previous=""
for name in ${layers//,/ }; do
    file="$(layer_file "$name")"
    vertices="$(python3 -c 'import sys, pyogrio.raw, shapely
wkb = pyogrio.raw.read(sys.argv[1], read_geometry=True, columns=[])[2]
print(int(shapely.get_num_coordinates(shapely.from_wkb(wkb)).sum()))' "$file")"
    timed_runs "$work" "$cli" -q -overwrite "$@" "$work/out.gpkg" "$file"
    growth="–"
    # Successive sizes of one layer (us_states_1e5 → us_states_1e6) give the exponent.
    if [ -n "$previous" ] && [ "${previous%% *}" = "${name%_*}" ]; then
        read -r _ pv pt <<< "$previous"
        growth="$(growth_exponent "$vertices" "$median" "$pv" "$pt")"
    fi
    printf '| %s | %s | %s | %s | %s | %s |\n' "$name" "$vertices" "$runs" "$median" "$((memory / 1024))" "$growth"
    previous="${name%_*} $vertices $median"
done
