/* Little-endian WKB written by hand, so that the C tests depend on nothing but the header. */
#ifndef SNAKEGRID_TESTS_WKB_H
#define SNAKEGRID_TESTS_WKB_H

#include <stddef.h>
#include <stdint.h>
#include <string.h>

typedef struct {
    uint8_t bytes[1024];
    size_t len;
} wkb_buffer;

static inline void wkb_u32(wkb_buffer *b, uint32_t v) {
    for (int i = 0; i < 4; i++) b->bytes[b->len++] = (uint8_t)(v >> (8 * i));
}

static inline void wkb_f64(wkb_buffer *b, double v) {
    uint64_t bits;
    memcpy(&bits, &v, sizeof bits);
    for (int i = 0; i < 8; i++) b->bytes[b->len++] = (uint8_t)(bits >> (8 * i));
}

/* A geometry header: byte order (little endian) and type (3 Polygon, 1 Point, ...). */
static inline void wkb_header(wkb_buffer *b, uint32_t type) {
    b->bytes[b->len++] = 1;
    wkb_u32(b, type);
}

/* A Polygon of one ring of `n` points, taken as given (not closed, not checked). */
static inline wkb_buffer wkb_polygon(size_t n, const double (*xy)[2]) {
    wkb_buffer b = {{0}, 0};
    wkb_header(&b, 3);
    wkb_u32(&b, 1);
    wkb_u32(&b, (uint32_t)n);
    for (size_t i = 0; i < n; i++) {
        wkb_f64(&b, xy[i][0]);
        wkb_f64(&b, xy[i][1]);
    }
    return b;
}

/* An axis-aligned square, closed, counter-clockwise. */
static inline wkb_buffer wkb_square(double x, double y, double side) {
    const double ring[5][2] = {{x, y}, {x + side, y}, {x + side, y + side}, {x, y + side}, {x, y}};
    return wkb_polygon(5, ring);
}

#endif
