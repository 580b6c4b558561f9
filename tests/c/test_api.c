/* The in-memory C API: regions from WKB, a run, every result field, and every error path.
 * Built by CMake (ctest) and by tests/c_api.rs (cargo test); run under ASan and valgrind by
 * scripts/check-c-api.sh. */
#define _POSIX_C_SOURCE 200809L /* pthreads, unlink and access under -std=c99 */
#include <math.h>
#include <pthread.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "check.h"

/* The test map: COLS x ROWS squares of SIDE metres, region "rCR" at column C, row R (row 0 at
 * the bottom, as map y grows upwards). */
enum { COLS = 6, ROWS = 4, REGIONS = COLS * ROWS };
static const double SIDE = 1000.0;

/* ---- WKB writing, by hand so that the test depends on nothing but the header ---- */

typedef struct {
    uint8_t bytes[512];
    size_t len;
} wkb_buffer;

static void put_u32(wkb_buffer *b, uint32_t v, int big_endian) {
    for (int i = 0; i < 4; i++) {
        int shift = big_endian ? 8 * (3 - i) : 8 * i;
        b->bytes[b->len++] = (uint8_t)(v >> shift);
    }
}

static void put_f64(wkb_buffer *b, double v, int big_endian) {
    uint64_t bits;
    memcpy(&bits, &v, sizeof bits);
    for (int i = 0; i < 8; i++) {
        int shift = big_endian ? 8 * (7 - i) : 8 * i;
        b->bytes[b->len++] = (uint8_t)(bits >> shift);
    }
}

/* An axis-aligned square polygon, closed ring, counter-clockwise. */
static void put_square(wkb_buffer *b, double x, double y, double side, int big_endian) {
    const double ring[5][2] = {{x, y}, {x + side, y}, {x + side, y + side}, {x, y + side}, {x, y}};
    b->bytes[b->len++] = big_endian ? 0 : 1;
    put_u32(b, 3, big_endian); /* Polygon */
    put_u32(b, 1, big_endian); /* one ring */
    put_u32(b, 5, big_endian); /* five points */
    for (int i = 0; i < 5; i++) {
        put_f64(b, ring[i][0], big_endian);
        put_f64(b, ring[i][1], big_endian);
    }
}

static double get_f64_le(const uint8_t *p) {
    uint64_t bits = 0;
    for (int i = 7; i >= 0; i--) bits = (bits << 8) | p[i];
    double v;
    memcpy(&v, &bits, sizeof v);
    return v;
}

static uint32_t get_u32_le(const uint8_t *p) {
    return (uint32_t)p[0] | (uint32_t)p[1] << 8 | (uint32_t)p[2] << 16 | (uint32_t)p[3] << 24;
}

/* The regions of the test map. Alternate regions use big-endian and MultiPolygon WKB, so that
 * every accepted form is exercised. */
static snakegrid_regions *make_regions(void) {
    snakegrid_regions *regions = NULL;
    CHECK_OK(snakegrid_regions_new(&regions));
    for (int r = 0; r < ROWS; r++) {
        for (int c = 0; c < COLS; c++) {
            char id[16];
            snprintf(id, sizeof id, "r%d%d", c, r);
            int k = r * COLS + c;
            wkb_buffer b = {{0}, 0};
            if (k % 3 == 2) {
                b.bytes[b.len++] = 1;
                put_u32(&b, 6, 0); /* MultiPolygon */
                put_u32(&b, 1, 0);
            }
            put_square(&b, c * SIDE, r * SIDE, SIDE, k % 3 == 1);
            CHECK_OK(snakegrid_regions_add(regions, id, b.bytes, b.len));
        }
    }
    return regions;
}

/* A quicker run than the defaults; the run's outcome is what is tested, not its quality. */
static snakegrid_options *make_options(void) {
    snakegrid_options *options = NULL;
    CHECK_OK(snakegrid_options_new(&options));
    CHECK_OK(snakegrid_options_set_int(options, "refine_moves_per_region", 80));
    CHECK_OK(snakegrid_options_set(options, "noise_levels", "0.02"));
    CHECK_OK(snakegrid_options_set(options, "shifts", "0:0,0:0.5,0.5:0,0.5:0.5"));
    return options;
}

/* ---- version and status ---- */

static void test_version(void) {
    char expected[64];
    snprintf(expected, sizeof expected, "%d.%d.%d", SNAKEGRID_VERSION_MAJOR, SNAKEGRID_VERSION_MINOR,
             SNAKEGRID_VERSION_PATCH);
    CHECK(strcmp(snakegrid_version(), expected) == 0);
    CHECK(strcmp(snakegrid_version(), SNAKEGRID_VERSION) == 0);
}

static void test_status_strings(void) {
    for (uint32_t s = SNAKEGRID_OK; s <= SNAKEGRID_INTERNAL_ERROR; s++) {
        const char *text = snakegrid_status_string(s);
        CHECK(text != NULL && strlen(text) > 0 && strcmp(text, "unknown status") != 0);
    }
    CHECK(strcmp(snakegrid_status_string(SNAKEGRID_UNSUPPORTED + 1), "unknown status") == 0);
    CHECK(strcmp(snakegrid_status_string(UINT32_MAX), "unknown status") == 0);
}

/* ---- NULL arguments, wrong handles, untouched out-parameters ---- */

