#!/usr/bin/env bash
# Builds the Python wheel target/wheels/snakegrid-<version>-py3-none-manylinux_2_28_x86_64.whl:
# python/snakegrid with the GDAL-free library inside, linked for glibc 2.28 so that it loads on
# any manylinux_2_28 system (Debian 10+, Ubuntu 18.10+, RHEL 8+), not only on this machine's
# glibc. The library is cross-linked by cargo-zigbuild (zig's linker carries the headers of old
# glibc versions); `auditwheel show` must then report the tag the file name carries, or the
# script fails. The version is Cargo.toml's.
#
# Usage: scripts/build-wheel.sh     (prints the wheel's path)
# Needs: Debian's python3-venv (the build tools go into a venv under target/), network access to
# crates.io and PyPI on the first run (hatchling, auditwheel, ziglang, and cargo-zigbuild as PyPI's
# prebuilt binary rather than compiled by `cargo install`, which cost CI minutes).
# Only Linux x86-64 is built here; README.md says how Windows and macOS wheels would be made.
set -euo pipefail

root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
glibc=2.28
platform="manylinux_${glibc/./_}_x86_64"
target=x86_64-unknown-linux-gnu

tools="$root/target/wheel-tools"
# Keyed on the last tool added, so that a venv an older version of this script made is
# completed rather than taken as it is.
if [ ! -x "$tools/bin/cargo-zigbuild" ]; then
    /usr/bin/python3 -m venv "$tools" || {
        echo "build-wheel: needs Debian's python3-venv (apt-get install python3-venv)" >&2
        exit 1
    }
    "$tools/bin/pip" install -q hatchling==1.33.0 auditwheel==6.8.2 ziglang==0.17.1 \
        cargo-zigbuild==0.24.1
fi

# cargo-zigbuild (the venv's) finds zig through `python3 -m ziglang`: the tools venv comes first.
# A target folder of its own, so that this build may run beside another cargo command (CI
# starts it in the background) without either waiting for the other's lock.
PATH="$tools/bin:$PATH" cargo zigbuild --manifest-path "$root/Cargo.toml" --release --lib \
    --no-default-features --target "$target.$glibc" --target-dir "$root/target/wheel"
library="$root/target/wheel/$target/release/libsnakegrid.so"
if ldd "$library" | grep -q gdal; then
    echo "build-wheel: $library links GDAL" >&2
    exit 1
fi

staging="$(mktemp -d)"
trap 'rm -rf "$staging"' EXIT
# Debug symbols are most of the library's size and of no use to its users.
strip --strip-debug -o "$staging/libsnakegrid.so" "$library"
(cd "$root/python" && SNAKEGRID_WHEEL_LIBRARY="$staging/libsnakegrid.so" \
    SNAKEGRID_WHEEL_PLATFORM="$platform" "$tools/bin/python" -m hatchling build -t wheel \
    -d "$staging/dist" >/dev/null 2>&1)
wheel="$(ls "$staging"/dist/*.whl)"

# auditwheel wraps its lines: compare on one line.
shown="$("$tools/bin/auditwheel" show "$wheel" | tr -s ' \n' ' ')"
if ! grep -q "consistent with the following platform tag: \"$platform\"" <<<"$shown"; then
    echo "build-wheel: auditwheel does not confirm $platform for $(basename "$wheel"):" >&2
    echo "$shown" >&2
    exit 1
fi

mkdir -p "$root/target/wheels"
out="$root/target/wheels/$(basename "$wheel")"
mv -f "$wheel" "$out"
echo "$out"
