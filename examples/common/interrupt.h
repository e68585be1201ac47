/*
 * Ctrl-C (SIGINT) and SIGTERM for the programs that run long: caught, so
 * that the run stops where it is, saves or says what it wrote, and exits
 * as a shell reports the signal (128 + its number).
 */
#ifndef NERF_EXAMPLES_INTERRUPT_H
#define NERF_EXAMPLES_INTERRUPT_H

#include <signal.h>

/* The signal that stopped the run (SIGINT, SIGTERM), 0 while none has:
 * progress callbacks return nonzero once it is set, which cancels the
 * library's work. */
extern volatile sig_atomic_t interrupted;

/* Catch SIGINT into interrupted, and SIGTERM too unless sigterm is 0:
 * under mpirun, SIGTERM is how the job ends a rank whose peer died, and
 * caught it would leave the rank waiting for the dead one. */
void interrupt_catch(int sigterm);

#endif
