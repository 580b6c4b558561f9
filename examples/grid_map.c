/* grid_map: the dataset entry point of the snakegrid C API, as a small program.
 *
 *   grid_map DST SRC [SRC_LAYER]
 *
 * reads the regions of SRC (any vector dataset GDAL reads), writes their grid map to DST as the
 * command line `snakegrid DST SRC [SRC_LAYER]` does, and prints the layout's metrics and each
 * region's id, column and row. Built by the top-level CMakeLists.txt and, from an installed
 * snakegrid, by examples/consumer/CMakeLists.txt. */
#include <stdio.h>

#include "snakegrid.h"

/* Progress on stderr, one line per tenth. */
static int show_progress(double fraction, const char *message, void *user_data) {
    int *shown = user_data;
    int tenth = (int)(fraction * 10.0);
    if (tenth > *shown) {
        *shown = tenth;
        fprintf(stderr, "%3d%% %s\n", tenth * 10, message);
    }
    return 0; /* go on; non-zero would cancel */
}

static int fail(const char *what, snakegrid_status status) {
    fprintf(stderr, "grid_map: %s failed (%s): %s\n", what, snakegrid_status_string(status),
            snakegrid_last_error_message());
    return 1;
}

int main(int argc, char **argv) {
    if (argc < 3 || argc > 4) {
        fprintf(stderr, "usage: %s DST SRC [SRC_LAYER]\n", argv[0]);
        return 2;
    }
    snakegrid_job *job = NULL;
    snakegrid_options *options = NULL;
    snakegrid_result *result = NULL;
    snakegrid_status status;
    int code = 1, shown = 0;

    if ((status = snakegrid_job_new(&job)) != SNAKEGRID_OK) return fail("snakegrid_job_new", status);
    if ((status = snakegrid_job_set(job, "dst", argv[1])) != SNAKEGRID_OK ||
        (status = snakegrid_job_set(job, "src", argv[2])) != SNAKEGRID_OK ||
        (status = snakegrid_job_set(job, "src_layer", argc == 4 ? argv[3] : NULL)) != SNAKEGRID_OK) {
        code = fail("snakegrid_job_set", status);
        goto done;
    }
    /* The command line's defaults; snakegrid_options_set() would change them by name. */
    if ((status = snakegrid_options_new(&options)) != SNAKEGRID_OK) {
        code = fail("snakegrid_options_new", status);
        goto done;
    }
    if ((status = snakegrid_run_job(job, options, show_progress, &shown, &result)) != SNAKEGRID_OK) {
        code = fail("snakegrid_run_job", status);
        goto done;
    }

    snakegrid_layout_metrics m;
    snakegrid_snake_report snake;
    size_t count = 0, notes = 0;
    if ((status = snakegrid_result_layout_metrics(result, &m)) != SNAKEGRID_OK ||
        (status = snakegrid_result_snake_report(result, &snake)) != SNAKEGRID_OK ||
        (status = snakegrid_result_count(result, &count)) != SNAKEGRID_OK ||
        (status = snakegrid_result_note_count(result, &notes)) != SNAKEGRID_OK) {
        code = fail("reading the result", status);
        goto done;
    }
    for (size_t i = 0; i < notes; i++) {
        const char *note = NULL;
        if (snakegrid_result_note(result, i, &note) == SNAKEGRID_OK) printf("note: %s\n", note);
    }
    printf("location %.3f cells, adjacent %.3f (rook %.3f), orientation %.1f deg, "
           "misdirected %.3f, shape %.3f\n",
           m.location, m.adjacent, m.adjacent_rook, m.orientation, m.misdirected, m.shape);
    printf("snake: %zu steps\n", snake.steps);
    printf("id\tcol\trow\n");
    for (size_t i = 0; i < count; i++) {
        const char *id = NULL;
        int32_t col = 0, row = 0;
        if ((status = snakegrid_result_region_id(result, i, &id)) != SNAKEGRID_OK ||
            (status = snakegrid_result_cell(result, i, &col, &row)) != SNAKEGRID_OK) {
            code = fail("reading the result", status);
            goto done;
        }
        printf("%s\t%d\t%d\n", id, (int)col, (int)row);
    }
    code = 0;

done:
    snakegrid_result_free(result);
    snakegrid_options_free(options);
    snakegrid_job_free(job);
    return code;
}
