#include "interrupt.h"

volatile sig_atomic_t interrupted;

static void on_signal(int sig)
{
    interrupted = sig;
}

void interrupt_catch(int sigterm)
{
    signal(SIGINT, on_signal);
    if (sigterm) {
        signal(SIGTERM, on_signal);
    }
}
