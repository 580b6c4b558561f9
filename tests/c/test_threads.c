/* Eight threads, each with its own handles, run the in-memory and the dataset entry points at
 * once (and fail on purpose in between); every thread must get exactly what a serial run gets,
 * and its own error messages. Built by CMake (ctest) and by tests/c_api.rs (cargo test); run
 * under ASan and valgrind by scripts/check-c-api.sh.
 *
 * usage: test_threads SOURCE OUTPUT_DIR   (SOURCE: a polygon layer with a "code" id field, e.g.
 *                                          tests/data/bad/enclave.geojson; a fresh OUTPUT_DIR)
 */
#define _POSIX_C_SOURCE 200809L /* pthreads and unlink under -std=c99 */
#include <pthread.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "check.h"
#include "wkb.h"

enum { THREADS = 8, COLS = 5, ROWS = 4, REGIONS = COLS * ROWS, MAX_CELLS = 64 };

/* What a run gave: its cells and layout metrics, compared byte for byte. The worker threads do
 * not CHECK (check.h's counters are not atomic): they record, and the main thread checks. */
typedef struct {
    int calls_ok; /* every call before and after the run succeeded */
    snakegrid_status status;
    size_t count;
    int32_t cells[MAX_CELLS][2];
    snakegrid_layout_metrics metrics;
} outcome;

static void record(int calls_ok, snakegrid_status status, const snakegrid_result *result, outcome *out) {
    memset(out, 0, sizeof *out);
    out->calls_ok = calls_ok;
    out->status = status;
    if (status != SNAKEGRID_OK) return;
    out->calls_ok &= snakegrid_result_count(result, &out->count) == SNAKEGRID_OK && out->count <= MAX_CELLS;
    for (size_t i = 0; i < out->count && i < MAX_CELLS; i++) {
        out->calls_ok &= snakegrid_result_cell(result, i, &out->cells[i][0], &out->cells[i][1]) == SNAKEGRID_OK;
    }
    out->calls_ok &= snakegrid_result_layout_metrics(result, &out->metrics) == SNAKEGRID_OK;
}

/* Field by field: padding bytes of a copied struct need not match. */
static int same(const outcome *a, const outcome *b) {
    return a->calls_ok && b->calls_ok && a->status == b->status && a->count == b->count &&
           memcmp(a->cells, b->cells, sizeof a->cells) == 0 &&
           memcmp(&a->metrics, &b->metrics, sizeof a->metrics) == 0;
}

/* A block of squares whose widths vary by column, so the layout is not trivial. */
static outcome run_in_memory(void) {
    snakegrid_regions *regions = NULL;
    snakegrid_options *options = NULL;
    snakegrid_result *result = NULL;
    int ok = snakegrid_regions_new(&regions) == SNAKEGRID_OK && snakegrid_options_new(&options) == SNAKEGRID_OK &&
             snakegrid_options_set_int(options, "seed", 3) == SNAKEGRID_OK;
    for (int r = 0; r < ROWS; r++) {
        double x = 0;
        for (int c = 0; c < COLS; c++) {
            double width = 800.0 + 100.0 * ((c + r) % 3);
            const double ring[5][2] = {{x, r * 1000.0}, {x + width, r * 1000.0}, {x + width, (r + 1) * 1000.0},
                                       {x, (r + 1) * 1000.0}, {x, r * 1000.0}};
            wkb_buffer w = wkb_polygon(5, ring);
            char id[16];
            snprintf(id, sizeof id, "r%d%d", c, r);
            ok &= snakegrid_regions_add(regions, id, w.bytes, w.len) == SNAKEGRID_OK;
            x += width;
        }
    }
    outcome out;
    snakegrid_status status = snakegrid_run(regions, options, NULL, NULL, &result);
    record(ok, status, result, &out);
    snakegrid_result_free(result);
    snakegrid_options_free(options);
    snakegrid_regions_free(regions);
    return out;
}

static outcome run_dataset(const char *src, const char *dst) {
    snakegrid_job *job = NULL;
    snakegrid_options *options = NULL;
    snakegrid_result *result = NULL;
    unlink(dst);
    int ok = snakegrid_job_new(&job) == SNAKEGRID_OK && snakegrid_options_new(&options) == SNAKEGRID_OK &&
             snakegrid_job_set(job, "src", src) == SNAKEGRID_OK && snakegrid_job_set(job, "dst", dst) == SNAKEGRID_OK &&
             snakegrid_job_set(job, "id_field", "code") == SNAKEGRID_OK;
    outcome out;
    snakegrid_status status = snakegrid_run_job(job, options, NULL, NULL, &result);
    record(ok, status, result, &out);
    snakegrid_result_free(result);
    snakegrid_options_free(options);
    snakegrid_job_free(job);
    unlink(dst);
    return out;
}

typedef struct {
    const char *src;
    char dst[4096];
    outcome memory, dataset;
    int messages_own;
} thread_work;

static void *work(void *arg) {
    thread_work *t = arg;
    t->memory = run_in_memory();
    /* A failure between runs leaves this thread's message, whatever the others do meanwhile. */
    snakegrid_options *options = NULL;
    snakegrid_status made = snakegrid_options_new(&options);
    snakegrid_status bad = snakegrid_options_set(options, "alpha", t->dst);
    t->messages_own = made == SNAKEGRID_OK && bad == SNAKEGRID_INVALID_OPTION &&
                      strstr(snakegrid_last_error_message(), t->dst) != NULL;
    snakegrid_options_free(options);
    t->dataset = run_dataset(t->src, t->dst);
    return NULL;
}

int main(int argc, char **argv) {
    if (argc != 3) {
        fprintf(stderr, "usage: %s SOURCE OUTPUT_DIR\n", argv[0]);
        return 2;
    }
    char serial_dst[4096];
    snprintf(serial_dst, sizeof serial_dst, "%s/serial.gpkg", argv[2]);
    outcome memory = run_in_memory();
    outcome dataset = run_dataset(argv[1], serial_dst);
    CHECK(memory.calls_ok && memory.status == SNAKEGRID_OK && memory.count == REGIONS);
    CHECK(dataset.calls_ok && dataset.status == SNAKEGRID_OK && dataset.count > 0);
    /* The failure each thread provokes, serially: the message names the function and the value. */
    snakegrid_options *options = NULL;
    CHECK_OK(snakegrid_options_new(&options));
    CHECK_FAILS(snakegrid_options_set(options, "alpha", serial_dst), SNAKEGRID_INVALID_OPTION);
    CHECK_MESSAGE_HAS(serial_dst);
    snakegrid_options_free(options);

    thread_work work_of[THREADS];
    pthread_t threads[THREADS];
    memset(work_of, 0, sizeof work_of);
    for (int t = 0; t < THREADS; t++) {
        work_of[t].src = argv[1];
        snprintf(work_of[t].dst, sizeof work_of[t].dst, "%s/thread-%d.gpkg", argv[2], t);
        CHECK(pthread_create(&threads[t], NULL, work, &work_of[t]) == 0);
    }
    for (int t = 0; t < THREADS; t++) CHECK(pthread_join(threads[t], NULL) == 0);
    for (int t = 0; t < THREADS; t++) {
        CHECK(same(&work_of[t].memory, &memory));
        CHECK(same(&work_of[t].dataset, &dataset));
        CHECK(work_of[t].messages_own);
    }
    return check_summary("test_threads");
}
