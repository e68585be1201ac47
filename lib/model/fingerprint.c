#include "fingerprint.h"

#include <math.h>
#include <stdio.h>
#include <string.h>

#include "byteorder.h"

/* A mean colour differs when a channel moves by more than this: the same
 * images give the same mean exactly, and another downscale of them moves
 * it by box-filter rounding only, far below it. */
#define COLOUR_TOLERANCE 0.02f

void nerf__fingerprint_store(unsigned char *p, const nerf__fingerprint *f)
{
    const uint32_t u[7] = {f->count, f->width, f->height, f->src_width,
                           f->src_height, f->kind, f->flags};
    for (int i = 0; i < 7; i++) {
        nerf__store_le32(p + 4 * i, u[i]);
    }
    const float x[5] = {f->mean_rgb[0], f->mean_rgb[1], f->mean_rgb[2],
                        f->near_bound, f->far_bound};
    for (int i = 0; i < 5; i++) {
        nerf__store_lef32(p + 28 + 4 * i, x[i]);
    }
}

bool nerf__fingerprint_parse(const unsigned char *p, uint64_t len,
                             nerf__fingerprint *f)
{
    memset(f, 0, sizeof *f);
    if (len < NERF__FINGERPRINT_SIZE) {
        return false;
    }
    uint32_t *u[7] = {&f->count, &f->width, &f->height, &f->src_width,
                      &f->src_height, &f->kind, &f->flags};
    for (int i = 0; i < 7; i++) {
        *u[i] = nerf__load_le32(p + 4 * i);
    }
    float *x[5] = {&f->mean_rgb[0], &f->mean_rgb[1], &f->mean_rgb[2],
                   &f->near_bound, &f->far_bound};
    for (int i = 0; i < 5; i++) {
        *x[i] = nerf__load_lef32(p + 28 + 4 * i);
        if (!isfinite(*x[i])) {
            return false;
        }
    }
    f->known = true;
    return true;
}

static void add(char *what, size_t size, int *n, const char *aspect)
{
    size_t used = strlen(what);
    snprintf(what + used, size - used, "%s%s", *n ? ", " : "", aspect);
    (*n)++;
}

static bool bounds_differ(float a, float b)
{
    return fabsf(a - b) > 1e-4f * fmaxf(1.0f, fmaxf(fabsf(a), fabsf(b)));
}

int nerf__fingerprint_compare(const nerf__fingerprint *a,
                              const nerf__fingerprint *b, char *what,
                              size_t what_size)
{
    int n = 0;
    what[0] = '\0';
    if (a->count != b->count) {
        add(what, what_size, &n, "image count");
    }
    if (a->width != b->width || a->height != b->height) {
        add(what, what_size, &n, "image size");
    } else if (a->src_width != b->src_width ||
               a->src_height != b->src_height) {
        /* Other files brought to one size by another downscale. */
        add(what, what_size, &n, "size of the image files");
    }
    if (a->kind != b->kind) {
        add(what, what_size, &n, "scene kind");
    }
    if ((a->flags ^ b->flags) & NERF__FINGERPRINT_NDC) {
        add(what, what_size, &n, "NDC");
    }
    for (int c = 0; c < 3; c++) {
        if (fabsf(a->mean_rgb[c] - b->mean_rgb[c]) > COLOUR_TOLERANCE) {
            add(what, what_size, &n, "mean colour");
            break;
        }
    }
    if (bounds_differ(a->near_bound, b->near_bound) ||
        bounds_differ(a->far_bound, b->far_bound)) {
        add(what, what_size, &n, "near/far bounds");
    }
    return n;
}

static const char *kind_name(uint32_t kind)
{
    return kind == NERF__FINGERPRINT_BLENDER ? "blender"
           : kind == NERF__FINGERPRINT_LLFF  ? "llff"
           : kind == NERF__FINGERPRINT_COLMAP ? "colmap"
                                              : "unknown kind";
}

void nerf__fingerprint_describe(const nerf__fingerprint *f, int with_word,
                                char *out, size_t out_size)
{
    char files[64] = "";
    if (f->src_width != f->width || f->src_height != f->height) {
        snprintf(files, sizeof files, " from %ux%u files", f->src_width,
                 f->src_height);
    }
    snprintf(out, out_size, "%u%s of %ux%u%s (%s%s, mean colour %.2f %.2f "
             "%.2f, near %g far %g)", f->count, with_word ? " images" : "",
             f->width, f->height, files, kind_name(f->kind),
             (f->flags & NERF__FINGERPRINT_NDC) ? ", NDC" : "",
             (double)f->mean_rgb[0], (double)f->mean_rgb[1],
             (double)f->mean_rgb[2], (double)f->near_bound,
             (double)f->far_bound);
}