static void test_null_arguments(void) {
    snakegrid_options *options = make_options();
    snakegrid_regions *regions = make_regions();
    snakegrid_job *job = NULL;
    CHECK_OK(snakegrid_job_new(&job));
    uint8_t byte = 1;

    CHECK_FAILS(snakegrid_options_new(NULL), SNAKEGRID_NULL_ARGUMENT);
    CHECK_MESSAGE_HAS("out");
    CHECK_FAILS(snakegrid_options_set(NULL, "alpha", "1"), SNAKEGRID_NULL_ARGUMENT);
    CHECK_FAILS(snakegrid_options_set(options, NULL, "1"), SNAKEGRID_NULL_ARGUMENT);
    CHECK_MESSAGE_HAS("name");
    CHECK_FAILS(snakegrid_options_set(options, "alpha", NULL), SNAKEGRID_NULL_ARGUMENT);
    CHECK_MESSAGE_HAS("value");
    CHECK_FAILS(snakegrid_options_set_double(NULL, "alpha", 1.0), SNAKEGRID_NULL_ARGUMENT);
    CHECK_FAILS(snakegrid_options_set_int(options, NULL, 1), SNAKEGRID_NULL_ARGUMENT);
    CHECK_FAILS(snakegrid_options_set_bool(NULL, "refine", true), SNAKEGRID_NULL_ARGUMENT);

    CHECK_FAILS(snakegrid_regions_new(NULL), SNAKEGRID_NULL_ARGUMENT);
    CHECK_FAILS(snakegrid_regions_add(NULL, "a", &byte, 1), SNAKEGRID_NULL_ARGUMENT);
    CHECK_FAILS(snakegrid_regions_add(regions, NULL, &byte, 1), SNAKEGRID_NULL_ARGUMENT);
    CHECK_FAILS(snakegrid_regions_add(regions, "a", NULL, 1), SNAKEGRID_NULL_ARGUMENT);
    CHECK_MESSAGE_HAS("wkb");

    CHECK_FAILS(snakegrid_job_new(NULL), SNAKEGRID_NULL_ARGUMENT);
    CHECK_FAILS(snakegrid_job_set(NULL, "src", "x"), SNAKEGRID_NULL_ARGUMENT);
    CHECK_FAILS(snakegrid_job_set(job, NULL, "x"), SNAKEGRID_NULL_ARGUMENT);
    CHECK_FAILS(snakegrid_job_set_overwrite(NULL, true), SNAKEGRID_NULL_ARGUMENT);
    CHECK_FAILS(snakegrid_job_set_update(NULL, true), SNAKEGRID_NULL_ARGUMENT);

    snakegrid_result *result = (snakegrid_result *)&byte; /* must stay untouched */
    CHECK_FAILS(snakegrid_run(NULL, options, NULL, NULL, &result), SNAKEGRID_NULL_ARGUMENT);
    CHECK_MESSAGE_HAS("regions");
    CHECK_FAILS(snakegrid_run(regions, NULL, NULL, NULL, &result), SNAKEGRID_NULL_ARGUMENT);
    CHECK_MESSAGE_HAS("options");
    CHECK_FAILS(snakegrid_run(regions, options, NULL, NULL, NULL), SNAKEGRID_NULL_ARGUMENT);
    CHECK_FAILS(snakegrid_run_job(NULL, options, NULL, NULL, &result), SNAKEGRID_NULL_ARGUMENT);
    CHECK_FAILS(snakegrid_run_job(job, NULL, NULL, NULL, &result), SNAKEGRID_NULL_ARGUMENT);
    CHECK_FAILS(snakegrid_run_job(job, options, NULL, NULL, NULL), SNAKEGRID_NULL_ARGUMENT);
    CHECK(result == (snakegrid_result *)&byte);

    size_t count = 7;
    double size = 7.0;
    const char *text = "untouched";
    const uint8_t *bytes = &byte;
    int32_t col = 7, row = 7;
    snakegrid_layout_metrics layout;
    snakegrid_region_metrics region;
    snakegrid_snake_report snake;
    snakegrid_candidate candidate;
    CHECK_FAILS(snakegrid_result_count(NULL, &count), SNAKEGRID_NULL_ARGUMENT);
    CHECK_FAILS(snakegrid_result_cell_size(NULL, &size), SNAKEGRID_NULL_ARGUMENT);
    CHECK_FAILS(snakegrid_result_region_id(NULL, 0, &text), SNAKEGRID_NULL_ARGUMENT);
    CHECK_FAILS(snakegrid_result_region_repair(NULL, 0, &text), SNAKEGRID_NULL_ARGUMENT);
    CHECK_FAILS(snakegrid_result_cell(NULL, 0, &col, &row), SNAKEGRID_NULL_ARGUMENT);
    CHECK_FAILS(snakegrid_result_cell_wkb(NULL, 0, &bytes, &count), SNAKEGRID_NULL_ARGUMENT);
    CHECK_FAILS(snakegrid_result_region_metrics(NULL, 0, &region), SNAKEGRID_NULL_ARGUMENT);
    CHECK_FAILS(snakegrid_result_layout_metrics(NULL, &layout), SNAKEGRID_NULL_ARGUMENT);
    CHECK_FAILS(snakegrid_result_snake_report(NULL, &snake), SNAKEGRID_NULL_ARGUMENT);
    CHECK_FAILS(snakegrid_result_candidate_count(NULL, &count), SNAKEGRID_NULL_ARGUMENT);
    CHECK_FAILS(snakegrid_result_candidate(NULL, 0, &candidate), SNAKEGRID_NULL_ARGUMENT);
    CHECK_FAILS(snakegrid_result_note_count(NULL, &count), SNAKEGRID_NULL_ARGUMENT);
    CHECK_FAILS(snakegrid_result_note(NULL, 0, &text), SNAKEGRID_NULL_ARGUMENT);
    CHECK_FAILS(snakegrid_result_hexjson(NULL, &text), SNAKEGRID_NULL_ARGUMENT);
    CHECK(count == 7 && size == 7.0 && strcmp(text, "untouched") == 0 && bytes == &byte);
    CHECK(col == 7 && row == 7);

    /* Freeing NULL is allowed and leaves the last message alone. */
    snakegrid_options_free(NULL);
    snakegrid_regions_free(NULL);
    snakegrid_job_free(NULL);
    snakegrid_result_free(NULL);
    CHECK_MESSAGE_HAS("snakegrid_result_hexjson");

    /* A successful call clears the message. */
    CHECK_OK(snakegrid_options_set(options, "alpha", "1"));
    CHECK(strcmp(snakegrid_last_error_message(), "") == 0);

    snakegrid_job_free(job);
    snakegrid_regions_free(regions);
    snakegrid_options_free(options);
}

static void test_wrong_handles(void) {
    snakegrid_options *options = make_options();
    snakegrid_regions *regions = make_regions();
    snakegrid_result *result = NULL;
    /* A handle of another kind is refused, not followed. */
    CHECK_FAILS(snakegrid_run((const snakegrid_regions *)options, options, NULL, NULL, &result),
                SNAKEGRID_INVALID_HANDLE);
    CHECK_MESSAGE_HAS("snakegrid_regions");
    CHECK_FAILS(snakegrid_options_set((snakegrid_options *)regions, "alpha", "1"), SNAKEGRID_INVALID_HANDLE);
    size_t count = 0;
    CHECK_FAILS(snakegrid_result_count((const snakegrid_result *)regions, &count), SNAKEGRID_INVALID_HANDLE);
    CHECK(result == NULL);
    /* Freeing through the wrong kind is refused too, and frees nothing. */
    snakegrid_options_free((snakegrid_options *)regions);
    CHECK_MESSAGE_HAS("snakegrid_options_free");
    snakegrid_regions_free(regions);
    snakegrid_options_free(options);
}

/* ---- options ---- */

static void test_options(void) {
    snakegrid_options *options = NULL;
    CHECK_OK(snakegrid_options_new(&options));
    CHECK_OK(snakegrid_options_set(options, "force_cap", "0.15"));
    CHECK_OK(snakegrid_options_set(options, "load_model", "element"));
    CHECK_OK(snakegrid_options_set(options, "shifts", "0:0,0.5:0.5"));
    CHECK_OK(snakegrid_options_set(options, "simplify_tolerance", "none"));
    CHECK_OK(snakegrid_options_set_double(options, "alpha", 2.5));
    CHECK_OK(snakegrid_options_set_double(options, "epsilon", 1e-4));
    CHECK_OK(snakegrid_options_set_int(options, "max_steps", 12));
    CHECK_OK(snakegrid_options_set_int(options, "beta", 3)); /* an integer for a real is fine */
    CHECK_OK(snakegrid_options_set_bool(options, "refine", false));
    CHECK_OK(snakegrid_options_set_bool(options, "point_adjacency", true));

    CHECK_FAILS(snakegrid_options_set(options, "gamma", "1"), SNAKEGRID_INVALID_OPTION);
    CHECK_MESSAGE_HAS("gamma");
    CHECK_FAILS(snakegrid_options_set_double(options, "no_such_option", 1.0), SNAKEGRID_INVALID_OPTION);
    CHECK_MESSAGE_HAS("no_such_option");
    CHECK_FAILS(snakegrid_options_set_double(options, "alpha", -1.0), SNAKEGRID_INVALID_OPTION);
    CHECK_MESSAGE_HAS("alpha");
    CHECK_FAILS(snakegrid_options_set_double(options, "force_cap", 2.0), SNAKEGRID_INVALID_OPTION);
    CHECK_MESSAGE_HAS("force_cap");
    CHECK_FAILS(snakegrid_options_set_double(options, "beta", NAN), SNAKEGRID_INVALID_OPTION);
    CHECK_FAILS(snakegrid_options_set_double(options, "beta", INFINITY), SNAKEGRID_INVALID_OPTION);
    CHECK_FAILS(snakegrid_options_set_double(options, "max_steps", 1.5), SNAKEGRID_INVALID_OPTION);
    CHECK_MESSAGE_HAS("max_steps");
    CHECK_FAILS(snakegrid_options_set_int(options, "max_steps", -1), SNAKEGRID_INVALID_OPTION);
    CHECK_FAILS(snakegrid_options_set_bool(options, "alpha", true), SNAKEGRID_INVALID_OPTION);
    CHECK_FAILS(snakegrid_options_set(options, "refine", "maybe"), SNAKEGRID_INVALID_OPTION);
    CHECK_FAILS(snakegrid_options_set(options, "shifts", "0.5"), SNAKEGRID_INVALID_OPTION);
    CHECK_FAILS(snakegrid_options_set(options, "load_model", "springs"), SNAKEGRID_INVALID_OPTION);
    /* Text that is not UTF-8 is an argument error, not an unknown option. */
    CHECK_FAILS(snakegrid_options_set(options, "alph\xff", "1"), SNAKEGRID_INVALID_ARGUMENT);
    CHECK_MESSAGE_HAS("UTF-8");
    snakegrid_options_free(options);
}

