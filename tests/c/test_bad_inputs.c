/* Bad and awkward inputs through the C API: every case of tests/data/bad/cases.tsv through the
 * dataset entry point (a grid map, or a failure whose message says what the manifest says and
 * nothing at the destination), then the geometry problems of the in-memory entry point.
 * Built by CMake (ctest) and by tests/c_api.rs (cargo test); run under ASan and valgrind by
 * scripts/check-c-api.sh.
 *
 * usage: test_bad_inputs CORPUS_DIR OUTPUT_DIR   (CORPUS_DIR: tests/data/bad; a fresh OUTPUT_DIR)
 */
#define _POSIX_C_SOURCE 200809L /* unlink and access under -std=c99 */
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "check.h"
#include "wkb.h"

/* Whether one of the result's notes contains `text`. */
static int has_note(const snakegrid_result *result, const char *text) {
    size_t count = 0;
    CHECK_OK(snakegrid_result_note_count(result, &count));
    for (size_t i = 0; i < count; i++) {
        const char *note = NULL;
        if (snakegrid_result_note(result, i, &note) == SNAKEGRID_OK && strstr(note, text) != NULL) return 1;
    }
    return 0;
}

/* One manifest line: file, id field, ok|error, text ("-" for none). */
static void run_case(const char *corpus, const char *out, char *line, const snakegrid_options *options) {
    char *file = strtok(line, "\t\n");
    char *id_field = strtok(NULL, "\t\n");
    char *expected = strtok(NULL, "\t\n");
    char *text = strtok(NULL, "\t\n");
    CHECK(file != NULL && id_field != NULL && expected != NULL && text != NULL);
    if (file == NULL || id_field == NULL || expected == NULL || text == NULL) return;
    char src[4096], dst[4096];
    snprintf(src, sizeof src, "%s/%s", corpus, file);
    snprintf(dst, sizeof dst, "%s/grid.gpkg", out);
    unlink(dst);

    snakegrid_job *job = NULL;
    CHECK_OK(snakegrid_job_new(&job));
    CHECK_OK(snakegrid_job_set(job, "src", src));
    CHECK_OK(snakegrid_job_set(job, "dst", dst));
    if (strcmp(id_field, "-") != 0) CHECK_OK(snakegrid_job_set(job, "id_field", id_field));
    snakegrid_result *result = NULL;
    snakegrid_status status = snakegrid_run_job(job, options, NULL, NULL, &result);
    if (strcmp(expected, "ok") == 0) {
        if (status != SNAKEGRID_OK) fprintf(stderr, "case %s: expected a grid map\n", file);
        CHECK(status == SNAKEGRID_OK && result != NULL);
        size_t count = 0;
        if (result != NULL) CHECK_OK(snakegrid_result_count(result, &count));
        CHECK(count > 0);
        CHECK(access(dst, F_OK) == 0);
        if (result != NULL && strcmp(text, "-") != 0) CHECK(has_note(result, text));
    } else {
        if (status == SNAKEGRID_OK) fprintf(stderr, "case %s: expected an error\n", file);
        snakegrid_status wanted = strcmp(expected, "io_error") == 0 ? SNAKEGRID_IO_ERROR : SNAKEGRID_INVALID_INPUT;
        CHECK(strcmp(expected, "invalid_input") == 0 || strcmp(expected, "io_error") == 0);
        CHECK(status == wanted);
        CHECK(result == NULL);
        CHECK_MESSAGE_HAS("snakegrid_run_job");
        CHECK_MESSAGE_HAS(text);
        CHECK(access(dst, F_OK) != 0);
    }
    snakegrid_result_free(result);
    snakegrid_job_free(job);
    unlink(dst);
}

static void test_corpus(const char *corpus, const char *out, const snakegrid_options *options) {
    char manifest[4096], line[1024];
    snprintf(manifest, sizeof manifest, "%s/cases.tsv", corpus);
    FILE *f = fopen(manifest, "r");
    CHECK(f != NULL);
    if (f == NULL) return;
    int cases = 0;
    while (fgets(line, sizeof line, f) != NULL) {
        if (line[0] == '#' || line[0] == '\n') continue;
        run_case(corpus, out, line, options);
        cases++;
    }
    fclose(f);
    CHECK(cases >= 20);
}

