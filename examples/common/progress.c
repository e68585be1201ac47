#include "progress.h"

#include <stdio.h>
#include <time.h>
#include <unistd.h>

#include <nerf.h>

/* Without a terminal, one line per this many seconds keeps logs short. */
#define PLAIN_INTERVAL 10.0

double progress_now(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

void progress_begin(progress *p, const char *label, uint64_t total)
{
    p->label = label;
    p->total = total ? total : 1;
    p->tty = isatty(fileno(stderr));
    p->start = progress_now();
    p->last_print = -1e30;
}

void progress_update(progress *p, uint64_t done, const char *note)
{
    double t = progress_now();
    double elapsed = t - p->start;
    double frac = (double)done / (double)p->total;
    double eta = done > 0 ? elapsed * (1.0 - frac) / frac : 0.0;
    if (p->tty) {
        if (t - p->last_print < 0.1 && done < p->total) {
            return; /* redraw at most ten times a second */
        }
        char bar[31];
        int fill = (int)(frac * 30.0 + 0.5);
        for (int i = 0; i < 30; i++) {
            bar[i] = i < fill ? '#' : '.';
        }
        bar[30] = '\0';
        fprintf(stderr, "\r%s [%s] %3.0f%% %llu/%llu %.0fs eta %.0fs %s\033[K",
                p->label, bar, 100.0 * frac, (unsigned long long)done,
                (unsigned long long)p->total, elapsed, eta, note ? note : "");
    } else {
        if (t - p->last_print < PLAIN_INTERVAL && done < p->total) {
            return;
        }
        fprintf(stderr, "%s: %llu/%llu (%.0f%%) %.0fs elapsed, eta %.0fs %s\n",
                p->label, (unsigned long long)done,
                (unsigned long long)p->total, 100.0 * frac, elapsed, eta,
                note ? note : "");
    }
    fflush(stderr);
    p->last_print = t;
}

void progress_end(progress *p, const char *note)
{
    if (p->tty) {
        fputc('\n', stderr);
    }
    fprintf(stderr, "%s: done in %.1fs %s\n", p->label,
            progress_now() - p->start, note ? note : "");
}

int progress_on_report(const nerf_progress *p, void *user)
{
    progress_reports *r = user;
    if (!r->started) {
        progress_begin(&r->bar, r->label, p->total);
        r->started = 1;
    }
    progress_update(&r->bar, p->done, NULL);
    return 0;
}

void progress_reports_end(progress_reports *r)
{
    if (r->started) {
        progress_end(&r->bar, NULL);
        r->started = 0;
    }
}