/* The parameter table: every option described, its default accepted back, its range enforced
 * at both ends, and values that once failed deep inside the Snake refused by name. */
static void test_option_table(void) {
    snakegrid_options *options = NULL;
    CHECK_OK(snakegrid_options_new(&options));
    size_t count = snakegrid_option_count();
    CHECK(count >= 25);
    int found_alpha = 0;
    for (size_t i = 0; i < count; i++) {
        snakegrid_option option;
        CHECK_OK(snakegrid_option_info(i, &option));
        CHECK(option.name != NULL && option.summary[0] != '\0' && option.help[0] != '\0');
        CHECK(option.group[0] != '\0' && option.range[0] != '\0');
        CHECK_OK(snakegrid_options_set(options, option.name, option.default_value));
        if (strcmp(option.name, "alpha") == 0) {
            found_alpha = 1;
            CHECK(option.kind == SNAKEGRID_OPTION_REAL && option.has_minimum && option.has_maximum);
            CHECK(!option.minimum_open && !option.maximum_open);
            CHECK_OK(snakegrid_options_set_double(options, "alpha", option.minimum));
            CHECK_OK(snakegrid_options_set_double(options, "alpha", option.maximum));
            CHECK_FAILS(snakegrid_options_set_double(options, "alpha", option.maximum * 1.01), SNAKEGRID_INVALID_OPTION);
        }
        if (option.kind == SNAKEGRID_OPTION_CHOICE) CHECK(strchr(option.choices, '|') != NULL);
        if (option.kind == SNAKEGRID_OPTION_INTEGER) CHECK(option.integer_bits == 32 || option.integer_bits == 64);
    }
    CHECK(found_alpha);
    snakegrid_option option;
    CHECK_FAILS(snakegrid_option_info(count, &option), SNAKEGRID_INVALID_ARGUMENT);
    CHECK_FAILS(snakegrid_option_info(0, NULL), SNAKEGRID_NULL_ARGUMENT);
    CHECK_FAILS(snakegrid_options_set(options, "alpha", "1e308"), SNAKEGRID_INVALID_OPTION);
    CHECK_MESSAGE_HAS("alpha must be in [0.001, 1000]");
    CHECK_FAILS(snakegrid_options_set(options, "beta", "1e308"), SNAKEGRID_INVALID_OPTION);
    CHECK_FAILS(snakegrid_options_set(options, "spring", "1e-300"), SNAKEGRID_INVALID_OPTION);
    CHECK_MESSAGE_HAS("spring");
    CHECK_FAILS(snakegrid_options_set(options, "alpha", "nan"), SNAKEGRID_INVALID_OPTION);
    /* A whole-number double is fine for an integer option (hosts often hold numbers as doubles). */
    CHECK_OK(snakegrid_options_set_double(options, "max_steps", 12.0));
    snakegrid_options_free(options);
}

/* The working-CRS rule: a country gets Lambert azimuthal equal-area at its centre, the world
 * Equal Earth, and numbers that are not degrees are refused. */
static void test_working_crs(void) {
    const double country[4] = {-125.0, 24.0, -66.0, 50.0};
    const double world[8] = {-180.0, -90.0, 0.0, 83.0, 0.0, -50.0, 180.0, 80.0};
    const double metres[4] = {0.0, 0.0, 10003.0, 3.0};
    snakegrid_crs *crs = NULL;
    const char *text = NULL;
    CHECK_OK(snakegrid_working_crs(country, 1, &crs));
    CHECK_OK(snakegrid_crs_name(crs, &text));
    CHECK(strcmp(text, "Lambert azimuthal equal-area at 37.0N 95.5W (snakegrid)") == 0);
    CHECK_OK(snakegrid_crs_wkt(crs, &text));
    CHECK(strncmp(text, "PROJCRS[", 8) == 0 && strstr(text, "Lambert Azimuthal Equal Area") != NULL);
    CHECK_OK(snakegrid_crs_note(crs, &text));
    CHECK(strstr(text, "centred on the layer") != NULL);
    snakegrid_crs_free(crs);
    crs = NULL;
    CHECK_OK(snakegrid_working_crs(world, 2, &crs));
    CHECK_OK(snakegrid_crs_name(crs, &text));
    CHECK(strcmp(text, "WGS 84 / Equal Earth Greenwich") == 0);
    snakegrid_crs_free(crs);
    crs = NULL;
    CHECK_FAILS(snakegrid_working_crs(metres, 1, &crs), SNAKEGRID_INVALID_INPUT);
    CHECK_MESSAGE_HAS("not longitudes and latitudes");
    CHECK_FAILS(snakegrid_working_crs(country, 0, &crs), SNAKEGRID_INVALID_INPUT);
    CHECK_FAILS(snakegrid_working_crs(NULL, 1, &crs), SNAKEGRID_NULL_ARGUMENT);
    CHECK_FAILS(snakegrid_working_crs(country, 1, NULL), SNAKEGRID_NULL_ARGUMENT);
    CHECK(crs == NULL);
    CHECK_FAILS(snakegrid_crs_name(NULL, &text), SNAKEGRID_NULL_ARGUMENT);
    snakegrid_crs_free(NULL);
}

/* A region drawn across the antimeridian as d3's world-atlas draws Chukotka, its ring stepping
 * from 180 to -180 (a square from 170 to 190, wrapped): its box runs past 180 and it is one
 * country; on a world map centred on 0 it is cut at ±180, centred on it is carried across. */
