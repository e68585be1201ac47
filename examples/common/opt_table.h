/*
 * A program's options, declared once as a table: reading the command
 * line, --help, the nearest name offered for a mistyped option and the
 * words that refuse a value all come from it, so that they cannot
 * disagree.  What concerns several options at once (--near below --far,
 * --resume against --overwrite) stays in the program, after opt_parse().
 */
#ifndef NERF_EXAMPLES_OPT_TABLE_H
#define NERF_EXAMPLES_OPT_TABLE_H

#include <stdbool.h>
#include <stdint.h>
#include <stdio.h>

/* The kinds of value an option takes. */
typedef enum opt_kind {
    OPT_FLAG,   /* none: stores .set */
    OPT_INT,    /* a whole number in [.min, .max] */
    OPT_REAL,   /* a finite number from .lo to .hi (.open: ends refused) */
    OPT_TEXT,   /* a path or a word, as given */
    OPT_CHOICE, /* one of .choices' names: stores that one's id */
    OPT_CUSTOM  /* read by .read */
} opt_kind;

/* The C type an option's value is stored as, from its pointer
 * (OPT_STORE()). */
typedef enum opt_type {
    OPT_T_NONE, /* OPT_CUSTOM's own: opt_parse() does not touch it */
    OPT_T_INT,
    OPT_T_U32,
    OPT_T_U64,
    OPT_T_I64,
    OPT_T_DOUBLE,
    OPT_T_FLOAT,
    OPT_T_TEXT
} opt_type;

/* One name an OPT_CHOICE option takes; a list ends with a NULL name. */
typedef struct opt_choice {
    const char *name;
    int id;
    /* NULL, or the choice's own paragraph of --help (the option's head
     * then names it: "--path orbit"); a choice without one, after one
     * with, shares that paragraph ("--layout colmap-text, colmap-binary"). */
    const char *help;
    bool alias; /* taken, but neither listed nor offered */
} opt_choice;

/* Flags of an option (opt.flags). */
#define OPT_REQUIRED 0x1u /* the program does nothing without it */
/* The options so marked: one of them is required ("--data, --path or
 * --poses"). */
#define OPT_ONE_OF 0x2u
/* The value may be left out: the next argument is taken as it only if
 * it starts with a digit ("--jpeg [QUALITY]"). */
#define OPT_VALUE_OPTIONAL 0x4u
/* A bad OPT_CHOICE value is refused as "OPTION needs one of A, B, C, not
 * 'V'", nerf-scene's wording since before the tables. */
#define OPT_SAY_NEEDS_ONE_OF 0x8u

typedef struct opt opt;

/* OPT_CUSTOM's reader: stores value (NULL when missing) through o->to,
 * or says why not (cli_bad_value()) and returns -1. */
typedef int (*opt_reader)(const char *program, const opt *o, const char *value);

struct opt {
    const char *name; /* "--steps"; NULL ends the table */
    opt_kind kind;
    void *to; /* where the value goes, of .type */
    opt_type type;
    uint64_t min, max;         /* OPT_INT's range */
    double lo, hi;             /* OPT_REAL's (-HUGE_VAL, HUGE_VAL: none) */
    unsigned open;             /* CLI_ABOVE_MIN, CLI_BELOW_MAX (options.h) */
    const opt_choice *choices; /* OPT_CHOICE's */
    int set;                   /* what OPT_FLAG stores */
    opt_reader read;           /* OPT_CUSTOM's */
    unsigned flags;            /* OPT_REQUIRED ... */
    int *given, bit;           /* when given: *given |= bit (0: 1) */
    const char *value;         /* the value's name in the help: "N" */
    /* The head of the help's paragraph when not "NAME VALUE" ("--near T
     * --far T"); an option without .help has no paragraph of its own. */
    const char *head;
    /*
     * The help's paragraph: lines separated by '\n', each indented to the
     * program's column.  "{default}" stands for the value the option
     * holds before the command line is read (set by the program, or the
     * library's options_init), "{range}" for OPT_INT's "MIN..MAX" and
     * OPT_REAL's "[LO, HI]" (a parenthesis for an open end).
     */
    const char *help;
};

/* .to and .type of an option, from a pointer to where its value goes: a
 * pointer of another type does not compile. */
#define OPT_STORE(p)                                                           \
    .to = (p), .type = _Generic((p), int *: OPT_T_INT,                         \
                                uint32_t *: OPT_T_U32,                         \
                                uint64_t *: OPT_T_U64,                         \
                                int64_t *: OPT_T_I64,                          \
                                double *: OPT_T_DOUBLE,                        \
                                float *: OPT_T_FLOAT,                          \
                                const char **: OPT_T_TEXT)

/* The kinds, each with its storage and its range or names. */
#define OPT_FLAG_SETS(p, v) .kind = OPT_FLAG, OPT_STORE(p), .set = (v)
#define OPT_INT_IN(p, lo_, hi_)                                                \
    .kind = OPT_INT, OPT_STORE(p), .min = (lo_), .max = (hi_)
#define OPT_REAL_IN(p, lo_, hi_, open_)                                        \
    .kind = OPT_REAL, OPT_STORE(p), .lo = (lo_), .hi = (hi_), .open = (open_)
#define OPT_TEXT_TO(p) .kind = OPT_TEXT, OPT_STORE(p)
#define OPT_CHOICE_OF(p, list)                                                 \
    .kind = OPT_CHOICE, OPT_STORE(p), .choices = (list)
#define OPT_CUSTOM_READ(p, fn)                                                 \
    .kind = OPT_CUSTOM, .to = (p), .type = OPT_T_NONE, .read = (fn)

/* A program: its name as messages give it, its options and the prose of
 * its --help around them. */
typedef struct opt_program {
    const char *name;  /* "nerf-train", "nerf-export mesh" */
    const opt *opts;   /* ended by an entry without a name */
    int column;        /* where the options' help texts start */
    const char *about; /* after the usage line, before the options */
    const char *after; /* after the options: notes, examples */
    /* A word that is no option (nerf-info's MODEL), at most one; NULL:
     * none is taken. */
    const char *operand;
    const char **operand_to;
} opt_program;

/*
 * Reads argv[1..argc-1] into the options' storage, in order, a later
 * option overriding an earlier one; --help or -h prints the help on
 * stdout and exits with status 0, as every program did before the
 * tables.  0: read, and the required options are there; -1: a mistake,
 * said on stderr in one line (an unknown option names the nearest real
 * one, cli_unknown()).
 */
int opt_parse(const opt_program *p, int argc, char **argv);

/* The help text, as --help prints it, with the values the options hold
 * now as their defaults. */
void opt_help(const opt_program *p, FILE *out);

/* The name of choice id in list, or NULL when none has it. */
const char *opt_choice_name(const opt_choice *list, int id);

#endif
