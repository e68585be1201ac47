/* opt_help(): a program's --help, written from its table of options. */
#include <inttypes.h>
#include <string.h>

#include "opt_table.h"
#include "options.h"

/* The usage line is wrapped before this column, as the help's prose. */
#define WIDTH 79

/* OPT_CHOICE's names as the usage line gives them: "a|b|c". */
static void choice_list(char *buf, size_t size, const opt_choice *list)
{
    size_t used = 0;
    buf[0] = '\0';
    for (size_t k = 0; list[k].name != NULL && used < size; k++) {
        if (!list[k].alias) {
            used += (size_t)snprintf(buf + used, size - used, "%s%s",
                                     used ? "|" : "", list[k].name);
        }
    }
}

/* The option with its value as the usage line gives it: "--steps N",
 * "--preset tiny|reference|fast", "--jpeg [QUALITY]"; the help's head
 * names a choice's value as .value does ("--preset P"), if it does. */
static void token(char *buf, size_t size, const opt *o, bool for_usage)
{
    char value[256] = "";
    if (o->kind == OPT_CHOICE && (for_usage || o->value == NULL)) {
        choice_list(value, sizeof value, o->choices);
    } else if (o->value != NULL) {
        snprintf(value, sizeof value,
                 o->flags & OPT_VALUE_OPTIONAL ? "[%s]" : "%s", o->value);
    }
    snprintf(buf, size, "%s%s%s", o->name, value[0] ? " " : "", value);
}

typedef struct line {
    FILE *out;
    int col, indent;
} line;

static void put_word(line *l, const char *word)
{
    int len = (int)strlen(word);
    if (l->col + 1 + len > WIDTH && l->col > l->indent) {
        fprintf(l->out, "\n%*s", l->indent, "");
        l->col = l->indent;
    } else {
        fputc(' ', l->out);
        l->col++;
    }
    fputs(word, l->out);
    l->col += len;
}

/* "usage: PROG REQUIRED (ONE | OF) [OPTIONAL]...", wrapped under the
 * first option. */
static void usage_line(const opt_program *p, FILE *out)
{
    line l = {out, 0, 0};
    l.col = fprintf(out, "usage: %s", p->name);
    l.indent = l.col + 1;
    char word[512];
    for (const opt *o = p->opts; o->name != NULL; o++) {
        if (o->flags & OPT_REQUIRED) {
            token(word, sizeof word, o, true);
            put_word(&l, word);
        }
    }
    const opt *last = NULL;
    for (const opt *o = p->opts; o->name != NULL; o++) {
        last = o->flags & OPT_ONE_OF ? o : last;
    }
    bool first = true;
    for (const opt *o = p->opts; o->name != NULL; o++) {
        if (o->flags & OPT_ONE_OF) {
            char t[400];
            token(t, sizeof t, o, true);
            snprintf(word, sizeof word, "%s%s%s", first ? "(" : "| ", t,
                     o == last ? ")" : "");
            put_word(&l, word);
            first = false;
        }
    }
    if (p->operand != NULL) {
        snprintf(word, sizeof word, "[%s]", p->operand);
        put_word(&l, word);
    }
    for (const opt *o = p->opts; o->name != NULL; o++) {
        if (!(o->flags & (OPT_REQUIRED | OPT_ONE_OF))) {
            char t[400];
            token(t, sizeof t, o, true);
            snprintf(word, sizeof word, "[%s]", t);
            put_word(&l, word);
        }
    }
    fputc('\n', out);
}