static void test_antimeridian(void) {
    wkb_buffer b = {{0}, 0};
    const double ring[5][2] = {{170.0, 60.0}, {-170.0, 60.0}, {-170.0, 70.0}, {170.0, 70.0},
                               {170.0, 60.0}};
    b.bytes[b.len++] = 1;
    put_u32(&b, 3, 0);
    put_u32(&b, 1, 0);
    put_u32(&b, 5, 0);
    for (int i = 0; i < 5; i++) {
        put_f64(&b, ring[i][0], 0);
        put_f64(&b, ring[i][1], 0);
    }
    const double *boxes = NULL;
    size_t count = 0;
    CHECK_OK(snakegrid_lon_lat_boxes(b.bytes, b.len, &boxes, &count));
    CHECK(count == 1 && boxes[0] == 170.0 && boxes[2] == 190.0);
    snakegrid_crs *crs = NULL;
    const char *text = NULL;
    CHECK_OK(snakegrid_working_crs(boxes, count, &crs));
    CHECK_OK(snakegrid_crs_name(crs, &text));
    CHECK(strcmp(text, "Lambert azimuthal equal-area at 65.0N 180.0E (snakegrid)") == 0);
    const uint8_t *cut = NULL;
    size_t cut_len = 0;
    CHECK_OK(snakegrid_crs_cut(crs, b.bytes, b.len, &cut, &cut_len));
    CHECK(cut != NULL && cut_len > 9 && cut[0] == 1 && cut[1] == 6); /* one MultiPolygon */
    snakegrid_crs_free(crs);
    const double world[4] = {-180.0, -60.0, 180.0, 80.0};
    crs = NULL;
    CHECK_OK(snakegrid_working_crs(world, 1, &crs));
    CHECK_OK(snakegrid_crs_cut(crs, b.bytes, b.len, &cut, &cut_len));
    CHECK(cut != NULL && cut[5] == 2 && cut[6] == 0); /* two pieces, one each side of ±180 */
    wkb_buffer inside = {{0}, 0};
    put_square(&inside, 10.0, 40.0, 5.0, 0);
    CHECK_OK(snakegrid_crs_cut(crs, inside.bytes, inside.len, &cut, &cut_len));
    CHECK(cut == NULL && cut_len == 0);
    CHECK_FAILS(snakegrid_crs_cut(crs, inside.bytes, 3, &cut, &cut_len), SNAKEGRID_INVALID_INPUT);
    CHECK_FAILS(snakegrid_lon_lat_boxes(NULL, 0, &boxes, &count), SNAKEGRID_NULL_ARGUMENT);
    snakegrid_crs_free(crs);
}

/* What a host laying a layer out in its own CRS tells the user: a Mercator projection by GDAL's,
 * PROJ's or QGIS's name, never UTM; and whether a layer without a CRS could be in degrees. */
static void test_source_crs_advice(void) {
    const char *note = "unset";
    bool degrees = false;
    CHECK_OK(snakegrid_projected_crs_note("merc", "EPSG:3857", &note));
    CHECK(note != NULL && strstr(note, "EPSG:3857 is a Mercator projection") != NULL);
    CHECK_OK(snakegrid_projected_crs_note("Mercator_1SP", "EPSG:3395", &note));
    CHECK(note != NULL && strstr(note, "EPSG:3395") != NULL);
    CHECK_OK(snakegrid_projected_crs_note("Transverse_Mercator", "EPSG:32633", &note));
    CHECK(note == NULL);
    CHECK_FAILS(snakegrid_projected_crs_note(NULL, "EPSG:3857", &note), SNAKEGRID_NULL_ARGUMENT);
    CHECK_FAILS(snakegrid_projected_crs_note("merc", "EPSG:3857", NULL), SNAKEGRID_NULL_ARGUMENT);
    const double africa[4] = {-17.0, -35.0, 51.0, 37.0};
    const double metres[4] = {400000.0, 4000000.0, 500000.0, 4100000.0};
    CHECK_OK(snakegrid_looks_like_degrees(africa, 1, &degrees));
    CHECK(degrees);
    CHECK_OK(snakegrid_looks_like_degrees(metres, 1, &degrees));
    CHECK(!degrees);
    CHECK_FAILS(snakegrid_looks_like_degrees(NULL, 1, &degrees), SNAKEGRID_NULL_ARGUMENT);
}

/* The fields a grid layer adds: named, typed, and valued per region as the cell accessors say. */
static void test_fields(void) {
    size_t count = snakegrid_field_count();
    CHECK(count >= 5);
    snakegrid_field field;
    CHECK_OK(snakegrid_field_info(0, &field));
    CHECK(strcmp(field.name, "grid_col") == 0 && field.integer && field.description[0] != '\0');
    CHECK_OK(snakegrid_field_info(1, &field));
    CHECK(strcmp(field.name, "grid_row") == 0 && field.integer);
    CHECK_OK(snakegrid_field_info(2, &field));
    CHECK(strcmp(field.name, "grid_q") == 0 && field.integer);
    CHECK_OK(snakegrid_field_info(3, &field));
    CHECK(strcmp(field.name, "grid_r") == 0 && field.integer);
    CHECK_FAILS(snakegrid_field_info(count, &field), SNAKEGRID_INVALID_ARGUMENT);

    snakegrid_options *options = make_options();
    snakegrid_regions *regions = make_regions();
    snakegrid_result *result = NULL;
    CHECK_OK(snakegrid_run(regions, options, NULL, NULL, &result));
    for (size_t i = 0; result != NULL && i < REGIONS; i++) {
        int32_t col = -1, row = -1;
        double value_col = -2, value_row = -2, displacement = -1;
        snakegrid_region_metrics metrics;
        CHECK_OK(snakegrid_result_cell(result, i, &col, &row));
        CHECK_OK(snakegrid_result_field(result, i, 0, &value_col));
        CHECK_OK(snakegrid_result_field(result, i, 1, &value_row));
        CHECK(value_col == col && value_row == row);
        CHECK_OK(snakegrid_result_region_metrics(result, i, &metrics));
        /* For squares the axial coordinates are the column and the row. */
        double q = -2, r = -2;
        CHECK_OK(snakegrid_result_field(result, i, 2, &q));
        CHECK_OK(snakegrid_result_field(result, i, 3, &r));
        CHECK(q == col && r == row);
        CHECK_OK(snakegrid_result_field(result, i, 4, &displacement));
        CHECK(displacement == metrics.displacement);
    }
    double unused = 0;
    CHECK_FAILS(snakegrid_result_field(result, REGIONS, 0, &unused), SNAKEGRID_INVALID_ARGUMENT);
    CHECK_FAILS(snakegrid_result_field(result, 0, count, &unused), SNAKEGRID_INVALID_ARGUMENT);
    snakegrid_result_free(result);
    snakegrid_regions_free(regions);
    snakegrid_options_free(options);
}

/* ---- regions ---- */

