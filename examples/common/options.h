/*
 * One-line command-line errors shared by the example programs: an unknown
 * option names the nearest known one, and every mistake points to --help
 * instead of printing all of it.
 */
#ifndef NERF_EXAMPLES_OPTIONS_H
#define NERF_EXAMPLES_OPTIONS_H

#include <stdint.h>

/*
 * The option of names (a NULL-terminated list, each "--name") that arg
 * most likely misspells, by edit distance (a swap of two neighbouring
 * letters counts as one edit) or as an abbreviation; NULL when none is
 * near enough to suggest.
 */
const char *cli_suggest(const char *arg, const char *const *names);

/*
 * Prints, as one line on stderr, "PROGRAM: unknown option 'ARG' (did you
 * mean --X?); PROGRAM --help lists the options" (or "unexpected argument"
 * for a word that is not an option), the suggestion the nearest of names.
 */
void cli_unknown(const char *program, const char *arg,
                 const char *const *names);

/* "PROGRAM: MESSAGE; PROGRAM --help lists the options", one line on
 * stderr; MESSAGE is a printf format without a newline. */
void cli_usage_error(const char *program, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 2, 3)))
#endif
    ;

/* "PROGRAM: bad value 'VALUE' for OPTION: expected EXPECTED; PROGRAM
 * --help ...", or "PROGRAM: OPTION needs a value: expected EXPECTED" when
 * value is NULL; expected may be NULL. */
void cli_bad_value(const char *program, const char *option, const char *value,
                   const char *expected);

/*
 * A numeric option's value: the range given here both checks it and
 * words the message that refuses it, so that the two cannot disagree.
 * 0 with *out set; else -1 after cli_bad_value() has said "expected an
 * integer from MIN to MAX" (or "a number ...").  A NULL value is one
 * missing ("OPTION needs a value").
 */
int cli_int_option(const char *program, const char *option, const char *value,
                   uint64_t min, uint64_t max, uint64_t *out);

/* Flags of cli_real_option(): the range's ends themselves refused. */
#define CLI_ABOVE_MIN 0x1u
#define CLI_BELOW_MAX 0x2u

/* As cli_int_option() for a finite number in [min, max] (either end open
 * by the flags; -HUGE_VAL or HUGE_VAL: no bound on that side). */
int cli_real_option(const char *program, const char *option,
                    const char *value, double min, double max, unsigned flags,
                    double *out);

#endif
