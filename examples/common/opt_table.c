#include "opt_table.h"

#include <assert.h>
#include <stdlib.h>
#include <string.h>

#include "options.h"

/* The most options a program has: each has about twenty. */
#define OPT_MAX 64

static size_t opt_count(const opt *opts)
{
    size_t n = 0;
    while (opts[n].name != NULL) {
        n++;
    }
    if (n > OPT_MAX) {
        /* A program's own mistake, found by its first run. */
        fprintf(stderr, "opt_table: %zu options, more than %d\n", n, OPT_MAX);
        abort();
    }
    return n;
}

static size_t type_size(opt_type t)
{
    switch (t) {
    case OPT_T_INT: return sizeof(int);
    case OPT_T_U32: return sizeof(uint32_t);
    case OPT_T_U64: return sizeof(uint64_t);
    case OPT_T_I64: return sizeof(int64_t);
    case OPT_T_DOUBLE: return sizeof(double);
    case OPT_T_FLOAT: return sizeof(float);
    case OPT_T_TEXT: return sizeof(const char *);
    default: return 0;
    }
}

/* A whole number into o's storage: OPT_INT's value within its range, or
 * an id or a flag's value, which may be negative (two's complement). */
static void put_int(const opt *o, uint64_t v)
{
    switch (o->type) {
    case OPT_T_INT: *(int *)o->to = (int)(int64_t)v; break;
    case OPT_T_U32: *(uint32_t *)o->to = (uint32_t)v; break;
    case OPT_T_U64: *(uint64_t *)o->to = v; break;
    case OPT_T_I64: *(int64_t *)o->to = (int64_t)v; break;
    default: assert(!"an option of whole numbers stored elsewhere");
    }
}

static void put_real(const opt *o, double v)
{
    if (o->type == OPT_T_FLOAT) {
        *(float *)o->to = (float)v;
    } else {
        assert(o->type == OPT_T_DOUBLE);
        *(double *)o->to = v;
    }
}

static const opt_choice *find_choice(const opt_choice *list, const char *v)
{
    for (size_t k = 0; v != NULL && list[k].name != NULL; k++) {
        if (strcmp(v, list[k].name) == 0) {
            return &list[k];
        }
    }
    return NULL;
}

const char *opt_choice_name(const opt_choice *list, int id)
{
    for (size_t k = 0; list[k].name != NULL; k++) {
        if (list[k].id == id && !list[k].alias) {
            return list[k].name;
        }
    }
    return NULL;
}

/* What goes before item k of n in a list: nothing before the first,
 * last before the last ("a, b or c"), else a comma. */
static const char *separator(size_t k, size_t n, const char *last)
{
    return k == 0 ? "" : k + 1 == n ? last : ", ";
}

/* Appends text to the string in buf, as far as it fits. */
static void append(char *buf, size_t size, const char *text)
{
    strncat(buf, text, size - strlen(buf) - 1);
}

/* The names of list that are not aliases, joined: "a, b or c". */
static void join_names(char *buf, size_t size, const opt_choice *list,
                       const char *last)
{
    size_t n = 0, k = 0;
    for (const opt_choice *c = list; c->name != NULL; c++) {
        n += !c->alias;
    }
    buf[0] = '\0';
    for (const opt_choice *c = list; c->name != NULL; c++) {
        if (!c->alias) {
            append(buf, size, separator(k++, n, last));
            append(buf, size, c->name);
        }
    }
}

static void refuse_choice(const char *program, const opt *o, const char *v)
{
    char names[256];
    if (o->flags & OPT_SAY_NEEDS_ONE_OF) {
        join_names(names, sizeof names, o->choices, ", ");
        cli_usage_error(program, "%s needs one of %s%s%s%s", o->name, names,
                        v ? ", not '" : "", v ? v : "", v ? "'" : "");
    } else {
        join_names(names, sizeof names, o->choices, " or ");
        cli_bad_value(program, o->name, v, names);
    }
}

/* Option o with its value v (NULL: missing); 0, or -1 after saying why
 * not. */
static int read_value(const char *program, const opt *o, const char *v)
{
    switch (o->kind) {
    case OPT_FLAG: put_int(o, (uint64_t)(int64_t)o->set); return 0;
    case OPT_INT: {
        uint64_t n = 0;
        if (cli_int_option(program, o->name, v, o->min, o->max, &n) != 0) {
            return -1;
        }
        put_int(o, n);
        return 0;
    }
    case OPT_REAL: {
        double d = 0.0;
        if (cli_real_option(program, o->name, v, o->lo, o->hi, o->open, &d) !=
            0) {
            return -1;
        }
        put_real(o, d);
        return 0;
    }
    case OPT_TEXT:
        if (v == NULL) {
            cli_bad_value(program, o->name, NULL, NULL);
            return -1;
        }
        *(const char **)o->to = v;
        return 0;
    case OPT_CHOICE: {
        const opt_choice *c = find_choice(o->choices, v);
        if (c == NULL) {
            refuse_choice(program, o, v);
            return -1;
        }
        put_int(o, (uint64_t)(int64_t)c->id);
        return 0;
    }
    case OPT_CUSTOM: return o->read(program, o, v);
    }
    return -1;
}