static void test_bad_regions(void) {
    snakegrid_regions *regions = NULL;
    CHECK_OK(snakegrid_regions_new(&regions));
    wkb_buffer square = {{0}, 0};
    put_square(&square, 0, 0, 1, 0);

    for (size_t len = 0; len < square.len; len += 7) {
        CHECK_FAILS(snakegrid_regions_add(regions, "cut", square.bytes, len), SNAKEGRID_INVALID_INPUT);
        CHECK_MESSAGE_HAS("cut");
        CHECK_MESSAGE_HAS("WKB");
    }
    wkb_buffer longer = square;
    longer.bytes[longer.len++] = 0;
    CHECK_FAILS(snakegrid_regions_add(regions, "long", longer.bytes, longer.len), SNAKEGRID_INVALID_INPUT);
    CHECK_MESSAGE_HAS("long");

    wkb_buffer garbage = square;
    garbage.bytes[0] = 7; /* no such byte order */
    CHECK_FAILS(snakegrid_regions_add(regions, "garbage", garbage.bytes, garbage.len), SNAKEGRID_INVALID_INPUT);

    wkb_buffer point = {{0}, 0};
    point.bytes[point.len++] = 1;
    put_u32(&point, 1, 0);
    put_f64(&point, 1.0, 0);
    put_f64(&point, 2.0, 0);
    CHECK_FAILS(snakegrid_regions_add(regions, "dot", point.bytes, point.len), SNAKEGRID_INVALID_INPUT);
    CHECK_MESSAGE_HAS("dot");
    CHECK_MESSAGE_HAS("Point");

    CHECK_FAILS(snakegrid_regions_add(regions, "\xc3", square.bytes, square.len), SNAKEGRID_INVALID_ARGUMENT);
    CHECK_FAILS(snakegrid_regions_add(regions, "huge", square.bytes, (size_t)-1), SNAKEGRID_INVALID_ARGUMENT);
    snakegrid_regions_free(regions);
}

/* The whole set is checked by the run: empty input, duplicate ids. */
static void test_invalid_input_runs(void) {
    snakegrid_options *options = make_options();
    snakegrid_regions *regions = NULL;
    snakegrid_result *result = NULL;
    CHECK_OK(snakegrid_regions_new(&regions));
    CHECK_FAILS(snakegrid_run(regions, options, NULL, NULL, &result), SNAKEGRID_INVALID_INPUT);
    CHECK(result == NULL);

    wkb_buffer a = {{0}, 0}, b = {{0}, 0};
    put_square(&a, 0, 0, 1, 0);
    put_square(&b, 1, 0, 1, 0);
    CHECK_OK(snakegrid_regions_add(regions, "twin", a.bytes, a.len));
    CHECK_OK(snakegrid_regions_add(regions, "twin", b.bytes, b.len));
    CHECK_FAILS(snakegrid_run(regions, options, NULL, NULL, &result), SNAKEGRID_INVALID_INPUT);
    CHECK_MESSAGE_HAS("twin");
    CHECK(result == NULL);
    snakegrid_regions_free(regions);
    snakegrid_options_free(options);
}

/* ---- a run and every result field ---- */

typedef struct {
    int calls;
    double last;
    int monotone;
    int in_range;
    int cancel_after; /* cancel on this call; 0 never */
} progress_log;

/* Called one at a time, though maybe from worker threads: no locking needed. */
static int record_progress(double fraction, const char *message, void *user_data) {
    progress_log *log = user_data;
    log->calls++;
    if (fraction < 0.0 || fraction > 1.0 || message == NULL) log->in_range = 0;
    if (fraction < log->last) log->monotone = 0;
    log->last = fraction;
    return log->cancel_after != 0 && log->calls >= log->cancel_after;
}

static void check_result(const snakegrid_result *result) {
    size_t count = 0;
    CHECK_OK(snakegrid_result_count(result, &count));
    CHECK(count == REGIONS);
    double cell_size = 0;
    CHECK_OK(snakegrid_result_cell_size(result, &cell_size));
    /* Total area / M is one square per region. */
    CHECK(cell_size > 0.5 * SIDE && cell_size < 2.0 * SIDE);

    int used[64][64] = {{0}};
    int cols = 0, rows = 0;
    for (size_t i = 0; i < count; i++) {
        const char *id = NULL;
        CHECK_OK(snakegrid_result_region_id(result, i, &id));
        char expected[16];
        snprintf(expected, sizeof expected, "r%d%d", (int)(i % COLS), (int)(i / COLS));
        CHECK(id != NULL && strcmp(id, expected) == 0); /* input order */

        int32_t col = -1, row = -1;
        CHECK_OK(snakegrid_result_cell(result, i, &col, &row));
        CHECK(col >= 0 && col < 64 && row >= 0 && row < 64);
        if (col >= 0 && col < 64 && row >= 0 && row < 64) {
            CHECK(used[col][row] == 0); /* one region per cell */
            used[col][row] = 1;
            if (col + 1 > cols) cols = col + 1;
            if (row + 1 > rows) rows = row + 1;
        }

        const uint8_t *wkb = NULL;
        size_t wkb_len = 0;
        CHECK_OK(snakegrid_result_cell_wkb(result, i, &wkb, &wkb_len));
        /* Little-endian Polygon, one ring of 5 points: 1 + 4 + 4 + 4 + 5 * 16 bytes. */
        CHECK(wkb != NULL && wkb_len == 93);
        if (wkb != NULL && wkb_len == 93) {
            CHECK(wkb[0] == 1 && get_u32_le(wkb + 1) == 3 && get_u32_le(wkb + 5) == 1 && get_u32_le(wkb + 9) == 5);
            double min_x = INFINITY, max_x = -INFINITY, min_y = INFINITY, max_y = -INFINITY;
            for (int p = 0; p < 5; p++) {
                double x = get_f64_le(wkb + 13 + 16 * p), y = get_f64_le(wkb + 21 + 16 * p);
                min_x = fmin(min_x, x), max_x = fmax(max_x, x), min_y = fmin(min_y, y), max_y = fmax(max_y, y);
            }
            CHECK(fabs((max_x - min_x) - cell_size) < 1e-6 * cell_size);
            CHECK(fabs((max_y - min_y) - cell_size) < 1e-6 * cell_size);
        }

        snakegrid_region_metrics m;
        CHECK_OK(snakegrid_result_region_metrics(result, i, &m));
        CHECK(m.displacement >= 0 && isfinite(m.displacement));
        CHECK(m.neighbours_kept >= 0 && m.neighbours_kept <= 1);
        CHECK(m.orientation_error >= 0 && m.orientation_error <= 180);
    }
    CHECK(cols * rows >= REGIONS);

    snakegrid_layout_metrics layout;
    CHECK_OK(snakegrid_result_layout_metrics(result, &layout));
    CHECK(layout.location >= 0 && isfinite(layout.location) && layout.location_raw >= 0 && layout.location_moved >= 0);
    CHECK(layout.adjacent >= 0 && layout.adjacent <= 1 && layout.adjacent_rook >= 0 && layout.adjacent_rook <= layout.adjacent);
    CHECK(layout.orientation >= 0 && layout.orientation <= 180);
    CHECK(layout.misdirected >= 0 && layout.misdirected <= 1);
    CHECK(layout.shape >= 0 && layout.shape <= 1);
    /* A block of squares is already a grid map: the method should keep most neighbours. */
    CHECK(layout.adjacent >= 0.8);

    snakegrid_snake_report snake;
    CHECK_OK(snakegrid_result_snake_report(result, &snake));
    CHECK(snake.stop_reason <= SNAKEGRID_STOP_NOT_RUN);
    CHECK(snake.nodes >= REGIONS && snake.edges >= REGIONS - 1);
    CHECK(snake.spread_before >= 0 && snake.spread_after >= 0);

    size_t candidates = 0;
    CHECK_OK(snakegrid_result_candidate_count(result, &candidates));
    CHECK(candidates == 8); /* noise levels 0 and 0.02, four shifts each */
    for (size_t i = 0; i < candidates; i++) {
        snakegrid_candidate c;
        CHECK_OK(snakegrid_result_candidate(result, i, &c));
        CHECK(c.noise == 0.0 || c.noise == 0.02);
        CHECK((c.shift_x == 0.0 || c.shift_x == 0.5) && (c.shift_y == 0.0 || c.shift_y == 0.5));
        CHECK(c.score >= 0 && c.score <= 1);
        if (i == 0) {
            /* The first candidate is the chosen layout. */
            CHECK(memcmp(&c.metrics, &layout, sizeof layout) == 0);
            CHECK(c.snake.steps == snake.steps && c.snake.stop_reason == snake.stop_reason);
        }
    }

    /* The moved outline: a little-endian MultiPolygon whose parts are Polygons. */
    const uint8_t *outline = NULL;
    size_t outline_len = 0;
    CHECK_OK(snakegrid_result_moved_outline_wkb(result, &outline, &outline_len));
    CHECK(outline != NULL && outline_len >= 9 + 13 + 4 * 16);
    if (outline != NULL && outline_len >= 9 + 13 + 4 * 16) {
        CHECK(outline[0] == 1 && get_u32_le(outline + 1) == 6 && get_u32_le(outline + 5) >= 1);
        CHECK(outline[9] == 1 && get_u32_le(outline + 10) == 3);
    }
    size_t untouched_len = 11;
    CHECK_FAILS(snakegrid_result_moved_outline_wkb(result, NULL, &untouched_len), SNAKEGRID_NULL_ARGUMENT);
    CHECK(untouched_len == 11);

    size_t notes = 7;
    CHECK_OK(snakegrid_result_note_count(result, &notes));
    CHECK(notes == 0);

    /* Indexes past the end are argument errors that leave the outputs alone. */
    const char *id = "untouched";
    int32_t col = -7, row = -7;
    snakegrid_candidate c;
    CHECK_FAILS(snakegrid_result_region_id(result, count, &id), SNAKEGRID_INVALID_ARGUMENT);
    CHECK_MESSAGE_HAS("out of range");
    CHECK_FAILS(snakegrid_result_cell(result, (size_t)-1, &col, &row), SNAKEGRID_INVALID_ARGUMENT);
    CHECK_FAILS(snakegrid_result_candidate(result, candidates, &c), SNAKEGRID_INVALID_ARGUMENT);
    CHECK_FAILS(snakegrid_result_note(result, 0, &id), SNAKEGRID_INVALID_ARGUMENT);
    CHECK(strcmp(id, "untouched") == 0 && col == -7 && row == -7);
    CHECK_FAILS(snakegrid_result_cell(result, 0, NULL, &row), SNAKEGRID_NULL_ARGUMENT);
    CHECK_FAILS(snakegrid_result_cell_wkb(result, 0, NULL, &count), SNAKEGRID_NULL_ARGUMENT);
}

