/*
 * libnerf's internals, for its benchmarks and tests.  Not installed, not
 * part of the ABI: the nerf__ functions and structs below change whenever
 * the library does, and programs outside this tree must use nerf.h only.
 *
 * The rules, so that a benchmark or a test measures the library and
 * never a copy of it:
 *
 *  - bench/ reaches the internals through this header alone, never by
 *    including a component's header directly (tests/ is to follow);
 *  - nothing is copied: a value or a computation the library has (march
 *    settings, seeds and stream keys, schedules, the way a step calls its
 *    building blocks) is exposed by the library, as a nerf__ function or
 *    a macro in the header of the code that uses it, and the benchmark
 *    or test calls that instead of writing it out again: one that
 *    restates it goes on measuring the old behaviour once the library
 *    changes;
 *  - a header that a benchmark or test needs and that is missing below is
 *    added here, in its component's place in the list.
 *
 * They link libnerf_internal_dep (lib/meson.build): the static archive,
 * whose objects keep the nerf__ symbols that the shared library hides, and
 * every folder of lib/ on the include path.
 */
#ifndef NERF_INTERNAL_H
#define NERF_INTERNAL_H

#include "nerf.h"

/* The layers bottom up, as in lib/layers.txt. */

/* common: allocation and logging, errors, threads, random streams. */
#include "cpu.h"
#include "env.h"
#include "error.h"
#include "parallel.h"
#include "rng.h"

/* camera: cameras, rays, NDC. */
#include "camera.h"
#include "ndc.h"

/* io: files, .npy arrays and the zip archives that hold them. */
#include "file_io.h"
#include "npy.h"
#include "zip_read.h"

/* image: PNG files. */
#include "png_io.h"

/* space and encoding: the scene space; frequency, hash grid and
 * spherical harmonics behind one interface. */
#include "encoding.h"
#include "hashgrid.h"
#include "sh.h"
#include "space.h"

/* mlp: the layers' products (fp32 and bf16), the network, Adam. */
#include "adam.h"
#include "fused.h"
#include "gemm.h"
#include "gemm_onednn.h"
#include "layer.h"
#include "network.h"
#include "network_fused.h"
#include "smm.h"

/* occupancy and model: the grid, and the struct behind nerf_model. */
#include "model.h"
#include "occupancy.h"

/* sampling: stratified, hierarchical, marching. */
#include "march.h"
#include "sampler.h"

/* render: compositing, the batch renderer and its threaded driver. */
#include "composite.h"
#include "composite_packed.h"
#include "render_batch.h"
#include "renderer.h"

/* dataset, scene: datasets, the built-in scene. */
#include "dataset.h"
#include "field.h"

/* train: the struct behind nerf_trainer and its schedules. */
#include "trainer.h"

#endif
