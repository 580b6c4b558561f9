/* Two 3x3 clusters of unit squares far apart, laid out in-process: memory must follow the
 * regions, not the empty space between them (the refinement once allocated one slot per cell of
 * the bounding box, 320 GB at 100,000 cells apart, and aborted the host).
 *
 * usage: test_clusters [PEAK_MB]   (the bound on peak memory, default 100; 0 checks none, for
 *                                  runs under valgrind, whose own memory counts as resident) */
#define _POSIX_C_SOURCE 200809L /* getrusage under -std=c99 */
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>

#include "check.h"
#include "wkb.h"

enum { SIDE = 3, PER_CLUSTER = SIDE * SIDE, REGIONS = 2 * PER_CLUSTER };

/* Peak resident memory of this process so far, in MB. */
static double peak_mb(void) {
    struct rusage usage;
    getrusage(RUSAGE_SELF, &usage);
    return (double)usage.ru_maxrss / 1024.0; /* kilobytes on Linux */
}

/* Lays out the clusters `gap` cells apart; checks that every region has its own cell and that
 * each cluster stays one 3x3 block. */
static void lay_out(double gap) {
    snakegrid_regions *regions = NULL;
    snakegrid_options *options = NULL;
    snakegrid_result *result = NULL;
    CHECK_OK(snakegrid_regions_new(&regions));
    CHECK_OK(snakegrid_options_new(&options));
    for (int k = 0; k < REGIONS; k++) {
        int cluster = k / PER_CLUSTER, col = k % SIDE, row = (k % PER_CLUSTER) / SIDE;
        char id[16];
        snprintf(id, sizeof id, "c%d_%d%d", cluster, col, row);
        wkb_buffer square = wkb_square(cluster * gap + col, row, 1.0);
        CHECK_OK(snakegrid_regions_add(regions, id, square.bytes, square.len));
    }
    CHECK_OK(snakegrid_run(regions, options, NULL, NULL, &result));
    if (result != NULL) {
        int32_t cols[REGIONS], rows[REGIONS];
        for (size_t i = 0; i < REGIONS; i++) CHECK_OK(snakegrid_result_cell(result, i, &cols[i], &rows[i]));
        for (int i = 0; i < REGIONS; i++)
            for (int j = i + 1; j < REGIONS; j++) CHECK(cols[i] != cols[j] || rows[i] != rows[j]);
        for (int cluster = 0; cluster < 2; cluster++) {
            int32_t min_col = INT32_MAX, max_col = INT32_MIN, min_row = INT32_MAX, max_row = INT32_MIN;
            for (int k = cluster * PER_CLUSTER; k < (cluster + 1) * PER_CLUSTER; k++) {
                if (cols[k] < min_col) min_col = cols[k];
                if (cols[k] > max_col) max_col = cols[k];
                if (rows[k] < min_row) min_row = rows[k];
                if (rows[k] > max_row) max_row = rows[k];
            }
            CHECK(max_col - min_col == SIDE - 1 && max_row - min_row == SIDE - 1);
        }
    }
    snakegrid_result_free(result);
    snakegrid_options_free(options);
    snakegrid_regions_free(regions);
}

int main(int argc, char **argv) {
#ifdef __SANITIZE_ADDRESS__
    const double bound = 0; /* AddressSanitizer's shadow memory counts as resident */
    (void)argc;
    (void)argv;
#else
    const double bound = argc > 1 ? atof(argv[1]) : 100.0;
#endif
    const double gaps[] = {1e4, 1e5, 9e5};
    for (size_t g = 0; g < sizeof gaps / sizeof gaps[0]; g++) {
        lay_out(gaps[g]);
        /* Peak memory stays far below what a dense board would need (18 squares take a few MB;
         * the bound leaves room for the allocator and the test itself). */
        printf("clusters %.0e cells apart: peak memory %.1f MB\n", gaps[g], peak_mb());
        if (bound > 0) CHECK(peak_mb() < bound);
    }
    return check_summary("test_clusters");
}
