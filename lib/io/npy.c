#include "npy.h"

#include <stdio.h>
#include <string.h>

#include "byteorder.h"
#include "error.h"

#define MAGIC "\x93NUMPY"
#define MAGIC_LEN 6

enum { KEY_DESCR = 1, KEY_FORTRAN = 2, KEY_SHAPE = 4 };

/* A position in the header text, for error messages and parsing. */
typedef struct cursor {
    const char *start, *p, *end;
} cursor;

static int syntax_error(const cursor *c, const char *expected)
{
    return nerf__error(NERF_EFORMAT, "npy header: expected %s at byte %zu",
                       expected, (size_t)(c->p - c->start));
}

static void skip_spaces(cursor *c)
{
    while (c->p < c->end && *c->p == ' ') {
        c->p++;
    }
}

static bool accept(cursor *c, char ch)
{
    skip_spaces(c);
    if (c->p < c->end && *c->p == ch) {
        c->p++;
        return true;
    }
    return false;
}

static bool accept_word(cursor *c, const char *word)
{
    size_t n = strlen(word);
    skip_spaces(c);
    if ((size_t)(c->end - c->p) >= n && memcmp(c->p, word, n) == 0) {
        c->p += n;
        return true;
    }
    return false;
}

/* A Python string literal without escapes, of printable ASCII. */
static int parse_string(cursor *c, char *buf, size_t size)
{
    skip_spaces(c);
    if (c->p >= c->end || (*c->p != '\'' && *c->p != '"')) {
        return syntax_error(c, "a quoted string");
    }
    char quote = *c->p++;
    size_t n = 0;
    while (c->p < c->end && *c->p != quote) {
        if (*c->p < 0x20 || *c->p > 0x7e || *c->p == '\\' || n + 1 >= size) {
            return syntax_error(c, "a short plain string");
        }
        buf[n++] = *c->p++;
    }
    if (c->p >= c->end) {
        return syntax_error(c, "a closing quote");
    }
    c->p++;
    buf[n] = '\0';
    return NERF_OK;
}

/* A non-negative decimal; Python 2 wrote longs with an 'L' suffix. */
static int parse_size(cursor *c, size_t *out)
{
    skip_spaces(c);
    if (c->p >= c->end || *c->p < '0' || *c->p > '9') {
        return syntax_error(c, "a dimension");
    }
    size_t v = 0;
    while (c->p < c->end && *c->p >= '0' && *c->p <= '9') {
        size_t digit = (size_t)(*c->p++ - '0');
        if (v > (SIZE_MAX - digit) / 10) {
            return nerf__error(NERF_EFORMAT, "npy header: dimension too large");
        }
        v = v * 10 + digit;
    }
    if (c->p < c->end && *c->p == 'L') {
        c->p++;
    }
    *out = v;
    return NERF_OK;
}

static int parse_descr(cursor *c, nerf__npy *a)
{
    skip_spaces(c);
    if (c->p < c->end && *c->p == '[') {
        return nerf__error(NERF_EFORMAT, "npy header: structured dtypes are "
                           "not supported");
    }
    char d[16];
    int rc = parse_string(c, d, sizeof d);
    if (rc != NERF_OK) {
        return rc;
    }
    if (strcmp(d, "<f4") == 0) {
        a->dtype = NERF__NPY_F4;
        a->elem_size = 4;
    } else if (strcmp(d, "<f8") == 0) {
        a->dtype = NERF__NPY_F8;
        a->elem_size = 8;
    } else {
        return nerf__error(NERF_EFORMAT, "npy: %sdtype '%s' is not supported "
                           "(expected '<f4' or '<f8')",
                           d[0] == '>' ? "big-endian " : "", d);
    }
    return NERF_OK;
}

static int parse_fortran(cursor *c, nerf__npy *a)
{
    if (accept_word(c, "True")) {
        a->fortran_order = true;
    } else if (accept_word(c, "False")) {
        a->fortran_order = false;
    } else {
        return syntax_error(c, "True or False");
    }
    return NERF_OK;
}

