#include "options.h"

#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <string.h>

#include "cli.h"

/* Longer options are not misspelt into each other; beyond this the
 * distance is not worth computing. */
#define NAME_MAX_LEN 64

/* Leading dashes do not count: "-steps" and "steps" mean "--steps". */
static const char *bare(const char *s)
{
    while (*s == '-') {
        s++;
    }
    return s;
}

/* Optimal string alignment distance: insertions, deletions,
 * substitutions and swaps of neighbours each cost one. */
static size_t distance(const char *a, const char *b)
{
    size_t n = strlen(a), m = strlen(b);
    if (n > NAME_MAX_LEN || m > NAME_MAX_LEN) {
        return (size_t)-1;
    }
    size_t d[NAME_MAX_LEN + 1][NAME_MAX_LEN + 1];
    for (size_t i = 0; i <= n; i++) {
        d[i][0] = i;
    }
    for (size_t j = 0; j <= m; j++) {
        d[0][j] = j;
    }
    for (size_t i = 1; i <= n; i++) {
        for (size_t j = 1; j <= m; j++) {
            size_t best = d[i - 1][j - 1] + (a[i - 1] != b[j - 1]);
            if (d[i - 1][j] + 1 < best) {
                best = d[i - 1][j] + 1;
            }
            if (d[i][j - 1] + 1 < best) {
                best = d[i][j - 1] + 1;
            }
            if (i > 1 && j > 1 && a[i - 1] == b[j - 2] &&
                a[i - 2] == b[j - 1] && d[i - 2][j - 2] + 1 < best) {
                best = d[i - 2][j - 2] + 1;
            }
            d[i][j] = best;
        }
    }
    return d[n][m];
}

const char *cli_suggest(const char *arg, const char *const *names)
{
    const char *a = bare(arg);
    size_t len = strlen(a);
    if (len == 0) {
        return NULL;
    }
    /* A short name is one letter from many others: allow one edit there,
     * two in longer names. */
    size_t limit = len <= 4 ? 1 : 2;
    const char *best = NULL;
    size_t best_d = limit + 1;
    for (int k = 0; names[k] != NULL; k++) {
        const char *name = bare(names[k]);
        if (strlen(name) <= 1) {
            continue; /* -h */
        }
        size_t d = distance(a, name);
        /* An abbreviation ("--check" for "--checkpoint-every") is as
         * likely as a one-letter slip. */
        if (len >= 3 && strncmp(a, name, len) == 0 && d > 1) {
            d = 1;
        }
        if (d < best_d) {
            best_d = d;
            best = names[k];
        }
    }
    return best;
}

void cli_unknown(const char *program, const char *arg,
                 const char *const *names)
{
    const char *guess = cli_suggest(arg, names);
    char hint[96] = "";
    if (guess != NULL) {
        snprintf(hint, sizeof hint, " (did you mean %s?)", guess);
    }
    fprintf(stderr, "%s: %s '%s'%s; %s --help lists the options\n", program,
            arg[0] == '-' ? "unknown option" : "unexpected argument", arg,
            hint, program);
}

void cli_usage_error(const char *program, const char *fmt, ...)
{
    char text[1024];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(text, sizeof text, fmt, ap);
    va_end(ap);
    fprintf(stderr, "%s: %s; %s --help lists the options\n", program, text,
            program);
}

void cli_bad_value(const char *program, const char *option, const char *value,
                   const char *expected)
{
    char why[256] = "";
    if (expected != NULL) {
        snprintf(why, sizeof why, ": expected %s", expected);
    }
    if (value == NULL) {
        cli_usage_error(program, "%s needs a value%s", option, why);
    } else {
        cli_usage_error(program, "bad value '%s' for %s%s", value, option,
                        why);
    }
}

int cli_int_option(const char *program, const char *option, const char *value,
                   uint64_t min, uint64_t max, uint64_t *out)
{
    if (value != NULL && cli_uint(value, min, max, out) == 0) {
        return 0;
    }
    char expected[96];
    snprintf(expected, sizeof expected, "an integer from %llu to %llu",
             (unsigned long long)min, (unsigned long long)max);
    cli_bad_value(program, option, value, expected);
    return -1;
}

/* "a number from 0 to 1", "above 0 and at most 1", "of at least 2", ... */
static void word_range(char *buf, size_t size, double min, double max,
                       unsigned flags)
{
    const int low = isfinite(min), high = isfinite(max);
    const char *from = flags & CLI_ABOVE_MIN ? "above" : "of at least";
    const char *to = flags & CLI_BELOW_MAX ? "below" : "at most";
    if (low && high && !(flags & (CLI_ABOVE_MIN | CLI_BELOW_MAX))) {
        snprintf(buf, size, "a number from %g to %g", min, max);
    } else if (low && high) {
        snprintf(buf, size, "a number %s %g and %s %g",
                 flags & CLI_ABOVE_MIN ? "above" : "at least", min, to, max);
    } else if (low) {
        snprintf(buf, size, "a number %s %g", from, min);
    } else if (high) {
        snprintf(buf, size, "a number %s %g", to, max);
    } else {
        snprintf(buf, size, "a finite number");
    }
}

int cli_real_option(const char *program, const char *option,
                    const char *value, double min, double max, unsigned flags,
                    double *out)
{
    double v = 0.0;
    if (value != NULL && cli_double(value, &v) == 0 &&
        (flags & CLI_ABOVE_MIN ? v > min : v >= min) &&
        (flags & CLI_BELOW_MAX ? v < max : v <= max)) {
        *out = v;
        return 0;
    }
    char expected[128];
    word_range(expected, sizeof expected, min, max, flags);
    cli_bad_value(program, option, value, expected);
    return -1;
}
