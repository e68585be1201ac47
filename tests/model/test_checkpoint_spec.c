/*
 * The checkpoint's sections as docs/formats.md specifies them and as
 * lib/model/checkpoint_sections.c writes and reads them: the same tags in
 * the same order, the same names, and a fixed body length where the
 * specification gives a number.  A section added to the code without the
 * specification, or the other way round, fails here.
 *
 * Usage: test_checkpoint_spec docs/formats.md
 */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "../harness.h"

#include "checkpoint_sections.h"

#define N NERF__CKPT_N_SECTIONS
#define MAX_ROWS 64

static const char *spec_path;

typedef struct spec_row {
    unsigned long tag;
    char name[96];
    char length[64];
} spec_row;

/* The i-th '|'-separated cell of line (0 is before the first bar), with
 * its spaces and backquotes trimmed, into out. */
static void cell(const char *line, int i, char *out, size_t size)
{
    const char *p = line;
    for (int k = 0; k < i && p != NULL; k++) {
        p = strchr(p, '|');
        p = p ? p + 1 : NULL;
    }
    out[0] = '\0';
    if (p == NULL) {
        return;
    }
    while (*p == ' ' || *p == '`') {
        p++;
    }
    const char *end = strchr(p, '|');
    size_t n = end ? (size_t)(end - p) : strlen(p);
    while (n > 0 && (p[n - 1] == ' ' || p[n - 1] == '`' ||
                     p[n - 1] == '\n')) {
        n--;
    }
    n = n < size - 1 ? n : size - 1;
    memcpy(out, p, n);
    out[n] = '\0';
}

/* The rows of the table that follows "A writer emits them in this order". */
static int read_spec(spec_row *rows)
{
    FILE *f = fopen(spec_path, "r");
    if (f == NULL) {
        FAILF("%s: cannot open", spec_path);
        return 0;
    }
    char line[1024];
    int n = 0;
    bool in_table = false, seen = false;
    while (fgets(line, sizeof line, f) != NULL) {
        if (strstr(line, "A writer emits them in this order") != NULL) {
            seen = true;
            continue;
        }
        if (!seen) {
            continue;
        }
        if (strncmp(line, "| `0x", 5) == 0 && n < MAX_ROWS) {
            char tag[32];
            cell(line, 1, tag, sizeof tag);
            rows[n].tag = strtoul(tag, NULL, 16);
            cell(line, 2, rows[n].name, sizeof rows[n].name);
            cell(line, 3, rows[n].length, sizeof rows[n].length);
            n++;
            in_table = true;
        } else if (in_table && line[0] != '|') {
            break;
        }
    }
    fclose(f);
    if (!seen) {
        FAILF("%s: no \"A writer emits them in this order\" table",
              spec_path);
    }
    return n;
}

TEST(same_sections_in_the_same_order)
{
    spec_row rows[MAX_ROWS];
    const int n = read_spec(rows);
    CHECK_EQ_INT(n, N);
    for (int i = 0; i < N && i < n; i++) {
        const nerf__ckpt_section *k = &nerf__ckpt_sections[i];
        if (rows[i].tag != k->tag) {
            FAILF("section %d: the specification has tag 0x%08lx, the code "
                  "0x%08lx (%s)", i, rows[i].tag, (unsigned long)k->tag,
                  k->name);
        }
        /* The specification may add a gloss: "Adam first moments (m)". */
        if (strncmp(rows[i].name, k->name, strlen(k->name)) != 0) {
            FAILF("section 0x%08lx: named \"%s\" in the specification, "
                  "\"%s\" in the code", rows[i].tag, rows[i].name, k->name);
        }
        char *end = NULL;
        const unsigned long len = strtoul(rows[i].length, &end, 10);
        const bool fixed = end != rows[i].length && *end == '\0';
        if (fixed != ((k->flags & NERF__CKPT_FIXED) != 0) ||
            (fixed && len != k->size)) {
            FAILF("section %s: body length \"%s\" in the specification, "
                  "%s %lu in the code", k->name, rows[i].length,
                  (k->flags & NERF__CKPT_FIXED) ? "fixed at" : "not fixed,",
                  (unsigned long)k->size);
        }
    }
}

/* A table that reads no writer's sections would let the test above pass
 * on nothing; each entry must be whole. */
TEST(every_section_can_be_written_and_read)
{
    for (int i = 0; i < N; i++) {
        const nerf__ckpt_section *k = &nerf__ckpt_sections[i];
        CHECK(k->name != NULL && k->write != NULL);
        CHECK((k->read != NULL) != (k->read_options != NULL));
        for (int j = 0; j < i; j++) {
            CHECK(nerf__ckpt_sections[j].tag != k->tag);
        }
    }
    /* The options come first, so that reading starts from them. */
    CHECK(nerf__ckpt_sections[0].read_options != NULL &&
          (nerf__ckpt_sections[0].flags & NERF__CKPT_CORE));
}

int main(int argc, char **argv)
{
    if (argc != 2) {
        fprintf(stderr, "usage: %s docs/formats.md\n", argv[0]);
        return 2;
    }
    spec_path = argv[1];
    RUN(same_sections_in_the_same_order);
    RUN(every_section_can_be_written_and_read);
    HARNESS_EXIT();
}
