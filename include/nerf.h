/*
 * libnerf: Neural Radiance Fields on the CPU.
 *
 * This is the only public header.  Everything that is not declared here is
 * private and may change at any time.  See docs/api-conventions.md for the
 * rules every declaration follows and docs/threading.md for the threading
 * contract.
 *
 * Copyright (c) 2026 the libnerf authors.  MIT licence, see LICENSE.
 */
#ifndef NERF_H
#define NERF_H

#include <stddef.h>
#include <stdint.h>

#include "nerf_version.h"

#ifndef NERF_API
#  if defined(_WIN32) && defined(NERF_BUILDING_DLL)
#    define NERF_API __declspec(dllexport)
#  elif defined(_WIN32) && !defined(NERF_STATIC)
#    define NERF_API __declspec(dllimport)
#  elif defined(__GNUC__) && __GNUC__ >= 4
#    define NERF_API __attribute__((visibility("default")))
#  else
#    define NERF_API
#  endif
#endif

#ifdef __cplusplus
extern "C" {
#endif

/**
 * @file nerf.h
 *
 * Conventions, in brief (the full text is docs/api-conventions.md):
 *  - Every fallible call returns an int status: NERF_OK (0) or a negative
 *    nerf_status.  On failure, nerf_last_error() explains what failed.
 *  - Objects handed back through a `**out` argument belong to the caller and
 *    are released with the matching *_destroy(), which accepts NULL.
 *  - Options structs start with `struct_size`; fill them with the matching
 *    *_init() (or its NERF_*_INIT macro) and change only what you need.
 *    Fields are only ever appended, so binaries built against an older
 *    header keep working.
 *  - The library never prints to stdout, never exits and never aborts.
 */

/* ------------------------------------------------------------------------ */
/* Status codes and errors                                                  */
/* ------------------------------------------------------------------------ */

/** Status codes.  Values are fixed forever; new codes get new numbers. */
typedef enum nerf_status {
    NERF_OK = 0,            /**< Success. */
    NERF_ERROR = -1,        /**< Unexpected internal failure. */
    NERF_EINVAL = -2,       /**< Invalid argument. */
    NERF_ENOMEM = -3,       /**< Out of memory. */
    NERF_EIO = -4,          /**< A file could not be opened, read or written. */
    NERF_EFORMAT = -5,      /**< A file or buffer is malformed or corrupted. */
    NERF_ECANCELLED = -6,   /**< A callback or nerf_*_cancel() stopped the call. */
    NERF_EVERSION = -7      /**< Unsupported struct or file version. */
} nerf_status;

/**
 * A short static description of a status code, such as "invalid argument".
 * @return never NULL; unknown codes give "unknown status".
 * Thread-safe.
 */
NERF_API const char *nerf_status_string(int status);

/**
 * The message of the last failing call on the calling thread, for example
 * "scene/transforms.json: missing field 'frames'".
 *
 * @return never NULL; "" when no call on this thread has failed yet.  The
 * string stays valid until the next failing libnerf call on the same thread.
 * Successful calls do not clear it.  Thread-safe (the message is
 * thread-local).
 */
NERF_API const char *nerf_last_error(void);

/** Forget the calling thread's last error message. Thread-safe. */
NERF_API void nerf_clear_error(void);

/* ------------------------------------------------------------------------ */
/* Version                                                                  */
/* ------------------------------------------------------------------------ */

/**
 * The library's version as NERF_VERSION_NUMBER encodes it
 * (major * 10000 + minor * 100 + patch).  Compare it with the header's
 * NERF_VERSION_NUMBER to detect a mismatched shared library.  Thread-safe.
 */
NERF_API unsigned nerf_version_number(void);

/** The library's version as "major.minor.patch".  Static, never NULL. */
NERF_API const char *nerf_version_string(void);

/**
 * A one-line description of how the library was built: version, BLAS
 * provider, library versions of libpng, zlib and cJSON, and build type.
 * Static, never NULL.  Thread-safe.
 */
NERF_API const char *nerf_build_info(void);

/* ------------------------------------------------------------------------ */
/* Logging and allocation hooks                                             */
/* ------------------------------------------------------------------------ */

/** Log levels; a message is delivered when its level <= the threshold. */
typedef enum nerf_log_level {
    NERF_LOG_ERROR = 0,
    NERF_LOG_WARN = 1,
    NERF_LOG_INFO = 2,
    NERF_LOG_DEBUG = 3
} nerf_log_level;

/**
 * Log callback.  @p msg is a complete line without a trailing newline and is
 * valid only during the call.  The callback runs on the thread that called
 * into libnerf and must not call back into the handle that logged.
 */
typedef void (*nerf_log_cb)(int level, const char *msg, void *user);

/**
 * Set the process-wide log handler, used by every handle whose hooks do not
 * name their own.  The default handler is silent: libnerf prints nothing
 * unless asked to.  Pass NULL to restore silence.  @p max_level filters
 * (NERF_LOG_INFO delivers errors, warnings and information).
 *
 * Not thread-safe with respect to concurrent logging: call it at start-up,
 * before other threads use libnerf.
 */
NERF_API void nerf_log_set_default(nerf_log_cb cb, void *user, int max_level);

/**
 * A ready-made log callback that writes "libnerf: <level>: <msg>" lines to
 * stderr.  @p user is ignored.  Pass it to nerf_log_set_default() or put it
 * in nerf_hooks.log_cb.
 */
NERF_API void nerf_log_stderr(int level, const char *msg, void *user);

/**
 * Per-handle hooks: where the handle's memory comes from and where its log
 * goes.  Passed by pointer at creation and copied; NULL means the process
 * defaults (malloc/free and the default log handler).
 *
 * alloc and free must both be set or both be NULL.  alloc returns memory
 * aligned for any standard type, or NULL on failure; libnerf aligns its own
 * SIMD buffers inside what alloc returns.  Memory that libpng, zlib, cJSON
 * and the BLAS allocate internally does not go through these hooks.
 */
typedef struct nerf_hooks {
    uint32_t struct_size;   /**< sizeof(nerf_hooks), set by nerf_hooks_init(). */
    int32_t log_level;      /**< Threshold for log_cb; default NERF_LOG_INFO. */
    void *(*alloc)(size_t size, void *user);  /**< NULL: malloc. */
    void (*free)(void *ptr, void *user);      /**< NULL: free. */
    void *alloc_user;       /**< Passed to alloc and free. */
    nerf_log_cb log_cb;     /**< NULL: the process default handler. */
    void *log_user;         /**< Passed to log_cb. */
} nerf_hooks;

/**
 * Fill @p hooks with defaults and record @p struct_size.
 * @return NERF_OK, or NERF_EINVAL if @p hooks is NULL or @p struct_size is
 * too small to hold struct_size itself.
 */
NERF_API int nerf_hooks_init(nerf_hooks *hooks, size_t struct_size);
#define NERF_HOOKS_INIT(h) nerf_hooks_init((h), sizeof *(h))

/* ------------------------------------------------------------------------ */
/* Handles                                                                  */
/* ------------------------------------------------------------------------ */

typedef struct nerf_model nerf_model;       /**< Scene networks and weights. */
typedef struct nerf_sampler nerf_sampler;   /**< Sample placement along rays. */
typedef struct nerf_renderer nerf_renderer; /**< Compositing and images. */
typedef struct nerf_dataset nerf_dataset;   /**< Images and cameras. */
typedef struct nerf_trainer nerf_trainer;   /**< Optimisation loop state. */

/* ------------------------------------------------------------------------ */
/* Model                                                                    */
/* ------------------------------------------------------------------------ */

/** Kinds of input encoding. */
typedef enum nerf_encoding_kind {
    NERF_ENCODING_FREQUENCY = 1   /**< Sinusoidal positional encoding. */
} nerf_encoding_kind;

/** Flags for nerf_model_options.encoding_flags. */
#define NERF_ENCODING_INCLUDE_INPUT 0x1u /**< Prepend the raw input. */
#define NERF_ENCODING_SCALE_PI 0x2u      /**< Frequencies 2^k pi, not 2^k. */

/** Named configurations for nerf_model_options_preset(). */
typedef enum nerf_preset {
    NERF_PRESET_REFERENCE = 1, /**< The paper's networks (the default). */
    NERF_PRESET_TINY = 2       /**< Small and fast, for trials and tests. */
} nerf_preset;

/** Which of the model's two networks a call addresses. */
typedef enum nerf_network {
    NERF_NETWORK_COARSE = 0,
    NERF_NETWORK_FINE = 1
} nerf_network;

/**
 * Structural settings of a model, fixed at creation.  The defaults are the
 * paper's reference configuration.
 */
typedef struct nerf_model_options {
    uint32_t struct_size;     /**< Set by nerf_model_options_init(). */
    uint32_t encoding;        /**< nerf_encoding_kind; default FREQUENCY. */
    uint32_t pos_frequencies; /**< L for positions; default 10, 0 = raw input only. */
    uint32_t dir_frequencies; /**< L for directions; default 4. */
    uint32_t encoding_flags;  /**< NERF_ENCODING_*; default INCLUDE_INPUT
                                   (the reference form; the paper's form is
                                   SCALE_PI without INCLUDE_INPUT). */
    uint32_t depth;           /**< Trunk layers; default 8. */
    uint32_t width;           /**< Trunk width; default 256. */
    uint32_t skip_layer;      /**< 0-based trunk layer whose input is
                                   [gamma(x), h]; default 5 (the encoded
                                   position rejoins after the fifth layer, as
                                   pts_linears.5 of the reference); 0 = no
                                   skip. */
    uint32_t view_width;      /**< Width of the view branch; default 128. */
    uint32_t use_viewdirs;    /**< 1: colour depends on direction; default 1. */
    uint32_t use_fine;        /**< 1: a fine network too; default 1. */
    uint32_t reserved0;       /**< Must be 0. */
    uint64_t seed;            /**< Seed of initialisation and training; default 0. */
    const nerf_hooks *hooks;  /**< Allocation and logging; NULL = defaults. */
} nerf_model_options;

/**
 * Fill @p opts with the reference configuration and record @p struct_size
 * (pass sizeof *opts, or use NERF_MODEL_OPTIONS_INIT).
 * @return NERF_OK, or NERF_EINVAL for a NULL or too small struct.
 */
NERF_API int nerf_model_options_init(nerf_model_options *opts,
                                     size_t struct_size);
#define NERF_MODEL_OPTIONS_INIT(o) nerf_model_options_init((o), sizeof *(o))

/**
 * Overwrite the structural fields of an initialised @p opts with a named
 * preset; seed and hooks are kept.
 * @return NERF_OK, or NERF_EINVAL for an unknown preset or bad struct.
 */
NERF_API int nerf_model_options_preset(nerf_model_options *opts,
                                       int preset);

/**
 * Create a model with freshly initialised weights (deterministic for a given
 * seed; see docs/architecture.md for the scheme).
 * @return NERF_OK; NERF_EINVAL for out-of-range options; NERF_EVERSION for
 * an options struct from a newer header with non-zero unknown fields;
 * NERF_ENOMEM.
 */
NERF_API int nerf_model_create(nerf_model **out,
                               const nerf_model_options *opts);

/** Release a model.  NULL is a no-op. */
NERF_API void nerf_model_destroy(nerf_model *model);

/**
 * Copy the model's options into @p out, whose struct_size the caller sets
 * (only that many bytes are written).  out->hooks is set to NULL.
 * @return NERF_OK or NERF_EINVAL.
 */
NERF_API int nerf_model_get_options(const nerf_model *model,
                                    nerf_model_options *out);

/** Number of trainable parameters (both networks); 0 for NULL. */
NERF_API size_t nerf_model_param_count(const nerf_model *model);

/** Optimisation steps taken so far (restored by nerf_model_load()). */
NERF_API uint64_t nerf_model_step(const nerf_model *model);

/**
 * Evaluate one network on @p n samples.
 *
 * @param positions  n x 3 floats, row-major (x, y, z).
 * @param directions n x 3 floats, unit view directions; may be NULL when
 *                   the model does not use view directions.
 * @param rgb_out    n x 3 floats in [0, 1].
 * @param sigma_out  n floats: raw density, before the ReLU applied when
 *                   rendering.
 * @return NERF_OK; NERF_EINVAL (NULL buffers, unknown or absent network);
 * NERF_ENOMEM.
 *
 * Reentrant: several threads may query one model at the same time as long
 * as nothing trains or modifies it.  Memory use is bounded whatever @p n.
 */
NERF_API int nerf_model_query(const nerf_model *model, int network, size_t n,
                              const float *positions, const float *directions,
                              float *rgb_out, float *sigma_out);

/** Training hyperparameters, set with nerf_model_set_param(). */
typedef enum nerf_param {
    NERF_PARAM_LEARNING_RATE = 100,       /**< Initial rate; default 5e-4. */
    NERF_PARAM_LEARNING_RATE_FINAL = 101, /**< Rate reached after
                                               DECAY_STEPS; default 5e-5. */
    NERF_PARAM_DECAY_STEPS = 102,         /**< Default 250000: lr(t) =
                                               lr0 (lr1/lr0)^(t/steps). */
    NERF_PARAM_ADAM_BETA1 = 103,          /**< Default 0.9. */
    NERF_PARAM_ADAM_BETA2 = 104,          /**< Default 0.999. */
    NERF_PARAM_ADAM_EPS = 105             /**< Default 1e-7 (the paper's). */
} nerf_param;

/**
 * Valid range of a parameter, inclusive.
 * @return NERF_OK or NERF_EINVAL for an unknown parameter.
 */
NERF_API int nerf_param_bounds(int param, double *min_out, double *max_out);

/**
 * Set a training hyperparameter.  Takes effect at the next optimiser step.
 * @return NERF_OK; NERF_EINVAL for an unknown parameter or a value outside
 * nerf_param_bounds().
 */
NERF_API int nerf_model_set_param(nerf_model *model, int param, double value);

/** Read a training hyperparameter. @return NERF_OK or NERF_EINVAL. */
NERF_API int nerf_model_get_param(const nerf_model *model, int param,
                                  double *value_out);

/**
 * The learning rate the schedule gives at the model's current step.
 * 0 for NULL.
 */
NERF_API double nerf_model_learning_rate(const nerf_model *model);

/**
 * Save the model, its optimiser state and training step to @p path in
 * libnerf's checkpoint format (docs/formats.md).  The file is written to a
 * temporary name beside @p path, flushed and renamed, so an existing file at
 * @p path is replaced only by a complete checkpoint.
 * @return NERF_OK; NERF_EINVAL; NERF_EIO; NERF_ENOMEM.
 */
NERF_API int nerf_model_save(const nerf_model *model, const char *path);

/**
 * Load a checkpoint written by nerf_model_save().
 * @param hooks allocation and logging for the new model; NULL = defaults.
 * @return NERF_OK; NERF_EIO (cannot open or read); NERF_EFORMAT (not a
 * checkpoint, truncated or corrupted); NERF_EVERSION (written by a newer
 * libnerf); NERF_ENOMEM; NERF_EINVAL.
 */
NERF_API int nerf_model_load(nerf_model **out, const char *path,
                             const nerf_hooks *hooks);

/**
 * Create a model with @p opts and fill its weights from a NumPy .npz file
 * holding the state dict of the reference implementation, with names
 * prefixed by network: "coarse.pts_linears.0.weight" ... and "fine." ones
 * (see docs/formats.md).  Optimiser state starts at zero.
 * @return NERF_OK; NERF_EIO; NERF_EFORMAT (not an npz, bad member, missing
 * name, shape that does not match @p opts); NERF_EINVAL; NERF_ENOMEM.
 */
NERF_API int nerf_model_import_npz(nerf_model **out, const char *path,
                                   const nerf_model_options *opts);

#ifdef __cplusplus
}
#endif

#endif /* NERF_H */
