/* nerf-export mesh and nerf-export grid: the model's density out. */
#include <nerf.h>

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "common/cli.h"
#include "common/options.h"
#include "common/opt_table.h"
#include "common/shared_opts.h"
#include "common/out_folder.h"
#include "common/out_file.h"
#include "common/progress.h"
#include "export.h"

static const char mesh_about[] =
    "Extract the surface where MODEL's density crosses T with marching\n"
    "cubes, coloured by the model as seen looking at the surface head on,\n"
    "and write it as PLY (binary, or --ascii) or OBJ, by FILE's extension.\n"
    "The mesh is closed wherever the surface stays inside the box.\n";

static const char mesh_after[] =
    "Examples:\n"
    "  nerf-export mesh --model lego.nerf --out lego.ply\n"
    "  nerf-export mesh --model lego.nerf --out lego.obj --resolution 512 \\\n"
    "      --largest\n";

static const char grid_about[] =
    "Sample MODEL's density at the centres of a grid of cells over a box\n"
    "and write it as a float32 .npy of shape (nz, ny, nx) (C order: element\n"
    "[k][j][i] is the cell at x index i), with FILE.json beside it recording\n"
    "the box, the shape and the spacing.  The whole grid is held in memory:\n"
    "4 bytes a cell, 16 with --colour.\n";

static const char grid_after[] =
    "Examples:\n"
    "  nerf-export grid --model lego.nerf --out lego.npy --resolution 128\n"
    "  python3 -c \"import numpy; print(numpy.load('lego.npy').shape)\"\n";

/* nerf_mesh_options' largest resolution, and the most threads taken. */
#define RESOLUTION_MAX 16384
#define THREADS_MAX 1024

typedef struct args {
    const char *model, *out;
    nerf_mesh_options o;
    int ascii, overwrite;
} args;

/* "x0,y0,z0,x1,y1,z1", each max above its min. */
static int parse_box(const char *text, float box[6])
{
    char *end;
    const char *p = text;
    for (int i = 0; i < 6; i++) {
        double v = strtod(p, &end);
        if (end == p || !(v == v) || v > 1e30 || v < -1e30) {
            return -1;
        }
        box[i] = (float)v;
        p = end;
        if (i < 5) {
            if (*p != ',') {
                return -1;
            }
            p++;
        }
    }
    if (*p != '\0') {
        return -1;
    }
    for (int a = 0; a < 3; a++) {
        if (!(box[a + 3] > box[a])) {
            return -1;
        }
    }
    return 0;
}

static int read_box(const char *program, const opt *o, const char *v)
{
    if (v == NULL || parse_box(v, o->to) != 0) {
        cli_bad_value(program, o->name, v,
                      "x0,y0,z0,x1,y1,z1 with each max above its min");
        return -1;
    }
    return 0;
}

static int parse(int argc, char **argv, args *a, int mesh)
{
    const char *program = mesh ? "nerf-export mesh" : "nerf-export grid";
    memset(a, 0, sizeof *a);
    NERF_MESH_OPTIONS_INIT(&a->o);
    if (!mesh) {
        a->o.colour = NERF_MESH_COLOUR_NONE;
    }
    opt opts[16];
    size_t n = 0;
    opts[n++] = (opt){OPT_MODEL(&a->model)};
    opts[n++] = (opt){
        .name = "--out", OPT_TEXT_TO(&a->out), .flags = OPT_REQUIRED,
        .value = mesh ? "FILE" : "FILE.npy",
        .help = mesh ? "the mesh: FILE.ply or FILE.obj (required)"
                     : "the density grid (required)"};
    opts[n++] = (opt){
        .name = "--resolution",
        OPT_INT_IN(&a->o.resolution, 1, RESOLUTION_MAX), .value = "N",
        .help = mesh ? "cells along the box's longest side, {range}\n"
                       "(default {default}); memory grows as N^2, time as N^3"
                     : "cells along the box's longest side, {range}\n"
                       "(default {default})"};
    if (mesh) {
        opts[n++] = (opt){
            .name = "--threshold",
            OPT_REAL_IN(&a->o.threshold, -HUGE_VAL, HUGE_VAL, 0), .value = "T",
            .help = "density at the surface (default {default})"};
    }
    opts[n++] = (opt){
        .name = "--box", OPT_CUSTOM_READ(a->o.box, read_box),
        .value = "X0,Y0,Z0,X1,Y1,Z1",
        .help = mesh ? "the region to mesh, min and max corners in the\n"
                       "model's space (default: the model's bounds)"
                     : "the region, min and max corners in the model's\n"
                       "space (default: the model's bounds)"};
    if (mesh) {
        opts[n++] = (opt){.name = "--ascii", OPT_FLAG_SETS(&a->ascii, 1),
                          .help = "write ASCII PLY instead of binary"};
        opts[n++] = (opt){
            .name = "--largest", OPT_FLAG_SETS(&a->o.keep_largest, 1),
            .help = "keep only the largest connected piece"};
        opts[n++] = (opt){
            .name = "--min-faces",
            OPT_INT_IN(&a->o.min_component_faces, 0, UINT32_MAX), .value = "N",
            .help = "drop pieces of fewer than N triangles (default "
                    "{default})"};
        opts[n++] = (opt){
            .name = "--no-colour",
            OPT_FLAG_SETS(&a->o.colour, NERF_MESH_COLOUR_NONE),
            .help = "no vertex colours"};
    } else {
        opts[n++] = (opt){
            .name = "--colour",
            OPT_FLAG_SETS(&a->o.colour, NERF_MESH_COLOUR_NORMAL),
            .help = "also FILE_rgb.npy, (nz, ny, nx, 3) colours in [0, 1]\n"
                    "seen looking down the density's gradient"};
    }
    opts[n++] = (opt){
        .name = "--threads", OPT_INT_IN(&a->o.threads, 0, THREADS_MAX),
        .value = "N",
        .help = "threads sampling the density (default {default}: all "
                "cores)"};
    opts[n++] = (opt){
        OPT_OVERWRITE(&a->overwrite),
        .help = mesh ? "replace FILE if it exists (default off: an existing\n"
                       "FILE is refused; MODEL never is)"
                     : "replace FILE.npy and its sidecars if they exist\n"
                       "(default off: an existing one is refused; MODEL\n"
                       "never is)"};
    opts[n] = (opt){.name = NULL};
    const opt_program p = {.name = program, .opts = opts, .column = 18,
                           .about = mesh ? mesh_about : grid_about,
                           .after = mesh ? mesh_after : grid_after};
    if (opt_parse(&p, argc, argv) != 0) {
        return -1;
    }
    if (mesh) {
        const size_t len = strlen(a->out);
        const char *ext = len >= 4 ? a->out + len - 4 : "";
        if (strcmp(ext, ".ply") != 0 && strcmp(ext, ".obj") != 0) {
            cli_usage_error(program, "--out %s: the file must end in .ply "
                            "or .obj", a->out);
            return -1;
        }
        if (a->ascii && strcmp(ext, ".ply") != 0) {
            cli_usage_error(program, "--ascii is for .ply files");
            return -1;
        }
    }
    return 0;
}

