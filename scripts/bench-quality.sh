#!/usr/bin/env bash
# Quality of the layouts, measured by the shared judge (../shared/eval/gridmap_eval.py, the
# reference implementation of method.md §8), on every shared layer and on generated ones (random
# Voronoi layers, islands, a river-like gap, an archipelago, a thin country, a thin ring;
# scripts/make-test-layers.py), through the command line with the defaults, with -refine false,
# in hexagons and (us_counties) grouped by state; writes QUALITY.md with every metric in one
# table and the reference figures of other tools beside them. Re-run it before any stop that
# touches the core.
#
# Usage: scripts/bench-quality.sh [EXTRA SNAKEGRID OPTIONS...]    (from anywhere; needs a release
#        build, Python 3 with shapely, numpy, pyogrio and pyproj; about 5 minutes)
# Environment: SNAKEGRID_DATA (default ../shared/data), QUALITY_OUT (default QUALITY.md).
set -euo pipefail

root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
data="${SNAKEGRID_DATA:-$root/../shared/data}"
judge="$root/../shared/eval/gridmap_eval.py"
out="${QUALITY_OUT:-$root/QUALITY.md}"
cli="$root/target/release/snakegrid"
work="$(mktemp -d)"
trap 'rm -rf "$work"' EXIT
[ -x "$cli" ] || cargo build --manifest-path "$root/Cargo.toml" --release --bin snakegrid

make() { python3 "$root/scripts/make-test-layers.py" "$@"; }
make voronoi 300 1 "$work/voronoi_300.gpkg"
make voronoi 3000 2 "$work/voronoi_3000.gpkg"
make islands 3 "$work/islands.gpkg"
make river 300 4 "$work/river.gpkg"
# a city's 33 districts on the two banks of a river a tenth of a district wide
make river 33 6 "$work/river_33.gpkg"
make archipelago 3000 300 5 "$work/archipelago.gpkg"
# a long thin country of 40 regions, 0.7 cells wide
make strip 40 9 "$work/strip.gpkg"
# a country round a lake of 300 regions, 0.7 cells wide
make ring 300 0.7 1 "$work/ring.gpkg"
# us_states with neighbours a five-hundredth of a cell apart, judged against us_states itself
# (its own regions share no border for the judge to count)
make apart "$data/us_states.gpkg" 0.001 "$work/us_states_apart.gpkg"
# and drawn over each other's borders: neighbours overlapping by a five-hundredth of a cell
make apart "$data/us_states.gpkg" -0.001 "$work/us_states_over.gpkg"
# us_counties with every county simplified alone by a sixteenth of a cell (ogr2ogr -simplify)
make simplify "$data/us_counties.gpkg" 0.06 "$work/us_counties_simplified.gpkg"
# the world's countries cut into 3,000 provinces, small countries finer for their size
make provinces "$data/world_countries.gpkg" 3000 1 "$work/world_provinces.gpkg"
declare -A judged_against=(["us_states_apart"]="$data/us_states.gpkg"
    ["us_states_over"]="$data/us_states.gpkg" ["us_counties_simplified"]="$data/us_counties.gpkg")
layers=(
    "$data/us_states.gpkg" "$data/nc_counties.gpkg" "$data/virginia_counties.gpkg"
    "$data/world_countries.gpkg" "$data/us_counties.gpkg"
    "$work/voronoi_300.gpkg" "$work/voronoi_3000.gpkg" "$work/islands.gpkg" "$work/river.gpkg"
    "$work/river_33.gpkg"
    "$work/archipelago.gpkg" "$work/strip.gpkg" "$work/ring.gpkg" "$work/us_states_apart.gpkg"
    "$work/us_states_over.gpkg" "$work/us_counties_simplified.gpkg" "$work/world_provinces.gpkg"
)