/* Two unit squares side by side, then a third region `id` of the given WKB; runs them. */
static snakegrid_status run_with(const char *id, const wkb_buffer *third, const snakegrid_options *options,
                                 snakegrid_result **result) {
    snakegrid_regions *regions = NULL;
    CHECK_OK(snakegrid_regions_new(&regions));
    wkb_buffer a = wkb_square(0, 0, 1), b = wkb_square(1, 0, 1);
    CHECK_OK(snakegrid_regions_add(regions, "a", a.bytes, a.len));
    CHECK_OK(snakegrid_regions_add(regions, "b", b.bytes, b.len));
    CHECK_OK(snakegrid_regions_add(regions, id, third->bytes, third->len));
    snakegrid_status status = snakegrid_run(regions, options, NULL, NULL, result);
    snakegrid_regions_free(regions);
    return status;
}

static void test_in_memory_geometry(const snakegrid_options *options) {
    snakegrid_result *result = NULL;

    /* A bow-tie is repaired into its two triangles. */
    const double bowtie[5][2] = {{2, 0}, {3, 1}, {3, 0}, {2, 1}, {2, 0}};
    wkb_buffer w = wkb_polygon(5, bowtie);
    CHECK_OK(run_with("bowtie", &w, options, &result));
    size_t count = 0;
    if (result != NULL) CHECK_OK(snakegrid_result_count(result, &count));
    CHECK(count == 3);
    /* Each region's repair comes with its cell: NULL for the valid squares. */
    const char *repair = "unset";
    if (result != NULL) {
        CHECK_OK(snakegrid_result_region_repair(result, 0, &repair));
        CHECK(repair == NULL);
        CHECK_OK(snakegrid_result_region_repair(result, 2, &repair));
        CHECK(repair != NULL && strcmp(repair, "a ring intersects itself at (2.5, 0.5)") == 0);
        CHECK_FAILS(snakegrid_result_region_repair(result, 3, &repair), SNAKEGRID_INVALID_ARGUMENT);
    }
    snakegrid_result_free(result);
    result = NULL;

    /* An unclosed ring is closed. */
    const double open[4][2] = {{2, 0}, {3, 0}, {3, 1}, {2, 1}};
    w = wkb_polygon(4, open);
    CHECK_OK(run_with("open", &w, options, &result));
    snakegrid_result_free(result);
    result = NULL;

    /* Refused, naming the region and the problem. */
    const double nan_ring[5][2] = {{2, 0}, {3, 0}, {NAN, 1}, {2, 1}, {2, 0}};
    w = wkb_polygon(5, nan_ring);
    CHECK(run_with("nan", &w, options, &result) == SNAKEGRID_INVALID_INPUT);
    CHECK_MESSAGE_HAS("snakegrid_run: feature nan: the geometry has a NaN or infinite coordinate");
    const double inf_ring[5][2] = {{2, 0}, {INFINITY, 0}, {3, 1}, {2, 1}, {2, 0}};
    w = wkb_polygon(5, inf_ring);
    CHECK(run_with("inf", &w, options, &result) == SNAKEGRID_INVALID_INPUT);
    CHECK_MESSAGE_HAS("snakegrid_run: feature inf: the geometry has a NaN or infinite coordinate");
    const double flat[4][2] = {{2, 0}, {3, 0}, {4, 0}, {2, 0}};
    w = wkb_polygon(4, flat);
    CHECK(run_with("flat", &w, options, &result) == SNAKEGRID_INVALID_INPUT);
    CHECK_MESSAGE_HAS("snakegrid_run: feature flat: the polygon has no area");
    const double two[2][2] = {{2, 0}, {3, 0}};
    w = wkb_polygon(2, two);
    CHECK(run_with("short", &w, options, &result) == SNAKEGRID_INVALID_INPUT);
    CHECK_MESSAGE_HAS("snakegrid_run: feature short:");
    wkb_buffer empty = {{0}, 0};
    wkb_header(&empty, 3);
    wkb_u32(&empty, 0);
    CHECK(run_with("hollow", &empty, options, &result) == SNAKEGRID_INVALID_INPUT);
    CHECK_MESSAGE_HAS("snakegrid_run: feature hollow: the geometry is empty");
    wkb_buffer same = wkb_square(0, 0, 1);
    CHECK(run_with("a", &same, options, &result) == SNAKEGRID_INVALID_INPUT);
    CHECK_MESSAGE_HAS("snakegrid_run: feature a: the id is used by more than one region");
    CHECK(result == NULL);

    /* What snakegrid_regions_add refuses at once. */
    snakegrid_regions *regions = NULL;
    CHECK_OK(snakegrid_regions_new(&regions));
    wkb_buffer point = {{0}, 0};
    wkb_header(&point, 1);
    wkb_f64(&point, 1);
    wkb_f64(&point, 2);
    CHECK_FAILS(snakegrid_regions_add(regions, "dot", point.bytes, point.len), SNAKEGRID_INVALID_INPUT);
    CHECK_MESSAGE_HAS("dot");
    wkb_buffer square = wkb_square(0, 0, 1);
    CHECK_FAILS(snakegrid_regions_add(regions, "cut", square.bytes, square.len - 3), SNAKEGRID_INVALID_INPUT);
    CHECK_MESSAGE_HAS("cut");
    CHECK_FAILS(snakegrid_regions_add(regions, "long", square.bytes, square.len + 3), SNAKEGRID_INVALID_INPUT);
    CHECK_MESSAGE_HAS("long");
    CHECK_FAILS(snakegrid_regions_add(regions, "Z\xfcrich", square.bytes, square.len), SNAKEGRID_INVALID_ARGUMENT);
    CHECK_FAILS(snakegrid_run(regions, options, NULL, NULL, &result), SNAKEGRID_INVALID_INPUT);
    CHECK_MESSAGE_HAS("no regions");
    CHECK(result == NULL);

    /* A layer's features as a host reads them: the command line's checks and messages. */
    CHECK_OK(snakegrid_regions_add_feature(regions, "FID 1", "a", square.bytes, square.len));
    CHECK_FAILS(snakegrid_regions_add_feature(regions, "FID 2", NULL, square.bytes, square.len), SNAKEGRID_INVALID_INPUT);
    CHECK_MESSAGE_HAS("feature FID 2: the id is null");
    CHECK_FAILS(snakegrid_regions_add_feature(regions, "FID 3", "", square.bytes, square.len), SNAKEGRID_INVALID_INPUT);
    CHECK_MESSAGE_HAS("feature FID 3: the id is empty");
    CHECK_FAILS(snakegrid_regions_add_feature(regions, "FID 4", "a", square.bytes, square.len), SNAKEGRID_INVALID_INPUT);
    CHECK_MESSAGE_HAS("feature a: the id is not unique (FID 1 and FID 4 share it)");
    CHECK_FAILS(snakegrid_regions_add_feature(regions, "FID 5", "nothing", NULL, 0), SNAKEGRID_INVALID_INPUT);
    CHECK_MESSAGE_HAS("feature nothing: the geometry is null");
    CHECK_FAILS(snakegrid_regions_add_feature(regions, "FID 6", "hollow", empty.bytes, empty.len), SNAKEGRID_INVALID_INPUT);
    CHECK_MESSAGE_HAS("feature hollow: the geometry is empty");
    CHECK_FAILS(snakegrid_regions_add_feature(regions, "FID 7", "p1", point.bytes, point.len), SNAKEGRID_INVALID_INPUT);
    CHECK_MESSAGE_HAS("feature p1: the geometry is a POINT, not a polygon or multipolygon");
    /* Refused features took nothing: "nothing" may still come, once. */
    wkb_buffer other = wkb_square(1, 0, 1);
    CHECK_OK(snakegrid_regions_add_feature(regions, "FID 8", "nothing", other.bytes, other.len));
    /* A curved polygon is taken, linearised: CURVEPOLYGON(CIRCULARSTRING(2 0.5, 3 0.5, 2 0.5)),
       the disc of radius 0.5 touching "nothing" at (2, 0.5). */
    wkb_buffer disc = {{0}, 0};
    wkb_header(&disc, 10);
    wkb_u32(&disc, 1);
    wkb_header(&disc, 8);
    wkb_u32(&disc, 3);
    const double arc[3][2] = {{2, 0.5}, {3, 0.5}, {2, 0.5}};
    for (int i = 0; i < 3; i++) {
        wkb_f64(&disc, arc[i][0]);
        wkb_f64(&disc, arc[i][1]);
    }
    CHECK_OK(snakegrid_regions_add_feature(regions, "FID 9", "disc", disc.bytes, disc.len));
    CHECK_OK(snakegrid_run(regions, options, NULL, NULL, &result));
    size_t admitted = 0;
    CHECK_OK(snakegrid_result_count(result, &admitted));
    CHECK(admitted == 3);
    CHECK(has_note(result, "feature disc: curved geometry (CURVEPOLYGON) linearised"));
    snakegrid_result_free(result);
    snakegrid_regions_free(regions);
}

int main(int argc, char **argv) {
    if (argc != 3) {
        fprintf(stderr, "usage: %s CORPUS_DIR OUTPUT_DIR\n", argv[0]);
        return 2;
    }
    snakegrid_options *options = NULL;
    CHECK_OK(snakegrid_options_new(&options));
    test_corpus(argv[1], argv[2], options);
    test_in_memory_geometry(options);
    snakegrid_options_free(options);
    return check_summary("test_bad_inputs");
}