/* Whether a file can be made beside path: found before the sampling, not
 * after it. */
static int check_writable(const char *program, const char *path)
{
    if (out_make_parent(path, program) != 0) {
        return -1;
    }
    char probe[4096];
    snprintf(probe, sizeof probe, "%s.check.%ld", path, (long)getpid());
    FILE *f = fopen(probe, "wb");
    if (f == NULL) {
        fprintf(stderr, "%s: %s: cannot be written\n", program, path);
        return -1;
    }
    fclose(f);
    remove(probe);
    return 0;
}

/*
 * The files the export will write, each new or replaced as told, none
 * the model: the mesh, or the grid with the sidecars
 * nerf_density_grid_write() names after it ("F.npy": "F.json" and, with
 * colours, "F_rgb.npy"; another name gets the suffixes appended).
 */
static int check_targets(const char *program, const args *a, int mesh)
{
    const out_input model = {"MODEL", a->model};
    if (out_file_check(program, a->out, a->overwrite, NULL, &model, 1) != 0) {
        return -1;
    }
    if (mesh) {
        return 0;
    }
    size_t n = strlen(a->out);
    if (n > 4 && strcmp(a->out + n - 4, ".npy") == 0) {
        n -= 4;
    }
    char path[4200];
    snprintf(path, sizeof path, "%.*s.json", (int)n, a->out);
    if (out_file_check(program, path, a->overwrite, NULL, &model, 1) != 0) {
        return -1;
    }
    snprintf(path, sizeof path, "%.*s_rgb.npy", (int)n, a->out);
    return a->o.colour == NERF_MESH_COLOUR_NONE
               ? 0
               : out_file_check(program, path, a->overwrite, NULL, &model, 1);
}

static int run(int argc, char **argv, int mesh)
{
    const char *program = mesh ? "nerf-export mesh" : "nerf-export grid";
    args a;
    if (parse(argc, argv, &a, mesh) != 0) {
        return 2;
    }
    if (check_targets(program, &a, mesh) != 0) {
        return 2;
    }
    if (check_writable(program, a.out) != 0) {
        return 1;
    }
    nerf_hooks hooks;
    NERF_HOOKS_INIT(&hooks);
    hooks.log_cb = cli_log;
    hooks.log_user = "nerf-export";
    a.o.hooks = &hooks;
    progress_reports bar = {.label = program};
    a.o.progress = progress_on_report;
    a.o.progress_user = &bar;
    nerf_model *m = NULL;
    nerf_mesh *mesh_out = NULL;
    int rc = nerf_model_load(&m, a.model, &hooks);
    if (rc == NERF_OK && mesh) {
        rc = nerf_mesh_extract(&mesh_out, m, &a.o);
        progress_reports_end(&bar);
        if (rc == NERF_OK) {
            rc = nerf_mesh_write(mesh_out, a.out,
                                 a.ascii ? NERF_MESH_FORMAT_PLY_ASCII
                                         : NERF_MESH_FORMAT_AUTO);
        }
        if (rc == NERF_OK) {
            fprintf(stderr, "%s: %s: %zu vertices, %zu triangles\n", program,
                    a.out, nerf_mesh_vertex_count(mesh_out),
                    nerf_mesh_face_count(mesh_out));
            if (nerf_mesh_face_count(mesh_out) == 0) {
                fprintf(stderr, "%s: no surface at threshold %g: try a lower "
                        "--threshold\n", program, (double)a.o.threshold);
            }
        }
    } else if (rc == NERF_OK) {
        rc = nerf_density_grid_write(m, a.out, &a.o);
        progress_reports_end(&bar);
        if (rc == NERF_OK) {
            fprintf(stderr, "%s: wrote %s and its .json sidecar\n", program,
                    a.out);
        }
    }
    if (rc != NERF_OK) {
        cli_report(program, rc);
    }
    nerf_mesh_destroy(mesh_out);
    nerf_model_destroy(m);
    return rc == NERF_OK ? 0 : 1;
}

int export_mesh(int argc, char **argv)
{
    return run(argc, argv, 1);
}

int export_grid(int argc, char **argv)
{
    return run(argc, argv, 0);
}
