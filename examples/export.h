/*
 * The subcommands of nerf-export, one function each: argv[0] is the
 * subcommand's name, the rest its options.  Each returns the program's
 * exit status (0, 1 for a failure, 2 for bad arguments, 128 + signal when
 * interrupted).
 */
#ifndef NERF_EXAMPLES_EXPORT_H
#define NERF_EXAMPLES_EXPORT_H

/* export-views.c: depth maps and point clouds from rendered views. */
int export_depth(int argc, char **argv);
int export_points(int argc, char **argv);

/* export-mesh.c */
int export_mesh(int argc, char **argv);
int export_grid(int argc, char **argv);

#endif
