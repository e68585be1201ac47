/*
 * Progress display for the example programs: a bar redrawn in place on a
 * terminal, plain periodic lines otherwise (logs, CI, pipes).
 */
#ifndef NERF_EXAMPLES_PROGRESS_H
#define NERF_EXAMPLES_PROGRESS_H

#include <stdint.h>

typedef struct progress {
    const char *label;
    uint64_t total;
    int tty;
    double start;      /* seconds */
    double last_print; /* seconds */
} progress;

void progress_begin(progress *p, const char *label, uint64_t total);

/* Report that done of total units are finished; note is printed after the
 * bar (e.g. "loss 0.0123"), may be NULL. */
void progress_update(progress *p, uint64_t done, const char *note);

/* Finish the bar (newline on a terminal) and print the elapsed time. */
void progress_end(progress *p, const char *note);

double progress_now(void);

/*
 * A bar drawn from a library call's nerf_progress reports: pass
 * progress_on_report as the callback and the progress_reports as its user
 * pointer; the bar starts at the first report, labelled label.
 * progress_reports_end() finishes it if it started.
 */
typedef struct progress_reports {
    progress bar;
    int started;
    const char *label;
} progress_reports;

struct nerf_progress;
int progress_on_report(const struct nerf_progress *p, void *user);
void progress_reports_end(progress_reports *r);

#endif
