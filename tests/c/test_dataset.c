/* The dataset entry point on a real layer, and the in-memory entry point on the same regions
 * read through GDAL's own C API: both must give the same cells. Then what the job settings of
 * the command line's -update, -s_srs, -lco, -dsco and -f do, and that a refused or cancelled
 * run leaves an existing destination byte for byte as it was.
 *
 * usage: test_dataset SOURCE.gpkg OUTPUT_DIR   (e.g. shared/data/us_states.gpkg, a fresh dir)
 */
#define _POSIX_C_SOURCE 200809L /* pthreads, unlink and access under -std=c99 */
#include <gdal.h>
#include <ogr_api.h>
#include <ogr_srs_api.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "check.h"

static int cancel_at_once(double fraction, const char *message, void *user_data) {
    (void)fraction;
    (void)message;
    (*(int *)user_data)++;
    return 1;
}

/* The bytes of a file (malloc'd, *size set), NULL when it cannot be read. */
static unsigned char *file_bytes(const char *path, long *size) {
    FILE *file = fopen(path, "rb");
    if (file == NULL) return NULL;
    fseek(file, 0, SEEK_END);
    *size = ftell(file);
    rewind(file);
    unsigned char *bytes = malloc((size_t)*size + 1);
    if (bytes != NULL && fread(bytes, 1, (size_t)*size, file) != (size_t)*size) {
        free(bytes);
        bytes = NULL;
    }
    fclose(file);
    return bytes;
}

/* Whether the file at `path` holds exactly `size` bytes equal to `bytes`. */
static int same_bytes(const char *path, const unsigned char *bytes, long size) {
    long now_size = 0;
    unsigned char *now = file_bytes(path, &now_size);
    int same = now != NULL && bytes != NULL && now_size == size && memcmp(now, bytes, (size_t)size) == 0;
    free(now);
    return same;
}

static snakegrid_job *make_job(const char *src, const char *dst) {
    snakegrid_job *job = NULL;
    CHECK_OK(snakegrid_job_new(&job));
    CHECK_OK(snakegrid_job_set(job, "src", src));
    CHECK_OK(snakegrid_job_set(job, "dst", dst));
    CHECK_OK(snakegrid_job_set(job, "id_field", "id"));
    return job;
}

/* The regions of the layer as snakegrid_regions, read as any GDAL user would. */
static snakegrid_regions *read_regions(const char *src) {
    snakegrid_regions *regions = NULL;
    CHECK_OK(snakegrid_regions_new(&regions));
    GDALDatasetH dataset = GDALOpenEx(src, GDAL_OF_VECTOR | GDAL_OF_READONLY, NULL, NULL, NULL);
    CHECK(dataset != NULL);
    if (dataset == NULL) return regions;
    OGRLayerH layer = GDALDatasetGetLayer(dataset, 0);
    OGRFeatureH feature;
    OGR_L_ResetReading(layer);
    while ((feature = OGR_L_GetNextFeature(layer)) != NULL) {
        const char *id = OGR_F_GetFieldAsString(feature, OGR_F_GetFieldIndex(feature, "id"));
        OGRGeometryH geometry = OGR_F_GetGeometryRef(feature);
        int size = OGR_G_WkbSize(geometry);
        unsigned char *wkb = malloc((size_t)size);
        CHECK(OGR_G_ExportToIsoWkb(geometry, wkbNDR, wkb) == OGRERR_NONE);
        CHECK_OK(snakegrid_regions_add(regions, id, wkb, (size_t)size));
        free(wkb);
        OGR_F_Destroy(feature);
    }
    GDALClose(dataset);
    return regions;
}

static size_t find_region(const snakegrid_result *result, const char *id) {
    size_t count = 0;
    CHECK_OK(snakegrid_result_count(result, &count));
    for (size_t i = 0; i < count; i++) {
        const char *other = NULL;
        if (snakegrid_result_region_id(result, i, &other) == SNAKEGRID_OK && strcmp(other, id) == 0) return i;
    }
    return count;
}

/* Same regions, same cells, same cell geometry, same metrics. */
static void check_same_layout(const snakegrid_result *a, const snakegrid_result *b) {
    size_t count_a = 0, count_b = 0;
    CHECK_OK(snakegrid_result_count(a, &count_a));
    CHECK_OK(snakegrid_result_count(b, &count_b));
    CHECK(count_a == count_b);
    for (size_t i = 0; i < count_a; i++) {
        const char *id = NULL;
        CHECK_OK(snakegrid_result_region_id(a, i, &id));
        size_t j = find_region(b, id);
        CHECK(j < count_b);
        if (j >= count_b) continue;
        int32_t col_a, row_a, col_b, row_b;
        CHECK_OK(snakegrid_result_cell(a, i, &col_a, &row_a));
        CHECK_OK(snakegrid_result_cell(b, j, &col_b, &row_b));
        CHECK(col_a == col_b && row_a == row_b);
        const uint8_t *wkb_a, *wkb_b;
        size_t len_a, len_b;
        CHECK_OK(snakegrid_result_cell_wkb(a, i, &wkb_a, &len_a));
        CHECK_OK(snakegrid_result_cell_wkb(b, j, &wkb_b, &len_b));
        CHECK(len_a == len_b && memcmp(wkb_a, wkb_b, len_a) == 0);
    }
    snakegrid_layout_metrics metrics_a, metrics_b;
    CHECK_OK(snakegrid_result_layout_metrics(a, &metrics_a));
    CHECK_OK(snakegrid_result_layout_metrics(b, &metrics_b));
    CHECK(memcmp(&metrics_a, &metrics_b, sizeof metrics_a) == 0);
}