static void test_run(void) {
    snakegrid_options *options = make_options();
    snakegrid_regions *regions = make_regions();
    snakegrid_result *result = NULL;
    progress_log log = {0, 0.0, 1, 1, 0};
    CHECK_OK(snakegrid_run(regions, options, record_progress, &log, &result));
    CHECK(result != NULL);
    CHECK(log.calls > 0 && log.in_range && log.monotone);
    if (result != NULL) check_result(result);

    /* Without a callback, and with the same options: the same layout, cell for cell. */
    snakegrid_result *again = NULL;
    CHECK_OK(snakegrid_run(regions, options, NULL, NULL, &again));
    CHECK(again != NULL);
    for (size_t i = 0; result != NULL && again != NULL && i < REGIONS; i++) {
        int32_t col = -1, row = -1, col_again = -2, row_again = -2;
        CHECK_OK(snakegrid_result_cell(result, i, &col, &row));
        CHECK_OK(snakegrid_result_cell(again, i, &col_again, &row_again));
        CHECK(col == col_again && row == row_again);
    }
    snakegrid_result_free(again);
    snakegrid_result_free(result);
    snakegrid_regions_free(regions);
    snakegrid_options_free(options);
}

/* Hexagons through the in-memory API: six-cornered cells, their HexJSON with one hexagon per
 * region keyed by its id, and a refusal naming the way out for squares. */
static void test_hexagons(void) {
    snakegrid_options *options = make_options();
    CHECK_OK(snakegrid_options_set(options, "cell", "hex"));
    CHECK_OK(snakegrid_options_set(options, "hex_orientation", "flat"));
    snakegrid_regions *regions = make_regions();
    snakegrid_result *result = NULL;
    CHECK_OK(snakegrid_run(regions, options, NULL, NULL, &result));
    if (result != NULL) {
        const uint8_t *bytes = NULL;
        size_t len = 0;
        CHECK_OK(snakegrid_result_cell_wkb(result, 0, &bytes, &len));
        /* A polygon of one ring of 7 points (the first repeated): 9 + 4 + 7 * 16 bytes. */
        CHECK(len == 9 + 4 + 7 * 16 && get_u32_le(bytes + 5) == 1 && get_u32_le(bytes + 9) == 7);
        const char *text = NULL;
        CHECK_OK(snakegrid_result_hexjson(result, &text));
        CHECK(text != NULL && (strstr(text, "\"odd-q\"") || strstr(text, "\"even-q\"")));
        for (int k = 0; text != NULL && k < REGIONS; k++) {
            char key[32];
            snprintf(key, sizeof key, "\"r%d%d\": {\"q\": ", k % COLS, k / COLS);
            CHECK(strstr(text, key) != NULL);
        }
        snakegrid_result_free(result);
    }
    snakegrid_options_free(options);

    snakegrid_options *squares = make_options();
    CHECK_OK(snakegrid_run(regions, squares, NULL, NULL, &result));
    const char *untouched = "untouched";
    CHECK_FAILS(snakegrid_result_hexjson(result, &untouched), SNAKEGRID_INVALID_ARGUMENT);
    CHECK_MESSAGE_HAS("cell hex");
    CHECK(strcmp(untouched, "untouched") == 0);
    snakegrid_result_free(result);
    snakegrid_options_free(squares);
    snakegrid_regions_free(regions);
}

/* Groups (method.md §10): the west and east halves of the test map, a cell apart. */
static void test_groups(void) {
    snakegrid_regions *regions = make_regions();
    CHECK_FAILS(snakegrid_regions_set_group(regions, REGIONS, "west"), SNAKEGRID_INVALID_ARGUMENT);
    CHECK_MESSAGE_HAS("24 regions");
    /* Without groups there are no group metrics. */
    snakegrid_options *options = make_options();
    snakegrid_result *result = NULL;
    CHECK_OK(snakegrid_run(regions, options, NULL, NULL, &result));
    snakegrid_group_metrics metrics;
    CHECK_FAILS(snakegrid_result_group_metrics(result, &metrics), SNAKEGRID_INVALID_ARGUMENT);
    CHECK_MESSAGE_HAS("without groups");
    snakegrid_result_free(result);
    /* Regions are added row by row, column c at index r * COLS + c. */
    for (int k = 0; k < REGIONS; k++) {
        CHECK_OK(snakegrid_regions_set_group(regions, (size_t)k, k % COLS < COLS / 2 ? "west" : "east"));
    }
    CHECK_OK(snakegrid_options_set(options, "group_gap", "1"));
    result = NULL;
    CHECK_OK(snakegrid_run(regions, options, NULL, NULL, &result));
    if (result != NULL) {
        CHECK_OK(snakegrid_result_group_metrics(result, &metrics));
        CHECK(metrics.groups == 2 && metrics.blocks == 2 && metrics.group_pairs == 1);
        CHECK(metrics.whole == 1.0 && metrics.adjacency == 1.0 && metrics.reach == 2);
        CHECK(metrics.contacts == 0);
        /* grid_group numbers the blocks 1 and 2, one per half. */
        size_t field = snakegrid_field_count();
        for (size_t f = 0; f < snakegrid_field_count(); f++) {
            snakegrid_field info;
            CHECK_OK(snakegrid_field_info(f, &info));
            if (strcmp(info.name, "grid_group") == 0) field = f;
        }
        CHECK(field < snakegrid_field_count());
        double west = 0.0, east = 0.0;
        CHECK_OK(snakegrid_result_field(result, 0, field, &west));
        CHECK_OK(snakegrid_result_field(result, COLS - 1, field, &east));
        CHECK((west == 1.0 && east == 2.0) || (west == 2.0 && east == 1.0));
        for (int k = 0; k < REGIONS; k++) {
            double block = 0.0;
            CHECK_OK(snakegrid_result_field(result, (size_t)k, field, &block));
            CHECK(block == (k % COLS < COLS / 2 ? west : east));
        }
        snakegrid_result_free(result);
    }
    snakegrid_options_free(options);
    snakegrid_regions_free(regions);
}

