/* A minimal test harness for the C tests: CHECK records a pass or a failure (with the library's
 * last error message, which is what a user would see) and check_summary() prints the plain
 * "N passed, N failed" line that CI reads and returns the exit code. */
#ifndef SNAKEGRID_TESTS_CHECK_H
#define SNAKEGRID_TESTS_CHECK_H

#include <stdio.h>
#include <string.h>

#include "snakegrid.h"

static int checks_passed = 0;
static int checks_failed = 0;

#define CHECK(condition)                                                                      \
    do {                                                                                      \
        if (condition) {                                                                      \
            checks_passed++;                                                                  \
        } else {                                                                              \
            checks_failed++;                                                                  \
            fprintf(stderr, "%s:%d: check failed: %s (last error: \"%s\")\n", __FILE__,       \
                    __LINE__, #condition, snakegrid_last_error_message());                    \
        }                                                                                     \
    } while (0)

/* A call that must succeed. */
#define CHECK_OK(call) CHECK((call) == SNAKEGRID_OK)

/* A call that must fail with `status`, leaving a message that names `function`. */
#define CHECK_FAILS(call, status)                                                             \
    do {                                                                                      \
        snakegrid_status got_ = (call);                                                       \
        CHECK(got_ == (status));                                                              \
        CHECK(strstr(snakegrid_last_error_message(), check_function_name(#call)) != NULL);     \
    } while (0)

/* The function name at the start of a call's text, e.g. "snakegrid_run" in "snakegrid_run(a)". */
static inline const char *check_function_name(const char *call) {
    static char name[128];
    size_t n = strcspn(call, "(");
    if (n >= sizeof name) n = sizeof name - 1;
    memcpy(name, call, n);
    name[n] = '\0';
    return name;
}

/* A message that must contain `part`. */
#define CHECK_MESSAGE_HAS(part) CHECK(strstr(snakegrid_last_error_message(), (part)) != NULL)

static inline int check_summary(const char *program) {
    printf("%s: %d passed, %d failed\n", program, checks_passed, checks_failed);
    return checks_failed == 0 ? 0 : 1;
}

#endif
