/*
 * The option tables of examples/common/opt_table.h: each kind of value
 * lands in its storage, whatever its C type; the given marks are set;
 * and the help written from a table quotes each option's range and
 * default from the table itself, with the programs' layout.  The
 * messages of mistakes are checked on the programs themselves
 * (test-cli-errors.sh, tests/bad-inputs).
 */
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "../tests/harness.h"
#include "common/opt_table.h"
#include "common/options.h"

enum { SHAPE_CUBE = 3, SHAPE_BALL = 5 };

static const opt_choice shapes[] = {
    {.name = "cube", .id = SHAPE_CUBE, .help = "six faces"},
    {.name = "box", .id = SHAPE_CUBE, .alias = true},
    {.name = "ball", .id = SHAPE_BALL, .help = "none"},
    {.name = NULL},
};

typedef struct args {
    const char *in;
    uint64_t n;
    uint32_t side;
    int64_t steps;
    float scale;
    double rate;
    int shape, quiet, given;
} args;

/* A table of every kind, as a program declares one. */
static void table(args *a, opt *opts)
{
    const opt t[] = {
        {.name = "--in", OPT_TEXT_TO(&a->in), .flags = OPT_REQUIRED,
         .value = "FILE", .help = "the input (required)"},
        {.name = "--n", OPT_INT_IN(&a->n, 1, 9), .given = &a->given,
         .bit = 1, .value = "N", .help = "count, {range} (default {default})"},
        {.name = "--side", OPT_INT_IN(&a->side, 2, 4096), .given = &a->given,
         .bit = 2, .value = "S", .help = "a side\nof {range}"},
        {.name = "--steps", OPT_INT_IN(&a->steps, 1, 65536), .value = "K"},
        {.name = "--scale", OPT_REAL_IN(&a->scale, 0.0, 1.0, CLI_ABOVE_MIN),
         .value = "X", .help = "in {range} (default {default})"},
        {.name = "--rate", OPT_REAL_IN(&a->rate, -1.0, 1.0, 0),
         .value = "R"},
        {.name = "--shape", OPT_CHOICE_OF(&a->shape, shapes),
         .help = "the shape (default {default})"},
        {.name = "--quiet", OPT_FLAG_SETS(&a->quiet, 7),
         .help = "say nothing"},
        {.name = NULL},
    };
    memcpy(opts, t, sizeof t);
}

static opt_program program(const opt *opts)
{
    const opt_program p = {.name = "prog", .opts = opts, .column = 12,
                           .about = "About.\n", .after = "After.\n"};
    return p;
}

static int parse(args *a, int argc, const char *const *words)
{
    opt opts[9];
    table(a, opts);
    const opt_program p = program(opts);
    char *argv[16];
    argv[0] = "prog";
    for (int i = 0; i < argc; i++) {
        argv[i + 1] = (char *)words[i];
    }
    return opt_parse(&p, argc + 1, argv);
}

TEST(each_kind_lands_in_its_storage)
{
    args a;
    memset(&a, 0, sizeof a);
    const char *w[] = {"--in", "x.nerf", "--n", "9", "--side", "4096",
                       "--steps", "65536", "--scale", "0.5", "--rate",
                       "-1", "--shape", "box", "--quiet"};
    CHECK_EQ_INT(parse(&a, 15, w), 0);
    CHECK(a.in != NULL && strcmp(a.in, "x.nerf") == 0);
    CHECK_EQ_INT(a.n, 9);
    CHECK_EQ_INT(a.side, 4096);
    CHECK_EQ_INT(a.steps, 65536);
    CHECK_NEAR(a.scale, 0.5, 0.0);
    CHECK_NEAR(a.rate, -1.0, 0.0);
    CHECK_EQ_INT(a.shape, SHAPE_CUBE); /* "box", the alias */
    CHECK_EQ_INT(a.quiet, 7);
    CHECK_EQ_INT(a.given, 3);
}

TEST(mistakes_are_refused)
{
    const char *const cases[][3] = {
        {"--in", "x", "--n"},       /* no value */
        {"--in", "x", "--nn"},      /* no such option */
        {"--in", "x", "word"},      /* no operand */
        {"--n", "1", "--quiet"},    /* --in required */
    };
    for (size_t k = 0; k < sizeof cases / sizeof cases[0]; k++) {
        args a;
        memset(&a, 0, sizeof a);
        CHECK_EQ_INT(parse(&a, 3, cases[k]), -1);
    }
    const char *const values[][2] = {
        {"--n", "0"},        {"--n", "10"},      {"--scale", "0"},
        {"--scale", "1.5"},  {"--rate", "nan"}, {"--shape", "cone"},
        {"--side", "-2"},    {"--steps", "2x"},
    };
    for (size_t k = 0; k < sizeof values / sizeof values[0]; k++) {
        args a;
        memset(&a, 0, sizeof a);
        const char *w[] = {"--in", "x", values[k][0], values[k][1]};
        CHECK_EQ_INT(parse(&a, 4, w), -1);
    }
}

/* opt_help()'s text, as a string (NULL on failure). */
static char *help_of(args *a)
{
    opt opts[9];
    table(a, opts);
    const opt_program p = program(opts);
    FILE *f = tmpfile();
    if (f == NULL) {
        return NULL;
    }
    opt_help(&p, f);
    long n = ftell(f);
    char *text = n >= 0 ? calloc((size_t)n + 1, 1) : NULL;
    rewind(f);
    if (text != NULL && fread(text, 1, (size_t)n, f) != (size_t)n) {
        free(text);
        text = NULL;
    }
    fclose(f);
    return text;
}

TEST(help_quotes_the_table)
{
    args a;
    memset(&a, 0, sizeof a);
    a.n = 4;
    a.scale = 0.25f;
    a.shape = SHAPE_BALL;
    char *h = help_of(&a);
    CHECK(h != NULL);
    if (h == NULL) {
        return;
    }
    static const char *const lines[] = {
        "usage: prog --in FILE [--n N] [--side S] [--steps K] [--scale X] "
        "[--rate R]\n"
        "            [--shape cube|ball] [--quiet]\n"
        "About.\n",
        "  --in FILE  the input (required)\n",
        "  --n N     count, 1..9 (default 4)\n",
        "  --side S  a side\n            of 2..4096\n",
        "  --scale X  in (0, 1] (default 0.25)\n",
        "  --shape cube|ball  the shape (default ball)\n",
        "  --shape cube  six faces\n",
        "  --shape ball  none\n",
        "  --quiet   say nothing\n",
        "  --help    print this help and exit\nAfter.\n",
    };
    for (size_t k = 0; k < sizeof lines / sizeof lines[0]; k++) {
        if (strstr(h, lines[k]) == NULL) {
            FAILF("no '%s' in:\n%s", lines[k], h);
        }
    }
    /* An option without help has no paragraph; an alias is not listed. */
    CHECK(strstr(h, "  --steps") == NULL && strstr(h, "  --rate") == NULL);
    CHECK(strstr(h, "box") == NULL);
    free(h);
}

int main(void)
{
    RUN(each_kind_lands_in_its_storage);
    RUN(mistakes_are_refused);
    RUN(help_quotes_the_table);
    HARNESS_EXIT();
}