int main(int argc, char **argv) {
    if (argc != 3) {
        fprintf(stderr, "usage: %s SOURCE OUTPUT_DIR\n", argv[0]);
        return 2;
    }
    const char *src = argv[1];
    char dst[4096], missing[4096];
    snprintf(dst, sizeof dst, "%s/grid.gpkg", argv[2]);
    snprintf(missing, sizeof missing, "%s/no-such-source.gpkg", argv[2]);
    unlink(dst);
    GDALAllRegister();

    snakegrid_options *options = NULL;
    CHECK_OK(snakegrid_options_new(&options));

    /* Cancelled at the first report: CANCELLED, no result, nothing at the destination. */
    snakegrid_job *job = make_job(src, dst);
    snakegrid_result *from_dataset = NULL;
    int calls = 0;
    CHECK_FAILS(snakegrid_run_job(job, options, cancel_at_once, &calls, &from_dataset), SNAKEGRID_CANCELLED);
    CHECK(calls == 1 && from_dataset == NULL);
    CHECK(access(dst, F_OK) != 0);

    /* The real run. */
    CHECK_OK(snakegrid_run_job(job, options, NULL, NULL, &from_dataset));
    CHECK(from_dataset != NULL);
    CHECK(access(dst, F_OK) == 0);

    /* The destination now exists: refused without overwrite, replaced with it. */
    snakegrid_result *again = NULL;
    CHECK_FAILS(snakegrid_run_job(job, options, NULL, NULL, &again), SNAKEGRID_IO_ERROR);
    CHECK_MESSAGE_HAS("grid.gpkg");
    CHECK(again == NULL);
    CHECK_OK(snakegrid_job_set_overwrite(job, true));
    CHECK_OK(snakegrid_run_job(job, options, NULL, NULL, &again));
    if (from_dataset != NULL && again != NULL) check_same_layout(from_dataset, again);
    snakegrid_result_free(again);

    /* The same regions in memory give the same cells. */
    snakegrid_regions *regions = read_regions(src);
    snakegrid_result *from_memory = NULL;
    CHECK_OK(snakegrid_run(regions, options, NULL, NULL, &from_memory));
    if (from_dataset != NULL && from_memory != NULL) check_same_layout(from_dataset, from_memory);
    snakegrid_result_free(from_memory);
    snakegrid_regions_free(regions);
    snakegrid_result_free(from_dataset);

    /* Formats that would leave nothing at the destination, or lose the cells, are refused. */
    const char *refused[][3] = {{"Memory", "grid.mem", "\"Memory\" does not write files"},
                                {"XLSX", "grid.xlsx", "\"XLSX\" cannot store geometries"}};
    for (size_t k = 0; k < sizeof refused / sizeof refused[0]; k++) {
        char path[4096];
        snprintf(path, sizeof path, "%s/%s", argv[2], refused[k][1]);
        snakegrid_job *format_job = make_job(src, path);
        snakegrid_result *nothing = NULL;
        CHECK_OK(snakegrid_job_set(format_job, "format", refused[k][0]));
        CHECK_FAILS(snakegrid_run_job(format_job, options, NULL, NULL, &nothing), SNAKEGRID_IO_ERROR);
        CHECK_MESSAGE_HAS(refused[k][2]);
        CHECK(nothing == NULL && access(path, F_OK) != 0);
        snakegrid_job_free(format_job);
    }

    /* -lco, -dsco, -s_srs and -update: a second layer in the destination GeoPackage. */
    long grid_size = 0;
    unsigned char *grid_bytes = file_bytes(dst, &grid_size);
    snakegrid_job *more = make_job(src, dst);
    snakegrid_result *added = NULL;
    CHECK_FAILS(snakegrid_job_set(more, "lco", "NOEQUALS"), SNAKEGRID_INVALID_ARGUMENT);
    CHECK_MESSAGE_HAS("lco \"NOEQUALS\": a creation option is written NAME=VALUE");
    CHECK_OK(snakegrid_job_set(more, "lco", "FID=cell_id"));
    CHECK_OK(snakegrid_job_set(more, "lco", "SPATIAL_INDEX=NO"));
    CHECK_OK(snakegrid_job_set(more, "dsco", "VERSION=1.2"));
    CHECK_OK(snakegrid_job_set(more, "s_srs", "EPSG:3857"));
    CHECK_OK(snakegrid_job_set(more, "layer_name", "more"));
    CHECK_FAILS(snakegrid_run_job(more, options, NULL, NULL, &added), SNAKEGRID_IO_ERROR);
    CHECK_MESSAGE_HAS("already exists");
    CHECK(added == NULL && same_bytes(dst, grid_bytes, grid_size));
    CHECK_OK(snakegrid_job_set_update(more, true));
    CHECK_OK(snakegrid_run_job(more, options, NULL, NULL, &added));
    snakegrid_result_free(added);
    added = NULL;
    GDALDatasetH written = GDALOpenEx(dst, GDAL_OF_VECTOR | GDAL_OF_READONLY, NULL, NULL, NULL);
    CHECK(written != NULL);
    if (written != NULL) {
        CHECK(GDALDatasetGetLayerCount(written) == 2);
        OGRLayerH kept = GDALDatasetGetLayerByName(written, "us_states");
        OGRLayerH layer = GDALDatasetGetLayerByName(written, "more");
        CHECK(kept != NULL && OGR_L_GetFeatureCount(kept, 1) == 49);
        CHECK(layer != NULL && strcmp(OGR_L_GetFIDColumn(layer), "cell_id") == 0);
        OGRSpatialReferenceH srs = layer != NULL ? OGR_L_GetSpatialRef(layer) : NULL;
        const char *code = srs != NULL ? OSRGetAuthorityCode(srs, NULL) : NULL;
        CHECK(code != NULL && strcmp(code, "3857") == 0);
        GDALClose(written);
    }
    /* The layer now exists: -update alone refuses it, leaving the file as it was. */
    free(grid_bytes);
    grid_bytes = file_bytes(dst, &grid_size);
    CHECK_FAILS(snakegrid_run_job(more, options, NULL, NULL, &added), SNAKEGRID_IO_ERROR);
    CHECK_MESSAGE_HAS("already has a layer \"more\"");
    CHECK(added == NULL && same_bytes(dst, grid_bytes, grid_size));
    /* With overwrite a cancelled run leaves it as it was too; a full one replaces the layer. */
    CHECK_OK(snakegrid_job_set_overwrite(more, true));
    calls = 0;
    CHECK_FAILS(snakegrid_run_job(more, options, cancel_at_once, &calls, &added), SNAKEGRID_CANCELLED);
    CHECK(added == NULL && same_bytes(dst, grid_bytes, grid_size));
    CHECK_OK(snakegrid_job_set(more, "lco", NULL));
    CHECK_OK(snakegrid_run_job(more, options, NULL, NULL, &added));
    snakegrid_result_free(added);
    written = GDALOpenEx(dst, GDAL_OF_VECTOR | GDAL_OF_READONLY, NULL, NULL, NULL);
    CHECK(written != NULL);
    if (written != NULL) {
        OGRLayerH layer = GDALDatasetGetLayerByName(written, "more");
        CHECK(GDALDatasetGetLayerCount(written) == 2);
        CHECK(layer != NULL && strcmp(OGR_L_GetFIDColumn(layer), "fid") == 0);
        GDALClose(written);
    }
    free(grid_bytes);
    snakegrid_job_free(more);

    /* No setting may write over the source: refused before any work, the source unchanged. */
    snakegrid_result *none = NULL;
    long size_before = 0, size_after = 0;
    unsigned char *before = file_bytes(src, &size_before);
    for (int k = 0; k < 2; k++) {
        CHECK_OK(snakegrid_job_set(job, k == 0 ? "json_report" : "svg", src));
        CHECK_FAILS(snakegrid_run_job(job, options, NULL, NULL, &none), SNAKEGRID_IO_ERROR);
        CHECK_MESSAGE_HAS("refusing to write over the source");
        CHECK_OK(snakegrid_job_set(job, k == 0 ? "json_report" : "svg", NULL));
    }
    unsigned char *after = file_bytes(src, &size_after);
    CHECK(before != NULL && after != NULL && size_before == size_after &&
          memcmp(before, after, (size_t)size_before) == 0);
    free(before);
    free(after);

    /* Dataset errors. */
    CHECK_OK(snakegrid_job_set(job, "src", missing));
    CHECK_FAILS(snakegrid_run_job(job, options, NULL, NULL, &none), SNAKEGRID_IO_ERROR);
    CHECK_MESSAGE_HAS("no-such-source");
    CHECK_OK(snakegrid_job_set(job, "src", src));
    CHECK_OK(snakegrid_job_set(job, "id_field", "no_such_field"));
    CHECK_FAILS(snakegrid_run_job(job, options, NULL, NULL, &none), SNAKEGRID_INVALID_INPUT);
    CHECK_MESSAGE_HAS("no_such_field");
    CHECK_OK(snakegrid_job_set(job, "id_field", NULL));
    CHECK_FAILS(snakegrid_job_set(job, "colour", "red"), SNAKEGRID_INVALID_ARGUMENT);
    CHECK_MESSAGE_HAS("colour");
    CHECK(none == NULL);

    snakegrid_job_free(job);
    snakegrid_options_free(options);
    unlink(dst);
    /* Release GDAL's drivers, so that leak checkers see only what the test itself left. */
    GDALDestroyDriverManager();
    return check_summary("test_dataset");
}
