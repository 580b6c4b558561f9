#!/usr/bin/env bash
# Checks the C API end to end, as a user of the installed library would meet it:
#  1. include/snakegrid.h is what build.rs regenerates from src/ffi (CI fails on a stale header);
#  2. CMake builds the library, the example and the C tests, and ctest passes;
#  3. `cmake --install` to a temporary prefix, then programs built only from the installed
#     header, library and CMake package (shared and static) or pkg-config file run the dataset
#     entry point on us_states.gpkg and write the same layer as the command line;
#  4. the C tests pass under AddressSanitizer (LeakSanitizer on), and all but the bad-input
#     corpus under valgrind too, with no error and no leak.
#
# Usage: scripts/check-c-api.sh            (from anywhere; needs cmake, a C/C++ compiler,
#                                           pkg-config, libgdal-dev, gdal-bin and valgrind)
# Environment: SNAKEGRID_CARGO_PROFILE (default release, to share the README test build),
#              SNAKEGRID_CHECK_DIR (default build/c-api-check). The layer is the bundled sample,
#              data/us_states.gpkg.
set -euo pipefail

root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
profile="${SNAKEGRID_CARGO_PROFILE:-release}"
work="${SNAKEGRID_CHECK_DIR:-$root/build/c-api-check}"
us_states="$root/data/us_states.gpkg"
profile_dir="$([ "$profile" = dev ] && echo debug || echo "$profile")"
passes=0
failures=0

step() { printf '\n== %s\n' "$*"; }
ok() { printf 'ok: %s\n' "$*"; passes=$((passes + 1)); }
fail() { printf 'FAILED: %s\n' "$*" >&2; failures=$((failures + 1)); }

rm -rf "$work"
mkdir -p "$work/out"

step "header: the committed one is the one build.rs generates from src/ffi"
if cargo test --manifest-path "$root/Cargo.toml" --profile "$profile" --test c_api header; then
    ok "include/snakegrid.h is current"
else
    fail "include/snakegrid.h is stale: SNAKEGRID_UPDATE_HEADER=1 cargo test --test c_api header"
fi

step "CMake build and ctest"
cmake -S "$root" -B "$work/build" -DSNAKEGRID_CARGO_PROFILE="$profile"
cmake --build "$work/build"
if ctest --test-dir "$work/build" --output-on-failure; then ok "ctest"; else fail "ctest"; fi

step "install, then consumers of the installed package"
cmake --install "$work/build" --prefix "$work/prefix"
cmake -S "$root/examples/consumer" -B "$work/consumer" -DCMAKE_PREFIX_PATH="$work/prefix"
cmake --build "$work/consumer"
PKG_CONFIG_PATH="$work/prefix/lib/pkgconfig" \
    cc -std=c99 -Wall -Wextra -Werror -pedantic "$root/examples/grid_map.c" -o "$work/consumer/grid_map_pc" \
    $(PKG_CONFIG_PATH="$work/prefix/lib/pkgconfig" pkg-config --cflags --libs snakegrid) \
    -Wl,-rpath,"$work/prefix/lib"

# The layer as text (attributes and WKT geometry), to compare two outputs.
dump() { ogr2ogr -f CSV /vsistdout/ "$1" -lco GEOMETRY=AS_WKT; }
"$root/target/$profile_dir/snakegrid" -q "$work/out/cli.gpkg" "$us_states"
dump "$work/out/cli.gpkg" > "$work/out/cli.csv"
for consumer in grid_map grid_map_static grid_map_pc; do
    if ! "$work/consumer/$consumer" "$work/out/$consumer.gpkg" "$us_states" > "$work/out/$consumer.txt" 2>/dev/null; then
        fail "$consumer did not run"
        continue
    fi
    dump "$work/out/$consumer.gpkg" > "$work/out/$consumer.csv"
    if cmp -s "$work/out/cli.csv" "$work/out/$consumer.csv"; then
        ok "$consumer wrote the same layer as the command line"
    else
        fail "$consumer wrote another layer than the command line"
    fi
done
soname="$(objdump -p "$work/prefix/lib/libsnakegrid.so" | awk '/SONAME/ {print $2}')"
if ldd "$work/consumer/grid_map" | grep "$soname => $work/prefix/lib/" >/dev/null; then
    ok "the CMake consumer loads the installed $soname"
else
    fail "the CMake consumer does not load the installed $soname"
fi

step "AddressSanitizer (with LeakSanitizer)"
cmake -S "$root" -B "$work/asan" -DSNAKEGRID_CARGO_PROFILE="$profile" \
    -DSNAKEGRID_SANITIZE=address
cmake --build "$work/asan"
if ASAN_OPTIONS=detect_leaks=1:halt_on_error=1 ctest --test-dir "$work/asan" --output-on-failure; then
    ok "the C tests and the example under AddressSanitizer"
else
    fail "the C tests or the example under AddressSanitizer"
fi

step "valgrind"
run_valgrind() {
    if valgrind --quiet --error-exitcode=1 --leak-check=full --show-leak-kinds=definite,possible \
        --errors-for-leak-kinds=definite,possible --suppressions="$root/tests/c/valgrind.supp" "$@"; then
        ok "valgrind: $(basename "$1")"
    else
        fail "valgrind: $*"
    fi
}
run_valgrind "$work/build/test_api"
run_valgrind "$work/build/test_clusters" 0
run_valgrind "$work/build/test_header"
run_valgrind "$work/build/test_dataset" "$us_states" "$work/out"
# test_bad_inputs (every case of the corpus through the C API, a few minutes under valgrind)
# runs under AddressSanitizer and LeakSanitizer above; here the tests that reach every entry
# point, the dataset job and the threads.
mkdir -p "$work/out/threads"
run_valgrind "$work/build/test_threads" "$root/tests/data/bad/enclave.geojson" "$work/out/threads"

# Last, because it leaves target/ with the library built without GDAL (the next default build
# relinks the other).
step "the same ABI without GDAL (the library the QGIS plugin and the Python package ship)"
cmake -S "$root" -B "$work/nogdal" -DSNAKEGRID_CARGO_PROFILE="$profile" -DSNAKEGRID_WITH_GDAL=OFF
cmake --build "$work/nogdal"
if ctest --test-dir "$work/nogdal" --output-on-failure; then ok "ctest without GDAL"; else fail "ctest without GDAL"; fi
if ldd "$root/target/$profile_dir/libsnakegrid.so" | grep -q gdal; then
    fail "the library built without GDAL links GDAL"
else
    ok "the library built without GDAL links no GDAL: $(ldd "$root/target/$profile_dir/libsnakegrid.so" | awk '{print $1}' | tr '\n' ' ')"
fi

step "summary"
echo "check-c-api: $passes passed, $failures failed"
[ "$failures" -eq 0 ]