/* The index of the added field `name`. */
static size_t field_named(const char *name) {
    for (size_t f = 0; f < snakegrid_field_count(); f++) {
        snakegrid_field info;
        CHECK_OK(snakegrid_field_info(f, &info));
        if (strcmp(info.name, name) == 0) return f;
    }
    CHECK(0);
    return 0;
}

static double cell_field(const snakegrid_result *result, size_t region, const char *name) {
    double value = NAN;
    CHECK_OK(snakegrid_result_field(result, region, field_named(name), &value));
    return value;
}

/* Pins (method.md §10): two regions keep their cells, in a frame of the caller's choosing. */
static void test_pins(void) {
    snakegrid_regions *regions = make_regions();
    CHECK_FAILS(snakegrid_regions_set_pin(regions, REGIONS, 0, 0), SNAKEGRID_INVALID_ARGUMENT);
    CHECK_MESSAGE_HAS("24 regions");
    CHECK_FAILS(snakegrid_regions_set_pin(regions, 0, 2.5, 0), SNAKEGRID_INVALID_ARGUMENT);
    CHECK_MESSAGE_HAS("feature r00: the pin column 2.5 is not a whole number");
    CHECK_FAILS(snakegrid_regions_set_pin(regions, 0, 1, NAN), SNAKEGRID_INVALID_ARGUMENT);
    CHECK_MESSAGE_HAS("the pin row is not");
    /* r00 (the south-west corner) and r10 east of it, at negative columns. */
    CHECK_OK(snakegrid_regions_set_pin(regions, 0, -5, 9));
    CHECK_OK(snakegrid_regions_set_pin(regions, 1, -4, 9));
    snakegrid_options *options = make_options();
    snakegrid_result *result = NULL;
    CHECK_OK(snakegrid_run(regions, options, NULL, NULL, &result));
    if (result != NULL) {
        CHECK(cell_field(result, 0, "grid_col") == -5 && cell_field(result, 0, "grid_row") == 9);
        CHECK(cell_field(result, 1, "grid_col") == -4 && cell_field(result, 1, "grid_row") == 9);
        snakegrid_result_free(result);
    }
    /* Two regions on one cell: refused, naming both. */
    CHECK_OK(snakegrid_regions_set_pin(regions, 1, -5, 9));
    result = NULL;
    CHECK_FAILS(snakegrid_run(regions, options, NULL, NULL, &result), SNAKEGRID_INVALID_INPUT);
    CHECK_MESSAGE_HAS("feature r10");
    CHECK_MESSAGE_HAS("feature r00");
    CHECK(result == NULL);
    snakegrid_options_free(options);
    snakegrid_regions_free(regions);
}

static void set_f64_le(uint8_t *p, double v) {
    uint64_t bits;
    memcpy(&bits, &v, sizeof v);
    for (int i = 0; i < 8; i++) p[i] = (uint8_t)(bits >> (8 * i));
}

/* The cells of `result` in its order as a regions handle, cell `moved` shifted by (dx, dy)
 * cells (its WKB is a little-endian polygon of one ring of 5 points). */
static snakegrid_regions *edited_cells(const snakegrid_result *result, size_t moved, double dx,
                                       double dy) {
    snakegrid_regions *cells = NULL;
    double size = 0.0;
    CHECK_OK(snakegrid_regions_new(&cells));
    CHECK_OK(snakegrid_result_cell_size(result, &size));
    for (size_t k = 0; k < REGIONS; k++) {
        const char *id = NULL;
        const uint8_t *wkb = NULL;
        size_t len = 0;
        CHECK_OK(snakegrid_result_region_id(result, k, &id));
        CHECK_OK(snakegrid_result_cell_wkb(result, k, &wkb, &len));
        uint8_t copy[128];
        CHECK(len <= sizeof copy);
        memcpy(copy, wkb, len);
        for (int point = 0; k == moved && point < 5; point++) {
            uint8_t *xy = copy + 13 + 16 * point;
            set_f64_le(xy, get_f64_le(xy) + dx * size);
            set_f64_le(xy + 8, get_f64_le(xy + 8) + dy * size);
        }
        CHECK_OK(snakegrid_regions_add(cells, id, copy, len));
    }
    return cells;
}

/* Re-layout after hand edits: the moved cell and the kept one are pinned where they lie. */
static void test_edit_pins(void) {
    snakegrid_regions *regions = make_regions();
    snakegrid_options *options = make_options();
    snakegrid_result *result = NULL;
    CHECK_OK(snakegrid_run(regions, options, NULL, NULL, &result));
    if (result == NULL) return;
    int32_t q[REGIONS], r[REGIONS];
    bool keep[REGIONS] = {false};
    for (size_t k = 0; k < REGIONS; k++) {
        q[k] = (int32_t)cell_field(result, k, "grid_q");
        r[k] = (int32_t)cell_field(result, k, "grid_r");
    }
    keep[1] = true;
    /* r00 dragged three cells west, off the map: moved, to column − 3. */
    snakegrid_regions *cells = edited_cells(result, 0, -3.0, 0.0);
    snakegrid_edit_pin out[REGIONS];
    CHECK_OK(snakegrid_edit_pins(cells, q, r, keep, REGIONS, options, out));
    CHECK(out[0].pinned && out[0].moved && out[0].col == q[0] - 3 && out[0].row == r[0]);
    CHECK(out[1].pinned && !out[1].moved && out[1].col == q[1] && out[1].row == r[1]);
    for (size_t k = 2; k < REGIONS; k++) CHECK(!out[k].pinned);
    CHECK_FAILS(snakegrid_edit_pins(cells, q, r, keep, REGIONS - 1, options, out),
                SNAKEGRID_INVALID_ARGUMENT);
    CHECK_MESSAGE_HAS("count is 23 but there are 24 cells");
    snakegrid_regions_free(cells);
    /* r00 dragged onto r10's cell: refused, naming both. */
    cells = edited_cells(result, 0, q[1] - q[0], r[0] - r[1]);
    CHECK_FAILS(snakegrid_edit_pins(cells, q, r, NULL, REGIONS, options, out),
                SNAKEGRID_INVALID_INPUT);
    CHECK_MESSAGE_HAS("r00");
    CHECK_MESSAGE_HAS("r10");
    snakegrid_regions_free(cells);
    snakegrid_result_free(result);
    snakegrid_options_free(options);
    snakegrid_regions_free(regions);
}