rows="$work/rows.tsv"
: > "$rows"
for source in "${layers[@]}"; do
    name="$(basename "$source" .gpkg)"
    for variant in default plain hex hex-flat; do
        options=("$@")
        case "$variant" in
            plain) options+=(-refine false) ;;
            hex) options+=(-cell hex) ;;
            hex-flat) options+=(-cell hex -hex_orientation flat) ;;
        esac
        grid="$work/$name-$variant.gpkg"
        started=$(date +%s.%N)
        "$cli" -q -id id "${options[@]}" "$grid" "$source"
        seconds=$(echo "$(date +%s.%N) - $started" | bc)
        python3 "$judge" --regions "${judged_against[$name]:-$source}" --grid "$grid" --id id |
            python3 -c '
import json, sys
j = json.load(sys.stdin)
name, variant, seconds = sys.argv[1:4]
print("\t".join([name, variant, "%.1f" % float(seconds)] + [
    "%.3f" % j["adjacency_kept_queen"], "%.3f" % j["adjacency_kept"],
    "%.3f" % j["false_neighbours_queen"], "%.1f" % j["orientation_deg"],
    "%.3f" % j["misdirected_share"], "%.3f" % j["location_cells"],
    "%.2f" % j["location_p90_cells"], "%.2f" % j["location_max_cells"], "%.3f" % j["shape_fd"],
    "%d" % j["components_cells"], "%d" % j["holes_cells"], "%d" % j["gap_cells"],
    "%.3f" % j["wrong_landmass_share"]]))' "$name" "$variant" "$seconds" >> "$rows"
        echo "quality: $name $variant done" >&2
    done
done

# Groups (issue 17): us_counties by state, squares and hexagons, with and without a gap; the
# judge's metrics and the layout's own group metrics (from the JSON report).
grouped="$work/grouped.tsv"
: > "$grouped"
for variant in group group-gap group-hex group-hex-gap; do
    options=("$@" -group state_abbr)
    case "$variant" in
        *-gap) options+=(-group_gap 1) ;;
    esac
    case "$variant" in
        group-hex*) options+=(-cell hex) ;;
    esac
    grid="$work/us_counties-$variant.gpkg"
    report="$work/us_counties-$variant.json"
    started=$(date +%s.%N)
    "$cli" -q -id id "${options[@]}" -json "$report" "$grid" "$data/us_counties.gpkg"
    seconds=$(echo "$(date +%s.%N) - $started" | bc)
    python3 "$judge" --regions "$data/us_counties.gpkg" --grid "$grid" --id id |
        python3 -c '
import json, sys
j = json.load(sys.stdin)
variant, seconds, report = sys.argv[1:4]
g = json.load(open(report))["groups"]
print("\t".join(["us_counties", variant, "%.1f" % float(seconds)] + [
    "%.3f" % j["adjacency_kept_queen"], "%.1f" % j["orientation_deg"],
    "%.3f" % j["location_cells"], "%.3f" % j["shape_fd"], "%d" % j["components_cells"],
    "%d" % j["holes_cells"], "%.3f" % g["whole"], "%.3f" % g["adjacency"], "%d" % g["reach"],
    "%.1f" % g["orientation"], "%d" % g["contacts"]]))' "$variant" "$seconds" "$report" >> "$grouped"
    echo "quality: us_counties $variant done" >&2
done

# The tab-separated rows of file $1 as Markdown table rows.
markdown_rows() {
    while IFS=$'\t' read -r -a cells; do
        printf '| %s |\n' "$(IFS='|'; echo "${cells[*]}" | sed 's/|/ | /g')"
    done < "$1"
}