/* "--data and --out are required", "--model, --out and --data, --path or
 * --poses are required": every required option named, when one is
 * missing, the alternatives last as one item. */
static int check_required(const opt_program *p, const bool *seen)
{
    const opt *opts = p->opts;
    const size_t n = opt_count(opts);
    bool missing = false, alternative_seen = false;
    size_t required = 0, alternatives = 0;
    for (size_t k = 0; k < n; k++) {
        if (opts[k].flags & OPT_REQUIRED) {
            missing |= !seen[k];
            required++;
        }
        if (opts[k].flags & OPT_ONE_OF) {
            alternative_seen |= seen[k];
            alternatives++;
        }
    }
    if (!missing && (alternatives == 0 || alternative_seen)) {
        return 0;
    }
    const size_t items = required + (alternatives > 0);
    size_t item = 0, alternative = 0;
    char list[512] = "";
    for (size_t k = 0; k < n; k++) {
        if (opts[k].flags & OPT_REQUIRED) {
            append(list, sizeof list, separator(item++, items, " and "));
            append(list, sizeof list, opts[k].name);
        }
    }
    if (alternatives > 0) {
        append(list, sizeof list, separator(item++, items, " and "));
    }
    for (size_t k = 0; k < n; k++) {
        if (opts[k].flags & OPT_ONE_OF) {
            append(list, sizeof list,
                   separator(alternative++, alternatives, " or "));
            append(list, sizeof list, opts[k].name);
        }
    }
    cli_usage_error(p->name, "%s %s required", list, items == 1 ? "is" : "are");
    return -1;
}

static const opt *find_opt(const opt *opts, const char *name)
{
    for (size_t k = 0; opts[k].name != NULL; k++) {
        if (strcmp(name, opts[k].name) == 0) {
            return &opts[k];
        }
    }
    return NULL;
}

/* The value of option argv[*i], advancing *i past it; NULL when there is
 * none. */
static const char *take_value(const opt *o, int argc, char **argv, int *i)
{
    if (o->kind == OPT_FLAG || *i + 1 >= argc) {
        return NULL;
    }
    const char *next = argv[*i + 1];
    if ((o->flags & OPT_VALUE_OPTIONAL) &&
        !(next[0] >= '0' && next[0] <= '9')) {
        return NULL;
    }
    return argv[++*i];
}

int opt_parse(const opt_program *p, int argc, char **argv)
{
    const opt *opts = p->opts;
    const size_t n = opt_count(opts);
    /* The names a mistyped option is compared with. */
    const char *names[OPT_MAX + 3] = {"--help", "-h"};
    /* The defaults, which --help shows whatever came before it. */
    uint64_t saved[OPT_MAX];
    bool seen[OPT_MAX];
    _Static_assert(sizeof(const char *) <= sizeof(uint64_t),
                   "a pointer fits a saved default");
    for (size_t k = 0; k < n; k++) {
        names[k + 2] = opts[k].name;
        memcpy(&saved[k], opts[k].to, type_size(opts[k].type));
        seen[k] = false;
    }
    names[n + 2] = NULL;
    for (int i = 1; i < argc; i++) {
        const char *k = argv[i];
        if (strcmp(k, "--help") == 0 || strcmp(k, "-h") == 0) {
            for (size_t j = 0; j < n; j++) {
                memcpy(opts[j].to, &saved[j], type_size(opts[j].type));
            }
            opt_help(p, stdout);
            exit(0);
        }
        const opt *o = find_opt(opts, k);
        if (o == NULL && p->operand && (k[0] != '-' || k[1] == '\0')) {
            if (*p->operand_to != NULL) {
                cli_usage_error(p->name, "one %s at a time (%s and %s)",
                                p->operand, *p->operand_to, k);
                return -1;
            }
            *p->operand_to = k;
            continue;
        }
        if (o == NULL) {
            cli_unknown(p->name, k, names);
            return -1;
        }
        if (read_value(p->name, o, take_value(o, argc, argv, &i)) != 0) {
            return -1;
        }
        seen[o - opts] = true;
        if (o->given != NULL) {
            *o->given |= o->bit ? o->bit : 1;
        }
    }
    return check_required(p, seen);
}