/* A tuple: "()", "(n,)", "(n, m)" or "(n, m,)"; (n) is an int, not a shape. */
static int parse_shape(cursor *c, nerf__npy *a)
{
    if (!accept(c, '(')) {
        return syntax_error(c, "a shape tuple");
    }
    a->ndim = 0;
    if (accept(c, ')')) {
        return NERF_OK;
    }
    for (;;) {
        if (a->ndim == NERF__NPY_MAX_DIMS) {
            return nerf__error(NERF_EFORMAT, "npy header: more than %d "
                               "dimensions", NERF__NPY_MAX_DIMS);
        }
        int rc = parse_size(c, &a->shape[a->ndim++]);
        if (rc != NERF_OK) {
            return rc;
        }
        if (accept(c, ',')) {
            if (accept(c, ')')) {
                return NERF_OK;
            }
        } else if (a->ndim > 1 && accept(c, ')')) {
            return NERF_OK;
        } else {
            return syntax_error(c, a->ndim == 1 ? "',' (a one-element shape "
                                "is written (n,))" : "',' or ')'");
        }
    }
}

static int parse_entry(cursor *c, nerf__npy *a, unsigned *seen)
{
    char key[16];
    int rc = parse_string(c, key, sizeof key);
    if (rc == NERF_OK && !accept(c, ':')) {
        rc = syntax_error(c, "':'");
    }
    if (rc != NERF_OK) {
        return rc;
    }
    unsigned bit = strcmp(key, "descr") == 0           ? KEY_DESCR
                   : strcmp(key, "fortran_order") == 0 ? KEY_FORTRAN
                   : strcmp(key, "shape") == 0         ? KEY_SHAPE
                                                       : 0;
    if (bit == 0 || (*seen & bit)) {
        return nerf__error(NERF_EFORMAT, "npy header: %s key '%s'",
                           bit ? "duplicate" : "unexpected", key);
    }
    *seen |= bit;
    if (bit == KEY_DESCR) {
        return parse_descr(c, a);
    }
    return bit == KEY_FORTRAN ? parse_fortran(c, a) : parse_shape(c, a);
}

static int parse_dict(const char *text, size_t len, nerf__npy *a)
{
    cursor c = {text, text, text + len};
    if (!accept(&c, '{')) {
        return syntax_error(&c, "'{'");
    }
    unsigned seen = 0;
    while (!accept(&c, '}')) {
        int rc = parse_entry(&c, a, &seen);
        if (rc != NERF_OK) {
            return rc;
        }
        if (!accept(&c, ',')) {
            if (!accept(&c, '}')) {
                return syntax_error(&c, "',' or '}'");
            }
            break;
        }
    }
    const char *missing = !(seen & KEY_DESCR)     ? "descr"
                          : !(seen & KEY_FORTRAN) ? "fortran_order"
                          : !(seen & KEY_SHAPE)   ? "shape"
                                                  : NULL;
    if (missing) {
        return nerf__error(NERF_EFORMAT, "npy header: missing key '%s'",
                           missing);
    }
    skip_spaces(&c);
    if (c.p != c.end - 1 || *c.p != '\n') {
        return syntax_error(&c, "the header to end with spaces and a newline");
    }
    return NERF_OK;
}

