/*
 * The subcommands of nerf-export, one function each, called by the
 * dispatcher in nerf-export.c with argv[0] the subcommand's name.  Each
 * returns the program's exit status: 0, 1 (failure), 2 (bad arguments),
 * 128 + signal when interrupted.
 */
#ifndef NERF_EXAMPLES_EXPORT_H
#define NERF_EXAMPLES_EXPORT_H

/* export-views.c: depth maps and point clouds from rendered views. */
int export_depth(int argc, char **argv);
int export_points(int argc, char **argv);

#endif
