"""Puts the compiled library into the wheel and tags the wheel with the platform it is for.

scripts/build-wheel.sh sets SNAKEGRID_WHEEL_LIBRARY (the GDAL-free libsnakegrid.so it built)
and SNAKEGRID_WHEEL_PLATFORM (e.g. manylinux_2_28_x86_64, the glibc it was linked for), then
checks the result with auditwheel. The tag is py3-none-<platform>: ctypes loads a plain C
library, so the wheel depends on no CPython ABI.
"""

import os

from hatchling.builders.hooks.plugin.interface import BuildHookInterface


class CustomBuildHook(BuildHookInterface):
    def initialize(self, version, build_data):
        library = os.environ.get("SNAKEGRID_WHEEL_LIBRARY")
        platform = os.environ.get("SNAKEGRID_WHEEL_PLATFORM")
        if not (library and platform and os.path.isfile(library)):
            raise RuntimeError(
                "a snakegrid wheel needs the compiled library: build it with "
                "scripts/build-wheel.sh")
        build_data["force_include"][library] = "snakegrid/" + os.path.basename(library)
        build_data["pure_python"] = False
        build_data["tag"] = f"py3-none-{platform}"
