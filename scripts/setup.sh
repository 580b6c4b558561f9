#!/usr/bin/env bash
# One-command setup on Debian 12: the system packages snakegrid builds and tests against, then a
# release build of the library and the command line. Run as root (or with sudo).
set -euo pipefail
cd "$(dirname "$0")/.."
export DEBIAN_FRONTEND=noninteractive
apt-get update -qq
apt-get install -y -qq --no-install-recommends \
    libgdal-dev gdal-bin pkg-config cmake g++ valgrind >/dev/null
cargo build --release
echo "snakegrid built: target/release/snakegrid, target/release/libsnakegrid.{so,a}"