/* The value o holds, as its help's "{default}" gives it. */
static void format_default(char *buf, size_t size, const opt *o)
{
    const char *name = NULL;
    int64_t id = 0;
    switch (o->type) {
    case OPT_T_INT: id = *(const int *)o->to; break;
    case OPT_T_U32: id = *(const uint32_t *)o->to; break;
    case OPT_T_I64: id = *(const int64_t *)o->to; break;
    case OPT_T_U64:
        if (o->kind != OPT_CHOICE) {
            snprintf(buf, size, "%" PRIu64, *(const uint64_t *)o->to);
            return;
        }
        id = (int64_t) * (const uint64_t *)o->to;
        break;
    case OPT_T_DOUBLE:
        snprintf(buf, size, "%g", *(const double *)o->to);
        return;
    case OPT_T_FLOAT:
        snprintf(buf, size, "%g", (double)*(const float *)o->to);
        return;
    case OPT_T_TEXT:
        name = *(const char *const *)o->to;
        snprintf(buf, size, "%s", name ? name : "none");
        return;
    default: snprintf(buf, size, "?"); return;
    }
    name = o->kind == OPT_CHOICE ? opt_choice_name(o->choices, (int)id) : NULL;
    if (name != NULL) {
        snprintf(buf, size, "%s", name);
    } else {
        snprintf(buf, size, "%" PRId64, id);
    }
}

/* o's range, as its help's "{range}" gives it: "1..256", "[0, 1]". */
static void format_range(char *buf, size_t size, const opt *o)
{
    if (o->kind == OPT_REAL) {
        snprintf(buf, size, "%c%g, %g%c", o->open & CLI_ABOVE_MIN ? '(' : '[',
                 o->lo, o->hi, o->open & CLI_BELOW_MAX ? ')' : ']');
    } else {
        snprintf(buf, size, "%" PRIu64 "..%" PRIu64, o->min, o->max);
    }
}

/* A paragraph: "  HEAD" then the text from the column on (two spaces
 * after a head that reaches it), each line after the first indented to
 * it. */
static void paragraph(FILE *out, int column, const char *head, const char *text,
                      const opt *o)
{
    int used = fprintf(out, "  %s", head);
    fprintf(out, "%*s", used + 2 > column ? 2 : column - used, "");
    for (const char *c = text; *c != '\0'; c++) {
        char sub[128];
        if (o != NULL && strncmp(c, "{default}", 9) == 0) {
            format_default(sub, sizeof sub, o);
            fputs(sub, out);
            c += 8;
        } else if (o != NULL && strncmp(c, "{range}", 7) == 0) {
            format_range(sub, sizeof sub, o);
            fputs(sub, out);
            c += 6;
        } else {
            fputc(*c, out);
            if (*c == '\n' && c[1] != '\0') {
                fprintf(out, "%*s", column, "");
            }
        }
    }
    fputc('\n', out);
}

/* "--path orbit", or "--layout colmap-text, colmap-binary" with the
 * choices that share the paragraph. */
static void choice_paragraphs(FILE *out, int column, const opt *o)
{
    const opt_choice *c = o->choices;
    for (size_t k = 0; c[k].name != NULL; k++) {
        if (c[k].help == NULL) {
            continue;
        }
        char head[256];
        int used = snprintf(head, sizeof head, "%s %s", o->name, c[k].name);
        for (size_t j = k + 1; c[j].name != NULL && c[j].help == NULL; j++) {
            if (!c[j].alias && used < (int)sizeof head) {
                used += snprintf(head + used, sizeof head - (size_t)used,
                                 ", %s", c[j].name);
            }
        }
        paragraph(out, column, head, c[k].help, o);
    }
}

void opt_help(const opt_program *p, FILE *out)
{
    usage_line(p, out);
    fputs(p->about, out);
    for (const opt *o = p->opts; o->name != NULL; o++) {
        if (o->help != NULL) {
            char head[512];
            if (o->head != NULL) {
                snprintf(head, sizeof head, "%s", o->head);
            } else {
                token(head, sizeof head, o, false);
            }
            paragraph(out, p->column, head, o->help, o);
        }
        if (o->kind == OPT_CHOICE && o->choices[0].help != NULL) {
            choice_paragraphs(out, p->column, o);
        }
    }
    paragraph(out, p->column, "--help", "print this help and exit", NULL);
    fputs(p->after, out);
}
