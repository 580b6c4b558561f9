// The header compiles as C++ (extern "C", enums with a fixed uint32_t type, struct tags) and
// links against the library. Built by CMake and by tests/c_api.rs.
#include "snakegrid.h"

#include <cstdio>
#include <cstring>

int main() {
    snakegrid_options *options = nullptr;
    snakegrid_status status = snakegrid_options_new(&options);
    bool ok = status == SNAKEGRID_OK && options != nullptr;
    ok = ok && snakegrid_options_set_bool(options, "refine", false) == SNAKEGRID_OK;
    ok = ok && snakegrid_options_set(options, "gamma", "1") == SNAKEGRID_INVALID_OPTION;
    ok = ok && std::strstr(snakegrid_last_error_message(), "gamma") != nullptr;
    snakegrid_options_free(options);

    snakegrid_snake_report report = {};
    ok = ok && report.stop_reason == SNAKEGRID_STOP_CONVERGED;
    ok = ok && std::strcmp(snakegrid_version(), SNAKEGRID_VERSION) == 0;
    std::printf("test_header: %d passed, %d failed\n", ok ? 1 : 0, ok ? 0 : 1);
    return ok ? 0 : 1;
}