/* Split buf into header text and data; returns the header's bounds. */
static int parse_preamble(const unsigned char *b, size_t size,
                          size_t *text_at, size_t *text_len)
{
    if (size < MAGIC_LEN + 2 || memcmp(b, MAGIC, MAGIC_LEN) != 0) {
        return nerf__error(NERF_EFORMAT, "not a .npy array (bad magic)");
    }
    unsigned major = b[6], minor = b[7];
    if ((major != 1 && major != 2) || minor != 0) {
        return nerf__error(NERF_EFORMAT, "npy format version %u.%u is not "
                           "supported (1.0 and 2.0 are)", major, minor);
    }
    size_t prefix = major == 1 ? 10 : 12;
    if (size < prefix) {
        return nerf__error(NERF_EFORMAT, "npy: truncated header");
    }
    size_t len = major == 1 ? nerf__load_le16(b + 8) : nerf__load_le32(b + 8);
    if (len > size - prefix) {
        return nerf__error(NERF_EFORMAT, "npy: header of %zu bytes is "
                           "truncated (%zu available)", len, size - prefix);
    }
    *text_at = prefix;
    *text_len = len;
    return NERF_OK;
}

static int locate_data(const unsigned char *b, size_t size, size_t at,
                       nerf__npy *a)
{
    size_t count = 1;
    for (uint32_t i = 0; i < a->ndim; i++) {
        if (a->shape[i] != 0 && count > SIZE_MAX / a->shape[i]) {
            return nerf__error(NERF_EFORMAT, "npy: shape is too large");
        }
        count *= a->shape[i];
    }
    if (count > SIZE_MAX / a->elem_size) {
        return nerf__error(NERF_EFORMAT, "npy: shape is too large");
    }
    a->count = count;
    a->data_size = count * a->elem_size;
    a->data = b + at;
    size_t have = size - at;
    if (have != a->data_size) {
        char s[96];
        nerf__npy_format_shape(a->shape, a->ndim, s, sizeof s);
        return nerf__error(NERF_EFORMAT, "npy: %s: shape %s of %s needs %zu "
                           "data bytes but %zu follow the header",
                           have < a->data_size ? "truncated" : "trailing bytes",
                           s, nerf__npy_dtype_name(a->dtype), a->data_size,
                           have);
    }
    return NERF_OK;
}

int nerf__npy_parse(const void *buf, size_t size, nerf__npy *out)
{
    const unsigned char *b = buf;
    memset(out, 0, sizeof *out);
    size_t at = 0, len = 0;
    int rc = parse_preamble(b, size, &at, &len);
    if (rc == NERF_OK) {
        rc = parse_dict((const char *)b + at, len, out);
    }
    if (rc == NERF_OK) {
        rc = locate_data(b, size, at + len, out);
    }
    if (rc != NERF_OK) {
        memset(out, 0, sizeof *out);
    }
    return rc;
}

void nerf__npy_to_float(const nerf__npy *a, float *dst, size_t n)
{
    for (size_t i = 0; i < n && i < a->count; i++) {
        const unsigned char *p = a->data + i * a->elem_size;
        dst[i] = a->dtype == NERF__NPY_F4 ? nerf__load_lef32(p)
                                          : (float)nerf__load_lef64(p);
    }
}

void nerf__npy_to_double(const nerf__npy *a, double *dst, size_t n)
{
    for (size_t i = 0; i < n && i < a->count; i++) {
        const unsigned char *p = a->data + i * a->elem_size;
        dst[i] = a->dtype == NERF__NPY_F4 ? (double)nerf__load_lef32(p)
                                          : nerf__load_lef64(p);
    }
}

const char *nerf__npy_dtype_name(nerf__npy_dtype dtype)
{
    return dtype == NERF__NPY_F4 ? "<f4" : dtype == NERF__NPY_F8 ? "<f8" : "?";
}

void nerf__npy_format_shape(const size_t *shape, uint32_t ndim, char *buf,
                            size_t size)
{
    /* 20 digits and a separator per dimension fit easily. */
    char text[32 * NERF__NPY_MAX_DIMS + 8] = "(";
    size_t at = 1;
    for (uint32_t i = 0; i < ndim && i < NERF__NPY_MAX_DIMS; i++) {
        at += (size_t)snprintf(text + at, sizeof text - at,
                               i ? ", %zu" : "%zu", shape[i]);
    }
    snprintf(text + at, sizeof text - at, ndim == 1 ? ",)" : ")");
    snprintf(buf, size, "%s", text);
}