static void test_cancel(void) {
    snakegrid_options *options = make_options();
    snakegrid_regions *regions = make_regions();
    snakegrid_result *result = NULL;
    progress_log log = {0, 0.0, 1, 1, 1};
    CHECK_FAILS(snakegrid_run(regions, options, record_progress, &log, &result), SNAKEGRID_CANCELLED);
    CHECK(result == NULL);
    CHECK(log.calls == 1); /* never called again once it has said stop */
    snakegrid_regions_free(regions);
    snakegrid_options_free(options);
}

/* ---- scoring a layout made elsewhere ---- */

/* The cells of `result` as a regions handle, each under its region's id, in reverse order (the
 * score matches them by id), leaving out the id `skip` (NULL: none). */
static snakegrid_regions *cells_of(const snakegrid_result *result, const char *skip) {
    snakegrid_regions *cells = NULL;
    size_t count = 0;
    CHECK_OK(snakegrid_regions_new(&cells));
    CHECK_OK(snakegrid_result_count(result, &count));
    for (size_t k = count; k-- > 0;) {
        const char *id = NULL;
        const uint8_t *wkb = NULL;
        size_t len = 0;
        CHECK_OK(snakegrid_result_region_id(result, k, &id));
        CHECK_OK(snakegrid_result_cell_wkb(result, k, &wkb, &len));
        if (skip == NULL || strcmp(id, skip) != 0) CHECK_OK(snakegrid_regions_add(cells, id, wkb, len));
    }
    return cells;
}

static void test_score(void) {
    snakegrid_options *options = make_options();
    snakegrid_regions *regions = make_regions();
    snakegrid_result *result = NULL;
    CHECK_OK(snakegrid_run(regions, options, NULL, NULL, &result));
    if (result == NULL) return;

    /* The run's own layout scores as the run measured it. */
    snakegrid_regions *cells = cells_of(result, NULL);
    snakegrid_layout_metrics run_layout, layout;
    snakegrid_region_metrics per_region[REGIONS];
    CHECK_OK(snakegrid_result_layout_metrics(result, &run_layout));
    CHECK_OK(snakegrid_score(regions, cells, &layout, per_region, REGIONS));
    CHECK(fabs(layout.location - run_layout.location) < 1e-9);
    CHECK(fabs(layout.adjacent - run_layout.adjacent) < 1e-9);
    CHECK(fabs(layout.orientation - run_layout.orientation) < 1e-9);
    CHECK(fabs(layout.shape - run_layout.shape) < 1e-9);
    for (size_t i = 0; i < REGIONS; i++) {
        snakegrid_region_metrics m;
        CHECK_OK(snakegrid_result_region_metrics(result, i, &m));
        CHECK(fabs(m.neighbours_kept - per_region[i].neighbours_kept) < 1e-9);
        CHECK(fabs(m.orientation_error - per_region[i].orientation_error) < 1e-9);
    }
    /* The per-region array is optional. */
    CHECK_OK(snakegrid_score(regions, cells, &layout, NULL, 0));

    /* Failures name the id and leave the outputs alone. */
    snakegrid_layout_metrics untouched;
    memset(&untouched, 0x5a, sizeof untouched);
    snakegrid_layout_metrics before = untouched;
    CHECK_FAILS(snakegrid_score(regions, cells, &untouched, per_region, REGIONS - 1), SNAKEGRID_INVALID_ARGUMENT);
    CHECK_MESSAGE_HAS("region_metrics_len");
    snakegrid_regions *missing = cells_of(result, "r23");
    CHECK_FAILS(snakegrid_score(regions, missing, &untouched, NULL, 0), SNAKEGRID_INVALID_INPUT);
    CHECK_MESSAGE_HAS("r23");
    wkb_buffer extra = {{0}, 0};
    put_square(&extra, 0, 0, SIDE, 0);
    CHECK_OK(snakegrid_regions_add(cells, "stray", extra.bytes, extra.len));
    CHECK_FAILS(snakegrid_score(regions, cells, &untouched, NULL, 0), SNAKEGRID_INVALID_INPUT);
    CHECK_MESSAGE_HAS("stray");
    CHECK(memcmp(&untouched, &before, sizeof before) == 0);
    CHECK_FAILS(snakegrid_score(regions, cells, NULL, NULL, 0), SNAKEGRID_NULL_ARGUMENT);
    CHECK_FAILS(snakegrid_score(regions, (const snakegrid_regions *)options, &layout, NULL, 0),
                SNAKEGRID_INVALID_HANDLE);

    snakegrid_regions_free(missing);
    snakegrid_regions_free(cells);
    snakegrid_result_free(result);
    snakegrid_regions_free(regions);
    snakegrid_options_free(options);
}

/* ---- threads: independent handles at once, a shared read-only one, per-thread messages ---- */

typedef struct {
    const snakegrid_options *options; /* shared, only read */
    snakegrid_status status;
    int32_t cells[REGIONS][2];
    int message_is_own;
} thread_job;

static void *run_in_thread(void *arg) {
    thread_job *job = arg;
    snakegrid_regions *regions = make_regions();
    snakegrid_result *result = NULL;
    job->status = snakegrid_run(regions, job->options, NULL, NULL, &result);
    for (size_t i = 0; result != NULL && i < REGIONS; i++) {
        if (snakegrid_result_cell(result, i, &job->cells[i][0], &job->cells[i][1]) != SNAKEGRID_OK)
            job->status = SNAKEGRID_INTERNAL_ERROR;
    }
    /* A failure on this thread leaves its own message, whatever the other thread does. */
    job->message_is_own =
        snakegrid_options_set(NULL, "alpha", "1") == SNAKEGRID_NULL_ARGUMENT &&
        strstr(snakegrid_last_error_message(), "snakegrid_options_set") != NULL;
    snakegrid_result_free(result);
    snakegrid_regions_free(regions);
    return NULL;
}

static void test_threads(void) {
    snakegrid_options *options = make_options();
    thread_job jobs[2];
    pthread_t threads[2];
    memset(jobs, 0, sizeof jobs);
    for (int t = 0; t < 2; t++) {
        jobs[t].options = options;
        CHECK(pthread_create(&threads[t], NULL, run_in_thread, &jobs[t]) == 0);
    }
    for (int t = 0; t < 2; t++) CHECK(pthread_join(threads[t], NULL) == 0);
    for (int t = 0; t < 2; t++) {
        CHECK(jobs[t].status == SNAKEGRID_OK);
        CHECK(jobs[t].message_is_own);
    }
    /* The method is deterministic: both threads found the same layout. */
    CHECK(memcmp(jobs[0].cells, jobs[1].cells, sizeof jobs[0].cells) == 0);
    snakegrid_options_free(options);
}

int main(void) {
    test_version();
    test_status_strings();
    test_null_arguments();
    test_wrong_handles();
    test_options();
    test_option_table();
    test_working_crs();
    test_antimeridian();
    test_source_crs_advice();
    test_fields();
    test_bad_regions();
    test_invalid_input_runs();
    test_run();
    test_hexagons();
    test_groups();
    test_pins();
    test_edit_pins();
    test_cancel();
    test_score();
    test_threads();
    return check_summary("test_api");
}