{
    echo "# Quality"
    echo
    echo "Every layout below is judged by the shared judge (\`../shared/eval/gridmap_eval.py\`, the"
    echo "reference implementation of method.md §8), which also scores the other tools. Made by"
    echo "\`scripts/bench-quality.sh $*\` on $(date -u +%Y-%m-%d), snakegrid $(git -C "$root" describe --always --dirty),"
    echo "load $(cut -d' ' -f1-3 /proc/loadavg). *default* is the command line's defaults; *plain* is"
    echo "\`-refine false\` (the paper's method with our landmass budgets); *hex* is \`-cell hex\`"
    echo "(pointy hexagons) and *hex-flat* adds \`-hex_orientation flat\`: for hexagons the judge's"
    echo "8-neighbourhood is the six edge neighbours, so adj 8 and adj 4 agree. The generated layers come"
    echo "from \`scripts/make-test-layers.py\`: random Voronoi cells of 300 and 3,000 regions, three"
    echo "far-apart landmasses with islands (\`islands\`), Voronoi cells cut by a winding river gap"
    echo "(\`river\`), a mainland of 3,000 Voronoi cells ringed by 300 one-region islands"
    echo "(\`archipelago\`), a long thin country of 40 Voronoi cells 0.7 cells wide (\`strip\`), a"
    echo "country of 300 Voronoi cells round a lake, 0.7 cells wide (\`ring\`), and"
    echo "us_states with every state narrowed by a thousandth of a cell (\`us_states_apart\`: regions"
    echo "drawn one by one, neighbours a hairline apart) and widened by as much (\`us_states_over\`:"
    echo "neighbours drawn over each other's borders), both judged against us_states itself, and"
    echo "us_counties with every county simplified alone by a sixteenth of a cell, as \`ogr2ogr"
    echo "-simplify\` does (\`us_counties_simplified\`: slivers between neighbours), judged against"
    echo "us_counties; and world_countries cut into 3,000 Voronoi provinces, each country's share"
    echo "following the square root of its area (\`world_provinces\`: the world's landmasses with"
    echo "densities far apart, as a layer of provinces or districts has them)."
    echo
    echo "Columns: C_adjacent in the 8-neighbourhood and the 4-neighbourhood (shared edge), the"
    echo "false-neighbour share, C_orientation (degrees) and the misdirected share (> 45°),"
    echo "C_location in fitted cells with its 90th percentile and maximum, C_shape, then the shape"
    echo "of the layout: pieces, holes (cells), notches, and the wrong-landmass share; time is the"
    echo "wall time of the whole command line run."
    echo
    echo "| layer | run | time s | adj 8 | adj 4 | false | orient ° | > 45° | location | p90 | max | shape | pieces | holes | notches | wrong land |"
    echo "|---|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|"
    markdown_rows "$rows"
    echo
    echo "## Groups (\`-group state_abbr\`, issue 17)"
    echo
    echo "us_counties with its 49 states as groups; *-gap* adds \`-group_gap 1\`, *hex* \`-cell hex\`."
    echo "The judge's metrics, then the layout's group metrics (JSON report \`groups\`): the share of"
    echo "blocks (a state's counties on one landmass) in one piece, the share of adjacent state pairs"
    echo "whose cells come within *reach* cells (1 + group_gap), the direction error between states"
    echo "and the touching cells of different states."
    echo
    echo "| layer | run | time s | adj 8 | orient ° | location | shape | pieces | holes | blocks whole | groups near | reach | group orient ° | contacts |"
    echo "|---|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|"
    markdown_rows "$grouped"
    echo
    echo "## Other tools, by the same judge (issue 13; adjacency 8-nbr / orientation / location / shape)"
    echo
    echo "| layout | us_states | nc_counties | virginia_counties | world_countries |"
    echo "|---|---|---|---|---|"
    echo "| R tilemaps 0.2.2 | .879 / 26.7 / .809 / .913 | .892 / 24.5 / .563 / .909 | .787 / 27.4 / .939 / .927 | fails |"
    echo "| carto-flow | .888 / 24.3 / .782 / .886 | .870 / 27.0 / .728 / .877 | .847 / 29.4 / .986 / .887 | .735 / 43.7 / 1.79 / .810 |"
    echo "| New York Times, hand-made | .897 / 22.1 / .864 / .899; 1 piece, 0 holes, 1 notch, false neighbours .338 | | | |"
    echo
    cat "$root/scripts/location-bound.md"
} > "$out"
echo "$out"
