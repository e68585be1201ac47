/*
 * libnerf: Neural Radiance Fields on the CPU.
 *
 * This is the only public header.  Everything that is not declared here is
 * private and may change at any time.  See docs/api-conventions.md for the
 * rules every declaration follows and docs/threading.md for the threading
 * contract.
 *
 * Contents, in the order of the sections below (search for "N. Title"):
 *   (the @file comment)  Conventions in brief
 *    1. Status codes and errors
 *    2. Version
 *    3. Logging and allocation hooks
 *    4. Progress reports      (callbacks of renderers, trainers, geometry)
 *    5. Handles               (the eight opaque handle types)
 *    6. Cameras               (nerf_camera, used by several handles)
 *    7. Sampler and renderer settings  (their options structs; a model
 *                             records them, so they come before it)
 *    8. Model
 *    9. Sampler
 *   10. Renderer              (images, depth, rays)
 *   11. Datasets and camera paths
 *   12. Trainer
 *   13. Built-in scene        (nerf_scene_write)
 *   14. Meshes
 *   15. Point clouds
 *   16. Density grids
 *   17. Utilities: images, arrays and metrics
 * A type is declared before the first call that takes it, which is why
 * sections 6 and 7 come ahead of the handles that use them.
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
 *  - Handles handed back through a `**out` argument belong to the caller
 *    and are released with the matching *_destroy(), which accepts NULL.
 *  - Arguments go: the handle or struct the call acts on (or, for a
 *    function that creates a handle, its `**out`) first, then inputs, then
 *    out-parameters.  The one exception: the render_image calls take their
 *    pixel_capacity after their output buffers.
 *  - Options structs start with `struct_size`; fill them with the matching
 *    *_init() (or its NERF_*_INIT macro) and change only what you need.
 *    Fields are only ever appended, so binaries built against an older
 *    header keep working.
 *  - NERF_*_INIT(p) is the function call *_init(p, sizeof *p), not a
 *    constant initializer: it runs when reached, fills *p in place and
 *    returns the status.  Use it inside a function, as a statement or as
 *    in `int rc = NERF_HOOKS_INIT(&hooks);`.  It cannot be a struct's
 *    initializer, nor fill a static or file-scope struct at compile time:
 *    call it before the struct's first use.
 *  - The library never prints to stdout, never exits and never aborts.
 */

/* ===========================================================================
 * 1. Status codes and errors
 * ======================================================================== */

/** Status codes.  Values are fixed forever; new codes get new numbers. */
typedef enum nerf_status {
    NERF_OK = 0,            /**< Success. */
    NERF_ERROR = -1,        /**< Unexpected internal failure. */
    NERF_EINVAL = -2,       /**< Invalid argument. */
    NERF_ENOMEM = -3,       /**< Out of memory. */
    NERF_EIO = -4,          /**< A file could not be opened, read or written. */
    NERF_EFORMAT = -5,      /**< A file or buffer is malformed or corrupted. */
    NERF_ECANCELLED = -6,   /**< A callback or nerf_*_cancel() stopped the
                                 call. */
    NERF_EVERSION = -7,     /**< Unsupported struct or file version. */
    /* Before 0.4 both of the next two were NERF_EIO (and a file that is
     * not a checkpoint NERF_EFORMAT). */
    NERF_ENOENT = -8,       /**< No such file or folder: a path to read does not
                                 exist.
                                 @since 0.4 */
    NERF_EUNRECOGNISED = -9 /**< The file or folder exists but is not the kind
                                 asked for: a folder in no known dataset layout,
                                 a file that is not a libnerf checkpoint, a
                                 folder where a file is expected or a file where
                                 a folder is.
                                 @since 0.4 */
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

/* ===========================================================================
 * 2. Version
 * ======================================================================== */

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
 * provider, library versions of libpng, libjpeg, zlib and cJSON, and
 * build type; then the instruction set of the kernels this process runs
 * and the environment variables that chose them (docs/dispatch.md).
 * Static, never NULL.  Thread-safe.
 */
NERF_API const char *nerf_build_info(void);

/* ===========================================================================
 * 3. Logging and allocation hooks
 * ======================================================================== */

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
    uint32_t struct_size;   /**< sizeof(nerf_hooks), set by
                                 nerf_hooks_init(). */
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

/**
 * nerf_hooks_init(h, sizeof *h): a function call, evaluated at run time,
 * that returns the status.  Not a constant initializer: it cannot stand in
 * a declaration's initializer or fill a static or file-scope struct at
 * compile time.  Every NERF_*_INIT macro below is the same kind of call:
 * the defaults belong to the library a program runs with, not to the
 * header it was compiled with.
 */
#define NERF_HOOKS_INIT(h) nerf_hooks_init((h), sizeof *(h))

/* ===========================================================================
 * 4. Progress reports
 * ======================================================================== */

/** What a nerf_progress report is about. */
typedef enum nerf_progress_kind {
    NERF_PROGRESS_RENDER = 1, /**< done and total count rays. */
    NERF_PROGRESS_TRAIN = 2,  /**< done and total count steps; loss and
                                   psnr are those of the last step. */
    NERF_PROGRESS_GEOMETRY = 3, /**< nerf_mesh_extract() and
                                   nerf_density_grid_write(): done and total
                                   count planes of grid samples.
                                   @since 0.5 */
    NERF_PROGRESS_BAKE = 4     /**< nerf_bake_create(): done and total
                                   count occupancy cells.  @since 0.14 */
} nerf_progress_kind;

/**
 * A progress report, passed by pointer to a nerf_progress_cb.  Versioned:
 * read a field only if struct_size covers it (fields are only appended).
 */
typedef struct nerf_progress {
    uint32_t struct_size; /**< sizeof the library's struct. */
    uint32_t kind;        /**< nerf_progress_kind. */
    uint64_t done;        /**< Units of work finished so far. */
    uint64_t total;       /**< Units of work of the whole call. */
    double elapsed;       /**< Seconds since the call started. */
    double loss;          /**< NERF_PROGRESS_TRAIN: loss of the last step;
                               otherwise 0. */
    double psnr;          /**< NERF_PROGRESS_TRAIN: PSNR (dB) of the last
                               step's fine colours; otherwise 0. */
} nerf_progress;

/**
 * Progress callback.  It runs on the thread that made the call, never on a
 * worker thread, and must not call back into the handle that reports.
 * Return 0 to continue, nonzero to cancel: the call then returns
 * NERF_ECANCELLED.  @p p is valid only during the callback.
 */
typedef int (*nerf_progress_cb)(const nerf_progress *p, void *user);

/* ===========================================================================
 * 5. Handles
 * ======================================================================== */

/*
 * Every handle is opaque: made by its *_create() or *_load() call (or
 * nerf_points_from_views(), nerf_mesh_extract()), released by its
 * *_destroy().  Its calls are in its own section below.
 */
typedef struct nerf_model nerf_model;       /**< Scene networks and weights. */
typedef struct nerf_sampler nerf_sampler;   /**< Sample placement along rays. */
typedef struct nerf_renderer nerf_renderer; /**< Compositing and images. */
typedef struct nerf_dataset nerf_dataset;   /**< Images and cameras. */
typedef struct nerf_trainer nerf_trainer;   /**< Optimisation loop state. */
typedef struct nerf_camera_path nerf_camera_path; /**< Cameras from a file. */

/**
 * A point cloud: read-only arrays owned by the handle.
 * @since 0.5
 */
typedef struct nerf_points nerf_points;

/**
 * A triangle mesh extracted from a model (nerf_mesh_extract()).
 * Read-only arrays, valid until nerf_mesh_destroy().  Immutable: any
 * number of threads may read one mesh and write it at the same time.
 * @since 0.5
 */
typedef struct nerf_mesh nerf_mesh;

/* ===========================================================================
 * 6. Cameras
 * ======================================================================== */

/**
 * Flags for nerf_camera.flags.
 *
 * By default the ray of pixel (column i, row j) passes through the pixel's
 * centre, (i + 0.5, j + 0.5).  NERF_CAMERA_PIXEL_CORNER uses (i, j), as the
 * reference implementation does; set it to reproduce its rays exactly.
 */
#define NERF_CAMERA_PIXEL_CORNER 0x1u

/**
 * A camera in the OpenGL/Blender convention: in camera space x points
 * right, y up, and the camera looks down -z.  A pinhole camera unless its
 * distortion coefficients are set.
 *
 * The ray of pixel (i, j) (column, row; row 0 at the top) has origin
 * c2w[.][3] (the camera centre) and the unnormalised direction
 * R ((i + 0.5 - cx) / fx, -(j + 0.5 - cy) / fy, -1), R being the left 3x3
 * of c2w: its camera-space z component is -1, so t along the ray is depth
 * along the optical axis.  Without the 0.5 when NERF_CAMERA_PIXEL_CORNER is
 * set.
 *
 * Lens distortion (k1, k2, p1, p2, k3) is OpenCV's (Brown-Conrady) model
 * on normalised image coordinates: each pixel's ray goes through the
 * point the lens shows at that pixel, and images are never resampled
 * (docs/formats.md, "Lens distortion").  COLMAP's SIMPLE_RADIAL, RADIAL
 * and OPENCV models and instant-ngp's k1, k2, p1, p2 (k3) map onto these
 * fields directly.  All zero (the default, and what a caller built
 * against a header without them gets) is a pinhole camera, with the rays
 * above bit for bit.
 *
 * Versioned: fill with nerf_camera_init() (or NERF_CAMERA_INIT), then set
 * the fields.  The defaults (identity pose, all intrinsics 0) are not a
 * usable camera: width, height, fx and fy must be set.
 */
typedef struct nerf_camera {
    uint32_t struct_size; /**< Set by nerf_camera_init(). */
    uint32_t flags;       /**< NERF_CAMERA_*; default 0. */
    uint32_t width;       /**< Image width in pixels, 1..65536. */
    uint32_t height;      /**< Image height in pixels, 1..65536. */
    float c2w[12];        /**< Camera-to-world 3x4, row-major: columns are
                               the camera's right, up and back axes and its
                               centre, in world units.  Default [I | 0]. */
    float fx, fy;         /**< Focal lengths in pixels, > 0.  For a
                               horizontal field of view a:
                               fx = 0.5 width / tan(0.5 a). */
    float cx, cy;         /**< Principal point in pixels from the top-left
                               image corner; usually width/2, height/2. */
    /* Lens distortion: zero-filled by an older caller, a pinhole camera.
     * @since 0.3 */
    float k1, k2;         /**< Radial distortion (r^2, r^4 terms); finite,
                               within +-1000; default 0. */
    float p1, p2;         /**< Tangential distortion; finite, within
                               +-1000; default 0. */
    float k3;             /**< Radial distortion, r^6 term; finite, within
                               +-1000; default 0. */
} nerf_camera;

/**
 * Fill @p camera with defaults and record @p struct_size.
 * @return NERF_OK, or NERF_EINVAL for a NULL or too small struct.
 */
NERF_API int nerf_camera_init(nerf_camera *camera, size_t struct_size);
/** A run-time call, not a constant initializer: see NERF_HOOKS_INIT. */
#define NERF_CAMERA_INIT(c) nerf_camera_init((c), sizeof *(c))

/**
 * Compute the rays of pixels first .. first + n - 1 of @p camera, pixels
 * being numbered row by row (index = row * width + column).
 *
 * @param origins_out    n x 3 floats, world units.
 * @param directions_out n x 3 floats, unnormalised (see nerf_camera):
 *                       their length scales distances when compositing.
 * @return NERF_OK; NERF_EINVAL for NULL pointers, an invalid camera
 * (sizes, non-positive or non-finite focal, non-finite pose, distortion
 * not finite or beyond +-1000) or a pixel range beyond width x height;
 * NERF_EVERSION for a camera struct from a newer header with non-zero
 * unknown fields.
 * Reentrant.
 */
NERF_API int nerf_camera_rays(const nerf_camera *camera, size_t first,
                              size_t n, float *origins_out,
                              float *directions_out);

/**
 * Set the pose of @p camera (its c2w; nothing else) to look from @p eye
 * at @p target, with @p up (world space) pointing up in the image: the
 * camera's -z axis points at the target, its x axis is up x z normalised.
 * @return NERF_OK; NERF_EINVAL for NULL pointers, an uninitialised
 * struct, eye equal to target, or up parallel to the viewing direction.
 * Reentrant.
 */
NERF_API int nerf_camera_look_at(nerf_camera *camera, const float eye[3],
                                 const float target[3], const float up[3]);

/* ===========================================================================
 * 7. Sampler and renderer settings
 * ======================================================================== */

/**
 * Settings of a sampler, fixed at creation.  The defaults are the
 * reference configuration for Blender scenes: 64 + 128 samples for t in
 * [2, 6], linear in depth, jittered in training.
 *
 * Forward-facing (LLFF) scenes: set ndc = 1, t_near = 0 and t_far = 1.
 * Rays are then warped to normalised device coordinates with the near plane
 * at world depth 1 (the frustum given by ndc_focal, ndc_width, ndc_height),
 * and t_near and t_far are NDC depths in [0, 1]: 0 is the near plane, 1
 * infinity.
 */
typedef struct nerf_sampler_options {
    uint32_t struct_size; /**< Set by nerf_sampler_options_init(). */
    uint32_t n_coarse;    /**< Stratified samples per ray, 2..4096;
                               default 64. */
    uint32_t n_fine;      /**< Hierarchical samples per ray, 0..4096
                               (0: coarse pass only; needs n_coarse >= 3
                               otherwise); default 128. */
    uint32_t perturb;     /**< 1: jitter the stratified samples and draw
                               the hierarchical ones at random in training
                               (evaluation is never random); default 1. */
    uint32_t lindisp;     /**< 1: sample linearly in disparity (1/depth)
                               instead of depth; needs t_near > 0;
                               default 0. */
    uint32_t paper_bins;  /**< 1: stratified samples as the paper's eq. 2
                               (one uniform draw in each of n_coarse equal
                               bins; bin centres in evaluation) instead of
                               the reference implementation's evenly spaced
                               values with both ends included; default 0. */
    uint32_t ndc;         /**< 1: warp rays to NDC first; default 0. */
    uint32_t reserved0;   /**< Must be 0. */
    float t_near;         /**< Start of the sampled range of t; default 2. */
    float t_far;          /**< End of the sampled range, > t_near; default 6. */
    float ndc_focal;      /**< NDC frustum: focal length in pixels of the
                               training images; one focal serves both axes,
                               as in the reference.  0 (the default) takes
                               the rendered camera's fx, width and height
                               instead; then only image rendering works. */
    uint32_t ndc_width;   /**< NDC frustum: image width in pixels. */
    uint32_t ndc_height;  /**< NDC frustum: image height in pixels. */
    uint32_t reserved1;   /**< Must be 0. */
    uint64_t seed;        /**< Key of the random streams; default 0. */
    const nerf_hooks *hooks; /**< Allocation and logging; NULL = defaults. */
    /* Ray marching: zero-filled by an older caller, which gives
     * stratified and hierarchical sampling.
     * @since 0.2 */
    uint32_t march_steps; /**< 0 (the default): stratified and
                               hierarchical sampling as above.  N in
                               1..65536: march through the model's
                               occupancy grid (hash-grid models only) in
                               steps of the grid's diagonal / N,
                               skipping empty cells; n_fine, lindisp
                               and paper_bins are then unused, and with
                               ndc the model's space must be NDC
                               (docs/api-notes.md, "Ray marching").
                               NERF_PRESET_FAST sets 1024
                               (instant-ngp's). */
    uint32_t max_samples; /**< With march_steps: at most this many samples
                               per ray, 1..65536; default 1024. */
} nerf_sampler_options;

/**
 * Fill @p opts with the reference sampler settings and record
 * @p struct_size (or use NERF_SAMPLER_OPTIONS_INIT).
 * @return NERF_OK, or NERF_EINVAL for a NULL or too small struct.
 */
NERF_API int nerf_sampler_options_init(nerf_sampler_options *opts,
                                       size_t struct_size);
/** A run-time call, not a constant initializer: see NERF_HOOKS_INIT. */
#define NERF_SAMPLER_OPTIONS_INIT(o) nerf_sampler_options_init((o), sizeof *(o))

/**
 * Set the sample counts of a nerf_preset in an initialised @p opts; other
 * fields are kept.  NERF_PRESET_REFERENCE: 64 + 128 (the paper's).
 * NERF_PRESET_TINY: 32 + 64.  NERF_PRESET_FAST: ray marching, march_steps
 * 1024 and max_samples 1024 (n_coarse 128 and n_fine 0 for a caller that
 * turns marching off); the other presets set march_steps 0.
 * @return NERF_OK; NERF_EINVAL for an unknown preset or a bad struct;
 * NERF_EVERSION as nerf_sampler_create().
 */
NERF_API int nerf_sampler_options_preset(nerf_sampler_options *opts,
                                         int preset);

/**
 * Make a marching @p opts march in @p steps steps of the grid's diagonal,
 * scaling max_samples by the same factor (within 1..65536) so that a ray
 * is marched as far as before: a finer march for rendering, or the
 * training march back from a recorded finer one.  Options that do not
 * march (march_steps 0) are left as they are.
 * @return NERF_OK; NERF_EINVAL for a bad struct or @p steps outside
 * 1..65536.
 * @since 0.12
 */
NERF_API int nerf_sampler_options_set_march(nerf_sampler_options *opts,
                                            uint32_t steps);

/** Sentinel for nerf_renderer_options.raw_noise_std. */
#define NERF_NOISE_AUTO (-1.0f)

/** Settings of a renderer, fixed at creation. */
typedef struct nerf_renderer_options {
    uint32_t struct_size;      /**< Set by nerf_renderer_options_init(). */
    uint32_t white_background; /**< 1: composite onto white (Blender
                                    scenes): rgb += 1 - opacity; default 0
                                    (black). */
    float raw_noise_std;       /**< Standard deviation of the Gaussian
                                    noise added to raw density before the
                                    ReLU, in training only.  Default
                                    NERF_NOISE_AUTO: 1 when the sampler
                                    uses NDC (forward-facing scenes, as the
                                    reference), else 0. */
    uint32_t chunk_rays;       /**< Rays per unit of work handed to a
                                    thread; progress is reported after each
                                    chunk.  Rounded up to a multiple of 64;
                                    1..2^20; default 512.  Neither memory
                                    use nor results depend on it. */
    uint32_t threads;          /**< Worker threads for image and ray
                                    rendering, 0..1024.  0 (the default):
                                    as many as the cores take without
                                    oversubscribing them, at least 1
                                    (docs/threading.md, "How many worker
                                    threads").  Results do not depend on
                                    it. */
    uint32_t appearance;       /**< Which of the model's per-image
                                    appearance codes renders use:
                                    NERF_APPEARANCE_NEUTRAL (0, the
                                    default: the mean of the codes), or
                                    NERF_APPEARANCE_OF(i), training image
                                    i's.  Nothing changes for a model
                                    without codes, which takes only
                                    NERF_APPEARANCE_NEUTRAL.  Was
                                    reserved0 before 0.13.
                                    @since 0.13 */
    const nerf_hooks *hooks;   /**< Allocation and logging; NULL =
                                    defaults. */
} nerf_renderer_options;

/**
 * Fill @p opts with defaults and record @p struct_size (or use
 * NERF_RENDERER_OPTIONS_INIT).
 * @return NERF_OK, or NERF_EINVAL for a NULL or too small struct.
 */
NERF_API int nerf_renderer_options_init(nerf_renderer_options *opts,
                                        size_t struct_size);
/** A run-time call, not a constant initializer: see NERF_HOOKS_INIT. */
#define NERF_RENDERER_OPTIONS_INIT(o) \
    nerf_renderer_options_init((o), sizeof *(o))

/* ===========================================================================
 * 8. Model
 * ======================================================================== */

/** Kinds of input encoding. */
typedef enum nerf_encoding_kind {
    NERF_ENCODING_FREQUENCY = 1,  /**< Sinusoidal positional encoding. */
    NERF_ENCODING_HASHGRID = 2,   /**< Multiresolution hash grid (positions
                                       only; its tables are trained).  The model
                                       then also owns an occupancy grid (128^3
                                       cells over the bound) for ray-marching
                                       samplers.
                                       @since 0.2 */
    NERF_ENCODING_SPHERICAL_HARMONICS = 3 /**< Real spherical harmonics
                                       (directions only).
                                       @since 0.2 */
} nerf_encoding_kind;

/** Activation turning the network's density output into sigma.  @since 0.2 */
typedef enum nerf_density_activation {
    NERF_DENSITY_RELU = 0, /**< The paper's: ReLU, applied when rendering. */
    NERF_DENSITY_EXP = 1   /**< exp, truncated at exp(15) (hash-grid
                                models). */
} nerf_density_activation;

/** Flags for nerf_model_options.encoding_flags. */
#define NERF_ENCODING_INCLUDE_INPUT 0x1u /**< Prepend the raw input. */
#define NERF_ENCODING_SCALE_PI 0x2u      /**< Frequencies 2^k pi, not 2^k. */

/** Named configurations for nerf_model_options_preset(). */
typedef enum nerf_preset {
    NERF_PRESET_REFERENCE = 1, /**< The paper's networks (the default). */
    NERF_PRESET_TINY = 2,      /**< Small and fast, for trials and tests. */
    NERF_PRESET_FAST = 3       /**< Hash-grid encoding and small MLPs (Mueller
                                    et al. 2022), one network.
                                    @since 0.2 */
} nerf_preset;

/**
 * How a model computes its matrix products (nerf_model_options.matmul).
 * Either way the weights, their gradients, the optimiser state and
 * checkpoints are fp32: the choice changes the arithmetic of the
 * products, never what is stored.
 * @since 0.2
 */
typedef enum nerf_matmul {
    NERF_MATMUL_FP32 = 0, /**< fp32 through cblas_sgemm (the default). */
    NERF_MATMUL_BF16 = 1, /**< Both operands of every layer product rounded
                               to bfloat16 (nearest even), products summed
                               in fp32; bias and ReLU fused into the
                               product.  Through oneDNN, on CPUs with
                               AVX512-BF16: ask nerf_matmul_supported()
                               first.  Faster than fp32 on wide layers
                               (docs/performance.md); results differ
                               from fp32 by the rounding (relative
                               errors of order 1e-3). */
    NERF_MATMUL_FP32_ONEDNN = 2, /**< fp32 products, bias and ReLU fused into
                               them, through oneDNN's matmul instead of
                               cblas_sgemm.  Needs a libnerf built with oneDNN:
                               ask nerf_matmul_supported() first.  Results
                               differ from FP32 by the order of the sums
                               only.  When it pays, and its determinism:
                               docs/api-notes.md, "fp32 products through
                               oneDNN".
                               @since 0.7 */
    NERF_MATMUL_FP32_FASTEST = 3 /**< Whichever fp32 kind trains the model
                               fastest here, chosen by nerf_model_create():
                               FP32_ONEDNN for a frequency-encoded model
                               where nerf_matmul_supported() says it is
                               available, else FP32 (a hash-grid model's
                               narrow layers run fastest on libnerf's own
                               kernels, which FP32 uses).  The model
                               records and reports the kind chosen, never
                               this one.  nerf-train's default.
                               @since 0.12 */
} nerf_matmul;

/**
 * Where a hash-grid model's grids lie (nerf_model_options.space).
 * The frequency encoding of the reference networks reads coordinates
 * anywhere and takes BOX (its only value) whatever the scene.
 * @since 0.3
 */
typedef enum nerf_space {
    NERF_SPACE_BOX = 0,      /**< The cube [-bound, bound]^3 of world space;
                                  nothing outside it (Blender scenes). */
    NERF_SPACE_NDC = 1,      /**< Forward-facing scenes: the grids lie over
                                  normalised device coordinates, x and y in
                                  [-bound, bound], z (NDC depth) in
                                  [-1, 1].  Needs a sampler with ndc = 1,
                                  which warps the rays first. */
    NERF_SPACE_UNBOUNDED = 2 /**< 360-degree captures with a far
                                  background: the cube [-bound, bound]^3 as
                                  it is, and all of space outside it
                                  contracted into [-2 bound, 2 bound]^3
                                  (mip-NeRF 360's contraction in the
                                  max-norm, docs/formats.md).  Marching
                                  spaces samples evenly in the contracted
                                  space, so the far field costs few. */
} nerf_space;

/**
 * Whether models of nerf_matmul @p kind can be created here: 1 or 0.
 * NERF_MATMUL_FP32 is always available.  NERF_MATMUL_BF16 needs a libnerf
 * built with oneDNN (meson option bf16) and a CPU on which oneDNN runs
 * bf16 natively (AVX512-BF16; the environment variable DNNL_MAX_CPU_ISA
 * can hide it).  NERF_MATMUL_FP32_ONEDNN needs a libnerf built with
 * oneDNN and a CPU on which oneDNN runs its brgemm fp32 kernels (AVX-512;
 * DNNL_MAX_CPU_ISA can hide it).  Unknown kinds give 0.
 *
 * The first call for a oneDNN kind creates small oneDNN primitives to
 * find out, which is slower than an ordinary query; later calls return
 * the stored answer.
 * Thread-safe.  Symbol version NERF_0.2.
 * @since 0.2
 */
NERF_API int nerf_matmul_supported(int kind);

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
    uint32_t pos_frequencies; /**< L for positions; default 10, 0 = raw
                                   input only. */
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
    uint64_t seed;            /**< Seed of initialisation and training;
                                   default 0. */
    const nerf_hooks *hooks;  /**< Allocation and logging; NULL = defaults. */
    /* The hash-grid model: zero-filled by an older caller, which gives
     * the reference behaviour.
     * @since 0.2 */
    uint32_t dir_encoding;    /**< nerf_encoding_kind of the view
                                   direction: FREQUENCY (the default; 0
                                   reads as FREQUENCY) or
                                   SPHERICAL_HARMONICS. */
    uint32_t sh_degree;       /**< Bands of the direction harmonics, 1..4
                                   (degree^2 values); default 4. */
    uint32_t hash_levels;     /**< Hash-grid levels, 1..32; default 16. */
    uint32_t hash_features;   /**< Features per level, 1..8; default 2. */
    uint32_t hash_log2_size;  /**< log2 of entries per level, 10..24;
                                   default 19. */
    uint32_t hash_min_resolution; /**< Coarsest cells across the grid's
                                   whole domain (which follows bound
                                   and space); default 16. */
    uint32_t hash_max_resolution; /**< Finest cells across the same
                                   domain (>= min); default 2048
                                   (the fast preset: 1024), whatever
                                   the bound. */
    float bound;              /**< The hash grid covers [-bound, bound]^3;
                                   default 1.5 (Blender scenes). */
    uint32_t geo_features;    /**< 0 (default): the reference head, a
                                   width-wide feature plus sigma.  G > 0:
                                   the head has G outputs, the first being
                                   the density, and all G feed the colour
                                   branch. */
    uint32_t view_depth;      /**< Layers of the colour branch before the
                                   rgb layer, 1..8; default 1. */
    uint32_t density_activation; /**< nerf_density_activation; default
                                   RELU. */
    /* Formerly reserved1, which had to be 0: old callers get fp32. */
    uint32_t matmul;          /**< nerf_matmul: how the products are
                                   computed; default NERF_MATMUL_FP32.
                                   A kind for which
                                   nerf_matmul_supported() says 0 makes
                                   nerf_model_create() fail with
                                   NERF_EINVAL.  Saved in checkpoints. */
    /* Zero-filled by an older caller: BOX, as before.
     * @since 0.3 */
    uint32_t space;           /**< nerf_space of a hash-grid model; default
                                   BOX.  Saved in checkpoints. */
    /* Zero-filled by an older caller: the learning rate of the model's
     * kind, as before.
     * @since 0.12 */
    uint32_t reserved2;       /**< Must be 0. */
    double learning_rate;     /**< The schedule's first learning rate
                                   (NERF_PARAM_LEARNING_RATE), its last a
                                   tenth of it, in (0, 1].  0 (default):
                                   the model kind's, 5e-4 (the paper's)
                                   for frequency encodings and 1e-2 for
                                   hash grids.  nerf_model_options_preset()
                                   sets its preset's. */
} nerf_model_options;

/**
 * Fill @p opts with the reference configuration and record @p struct_size
 * (pass sizeof *opts, or use NERF_MODEL_OPTIONS_INIT).
 * @return NERF_OK, or NERF_EINVAL for a NULL or too small struct.
 */
NERF_API int nerf_model_options_init(nerf_model_options *opts,
                                     size_t struct_size);
/** A run-time call, not a constant initializer: see NERF_HOOKS_INIT. */
#define NERF_MODEL_OPTIONS_INIT(o) nerf_model_options_init((o), sizeof *(o))

/**
 * Overwrite the structural fields of an initialised @p opts with a named
 * preset, and its learning rate (since 0.12: 5e-4 for
 * NERF_PRESET_REFERENCE, 5e-3 for NERF_PRESET_TINY, 1e-2 for
 * NERF_PRESET_FAST, those nerf-train trains them with); seed, hooks and
 * matmul are kept.
 * @return NERF_OK, or NERF_EINVAL for an unknown preset or bad struct.
 */
NERF_API int nerf_model_options_preset(nerf_model_options *opts,
                                       int preset);

/**
 * Create a model with freshly initialised weights (deterministic for a given
 * seed; see docs/architecture.md for the scheme).
 * @return NERF_OK; NERF_EINVAL for out-of-range options, or for
 * a matmul kind for which nerf_matmul_supported() says 0 (the message
 * says why); NERF_EVERSION for an options struct from a newer header with
 * non-zero unknown fields; NERF_ENOMEM.
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
    NERF_PARAM_LEARNING_RATE = 100,       /**< Initial rate; default
                                               nerf_model_options'
                                               learning_rate, else 5e-4
                                               (1e-2 for hash grids). */
    NERF_PARAM_LEARNING_RATE_FINAL = 101, /**< Rate reached after
                                               DECAY_STEPS; default a
                                               tenth of the initial. */
    NERF_PARAM_DECAY_STEPS = 102,         /**< Default 250000: lr(t) =
                                               lr0 (lr1/lr0)^(t/steps). */
    /** Default 0.9.  Adam's bias corrections go by the step count, but
     * for a hash table's parameters by each one's own count of updates,
     * as Mueller et al.'s: a step leaves the parameters it did not touch,
     * moments and corrections included, as they were.  A model resumed
     * from a checkpoint of an older libnerf goes on by the step, as it
     * was trained.
     * @since 0.10 for the hash tables' own counts */
    NERF_PARAM_ADAM_BETA1 = 103,
    NERF_PARAM_ADAM_BETA2 = 104,          /**< Default 0.999; 0.99 for
                                               hash-grid models. */
    NERF_PARAM_ADAM_EPS = 105,            /**< Default 1e-7 (the paper's);
                                               1e-15 for hash-grid models
                                               (Mueller et al.'s). */
    /** L2 penalty on the network layers (not on a hash table):
     * weight_decay * w is added to each layer parameter's gradient.
     * Default 0; 1e-6 for hash-grid models, as Mueller et al. train
     * them.
     * @since 0.2 */
    NERF_PARAM_WEIGHT_DECAY = 106,
    /** The rate holds at LEARNING_RATE until this step, then decays
     * exponentially to LEARNING_RATE_FINAL at DECAY_STEPS:
     * lr(t) = lr0 (lr1/lr0)^((t - start) / (steps - start)) for t > start.
     * Default 0 (the paper's schedule).  nerf_trainer_run_for() sets it
     * to the step where it fits the schedule to its time budget.
     * @since 0.5 */
    NERF_PARAM_DECAY_START = 107,
    /** Over this many last steps up to DECAY_STEPS the model keeps an
     * exponential moving average of its weights, which the step that
     * reaches DECAY_STEPS makes the weights (docs/api-notes.md, "Weight
     * averaging").  Default 0 (off; the paper's models); 100 for
     * hash-grid models.  A checkpoint from before 0.9 resumes with 0.
     * @since 0.9 */
    NERF_PARAM_AVERAGE_STEPS = 108
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

/** What a model's learning-rate schedule is (nerf_schedule).  @since 0.5 */
typedef enum nerf_schedule_state {
    /** Set by its parameters alone: a decay over DECAY_STEPS (from
     * DECAY_START), as nerf-train --steps sets it. */
    NERF_SCHEDULE_STEPS = 0,
    /** nerf_trainer_run_for() is measuring the step rate, the rate held
     * at LEARNING_RATE, and has not fixed the run's length yet (a model
     * saved then resumes by measuring again). */
    NERF_SCHEDULE_MEASURING = 1,
    /** nerf_trainer_run_for() fixed the run's length: the schedule decays
     * from fit_step to total_steps, and training to total_steps is
     * deterministic and resumes bit for bit like a --steps run. */
    NERF_SCHEDULE_FITTED = 2
} nerf_schedule_state;

/**
 * How a model's schedule came about; saved in checkpoints.
 * Versioned: set struct_size (sizeof) before passing it.
 * @since 0.5
 */
typedef struct nerf_schedule {
    uint32_t struct_size;    /**< Set by the caller. */
    uint32_t state;          /**< A nerf_schedule_state. */
    double budget_seconds;   /**< The time budget the schedule was (or is
                                  being) fitted to; 0 for STEPS. */
    double steps_per_second; /**< FITTED: the step rate the length was
                                  last fitted to; else 0. */
    uint64_t fit_step;       /**< FITTED: the step at which the length was
                                  first fixed (DECAY_START); else 0. */
    uint64_t total_steps;    /**< FITTED: the run's length (DECAY_STEPS):
                                  where nerf_trainer_run_for() stops;
                                  STEPS: DECAY_STEPS; MEASURING: 0. */
} nerf_schedule;

/**
 * Fill @p out with the model's schedule.
 * @return NERF_OK, or NERF_EINVAL for a NULL argument or a struct_size
 * too small for struct_size and state.
 * @since 0.5
 */
NERF_API int nerf_model_schedule(const nerf_model *model, nerf_schedule *out);

/**
 * Save the model, its optimiser state and training step to @p path in
 * libnerf's checkpoint format (docs/formats.md).  The file is written to a
 * temporary name beside @p path, flushed and renamed, so an existing file at
 * @p path is replaced only by a complete checkpoint.  A model whose
 * weights are not finite (NERF_MODEL_HAS_NONFINITE_WEIGHTS) is not saved:
 * no call could use the file, and a run that diverged would replace its
 * last good checkpoint with it.
 * @return NERF_OK; NERF_EINVAL (a NULL argument, weights not finite);
 * NERF_EIO; NERF_ENOMEM.
 */
NERF_API int nerf_model_save(const nerf_model *model, const char *path);

/**
 * Load a checkpoint written by nerf_model_save().  The model computes as it
 * was saved (nerf_model_options.matmul), except that a model saved with
 * oneDNN products (bf16 or FP32_ONEDNN) loads computing in fp32 through
 * cblas where nerf_matmul_supported() says its kind is not available:
 * its weights are fp32 either way, and a warning goes to the log.
 * Parameter values are not checked against the file: a checkpoint of a
 * run that diverged (weights NaN or infinite) loads, with a warning in
 * the log naming the file, how many weights are not finite and where the
 * first is, so that it can be inspected (nerf_model_query());
 * nerf_model_contents() has NERF_MODEL_HAS_NONFINITE_WEIGHTS, and the
 * calls that would make something of it refuse it with NERF_EINVAL:
 * nerf_renderer_create() and the render calls, nerf_trainer_create(),
 * nerf_mesh_extract(), nerf_density_grid_write(), nerf_model_save() and
 * nerf_model_export().
 * @param hooks allocation and logging for the new model; NULL = defaults.
 * @return NERF_OK; NERF_ENOENT (no such file); NERF_EUNRECOGNISED (not a
 * checkpoint, or not a regular file: a folder, a FIFO, a device, refused
 * without blocking); NERF_EIO (cannot open or read);
 * NERF_EFORMAT (truncated or corrupted checkpoint); NERF_EVERSION
 * (written by a newer libnerf); NERF_ENOMEM; NERF_EINVAL.
 */
NERF_API int nerf_model_load(nerf_model **out, const char *path,
                             const nerf_hooks *hooks);

/**
 * Save the model like nerf_model_save() but without the Adam
 * moments, which hold twice as many floats as the weights: the weights,
 * the options, the step, the occupancy grid and the render settings
 * (nerf_model_render_settings()), all a render or an evaluation needs.
 * nerf_model_load() reads it like a checkpoint; the model it gives has no
 * optimiser state (nerf_model_contents() lacks NERF_MODEL_HAS_OPTIMIZER),
 * nerf_trainer_create() refuses it, and nerf_model_save() of it writes a
 * weights-only file again.  libnerf before 0.4 refuses the file with
 * NERF_EVERSION.
 * @return as nerf_model_save().
 * @since 0.4
 */
NERF_API int nerf_model_export(const nerf_model *model, const char *path);

/**
 * Create a model with @p opts and fill its weights from a NumPy .npz file
 * holding the state dict of the reference implementation, with names
 * prefixed by network: "coarse.pts_linears.0.weight" ... and "fine." ones
 * (see docs/formats.md).  Optimiser state starts at zero.
 * @return NERF_OK; NERF_ENOENT (no such file); NERF_EUNRECOGNISED (not a
 * regular file: a folder, a FIFO, a device); NERF_EIO; NERF_EFORMAT (not
 * an npz, bad member, missing
 * name, shape that does not match @p opts); NERF_EINVAL; NERF_ENOMEM.
 */
NERF_API int nerf_model_import_npz(nerf_model **out, const char *path,
                                   const nerf_model_options *opts);

/** Bits of nerf_model_contents().  @since 0.4 */
#define NERF_MODEL_HAS_OPTIMIZER 0x1u /**< The Adam moments: training can
                                           resume (every model but one
                                           loaded from a weights-only
                                           export). */
#define NERF_MODEL_HAS_OCCUPANCY 0x2u /**< An occupancy grid that training
                                           has updated (hash-grid models). */
#define NERF_MODEL_HAS_RENDER_SETTINGS 0x4u /**< Render settings recorded
                                           by a trainer or
                                           nerf_model_set_render_settings(),
                                           kept by checkpoints. */
#define NERF_MODEL_HAS_DATA_RECORD 0x8u /**< What data a trainer last
                                           trained the model on
                                           (nerf_model_training_data()),
                                           kept by checkpoints. */
#define NERF_MODEL_HAS_BATCH_RECORD 0x10u /**< The batch a trainer last trained
                                           the model with
                                           (nerf_model_training_batch()), kept
                                           by checkpoints.
                                           @since 0.8 */
#define NERF_MODEL_HAS_ADAM_CORRECTIONS 0x20u /**< Each hash-table parameter's
                                           Adam corrections by its own count of
                                           updates (hash-grid models), kept by
                                           checkpoints.  A hash-grid model
                                           loaded with the moments but without
                                           them, from an older libnerf's file,
                                           corrects by the step, as it was
                                           trained.
                                           @since 0.10 */
#define NERF_MODEL_HAS_NONFINITE_WEIGHTS 0x40u /**< Weights that are NaN or
                                           infinite, as a run that diverged
                                           leaves them: the model can be
                                           queried, and nothing else takes it
                                           (see nerf_model_load()).
                                           @since 0.11 */
#define NERF_MODEL_HAS_APPEARANCE 0x80u /**< Per-image appearance codes
                                           (nerf_trainer_options.
                                           appearance_codes), kept by
                                           checkpoints and exports.
                                           @since 0.13 */

/**
 * What @p model holds beyond its weights, NERF_MODEL_HAS_*
 * bits; 0 for NULL.  For a loaded model, which of these its file held.
 * NERF_MODEL_HAS_NONFINITE_WEIGHTS is found by a pass over the weights
 * after they last changed (a training step, a load).
 * @since 0.4
 */
NERF_API uint32_t nerf_model_contents(const nerf_model *model);

/** nerf_renderer_options.appearance and nerf_model_appearance_code():
 * the neutral appearance, the mean of a model's codes (the training
 * photos' average look).  @since 0.13 */
#define NERF_APPEARANCE_NEUTRAL 0u
/** The same for training image @p i's own appearance.  @since 0.13 */
#define NERF_APPEARANCE_OF(i) ((uint32_t)(i) + 1u)
/** Floats of one appearance code: the natural logarithms of the gains
 * of red, green and blue, mapping a colour c to (e^l0 c0, e^l1 c1,
 * e^l2 c2).  @since 0.13 */
#define NERF_APPEARANCE_CODE_FLOATS 3u

/**
 * How many per-image appearance codes @p model holds, into @p count: the
 * training images of the trainer that added them
 * (nerf_trainer_options.appearance_codes), 0 for a model without.  What
 * they are and how renders use them: docs/api-notes.md, "Photos whose
 * exposure differs".
 * @return NERF_OK, or NERF_EINVAL (a NULL argument).
 * @since 0.13
 */
NERF_API int nerf_model_appearance_count(const nerf_model *model,
                                         uint32_t *count);

/**
 * The appearance code @p which (NERF_APPEARANCE_NEUTRAL, or
 * NERF_APPEARANCE_OF(i) for training image i) of @p model into
 * @p code[NERF_APPEARANCE_CODE_FLOATS].  A model without codes has only
 * the neutral one, all zeros (gains of 1).
 * @return NERF_OK, or NERF_EINVAL (a NULL argument, an image beyond the
 * model's codes).
 * @since 0.13
 */
NERF_API int nerf_model_appearance_code(const nerf_model *model,
                                        uint32_t which, float *code);

/**
 * A one-line description of the data @p model was last trained
 * on, as its trainer recorded it: image count and size, the files' size
 * when downscaled, the scene's format, NDC, mean colour and bounds ("100
 * images of 100x100 from 800x800 files (blender, mean colour 0.85 0.83
 * 0.80, near 2 far 6)"), into @p buf (at most @p size bytes with the
 * terminating NUL; truncated to fit).  An empty string when nothing is
 * recorded (nerf_model_contents() lacks NERF_MODEL_HAS_DATA_RECORD).
 * nerf_trainer_create() warns when it is given data unlike this record.
 * @return NERF_OK, or NERF_EINVAL (NULL model or buffer, size 0).
 * @since 0.4
 */
NERF_API int nerf_model_training_data(const nerf_model *model, char *buf,
                                      size_t size);

/**
 * The batch @p model was last trained with, as its trainer
 * recorded it: nerf_trainer_options.batch_rays into @p rays and
 * batch_samples into @p samples.  Both 0 when nothing is recorded
 * (nerf_model_contents() lacks NERF_MODEL_HAS_BATCH_RECORD: a model never
 * trained, or a checkpoint of libnerf before 0.8).  A run resumed from a
 * checkpoint goes on bit for bit as the unbroken run only with the batch
 * it began with, so a caller that resumes takes this one;
 * nerf_trainer_create() warns when a model that has taken steps is given
 * another.
 * @return NERF_OK, or NERF_EINVAL (a NULL argument).
 * @since 0.8
 */
NERF_API int nerf_model_training_batch(const nerf_model *model,
                                       uint32_t *rays, uint32_t *samples);

/**
 * Record what rendering @p model needs: the sampling fields of
 * @p sampler (counts, marching, t_near and t_far, ndc and its frustum,
 * lindisp, paper_bins; not seed, perturb or hooks) and whether renders
 * are composited on white (@p white_background 1) or black (0).
 * nerf_trainer_create() records those it trains with, and checkpoints keep
 * them (docs/formats.md), so that nerf_model_render_settings() gives them
 * back to a caller who knows nothing of the scene.
 * @return NERF_OK; NERF_EINVAL (NULL argument, options nerf_sampler_create()
 * would refuse, white_background not 0 or 1); NERF_EVERSION as
 * nerf_sampler_create().
 * @since 0.4
 */
NERF_API int nerf_model_set_render_settings(nerf_model *model,
                                            const nerf_sampler_options *sampler,
                                            uint32_t white_background);

/**
 * The settings to render @p model with.  Either output may be
 * NULL; each must be initialised (its struct_size set).  Into @p sampler go
 * the fields nerf_model_set_render_settings() lists; its seed, perturb
 * and hooks are kept.  Into @p renderer goes white_background; its other
 * fields are kept.
 *
 * A model without recorded settings (nerf_model_contents() lacks
 * NERF_MODEL_HAS_RENDER_SETTINGS: created and never trained, or loaded from
 * a file of libnerf before 0.4) gets those its shape suggests
 * (docs/api-notes.md, "Render settings a model suggests").
 * @return NERF_OK; NERF_EINVAL (NULL model, both outputs NULL, bad
 * struct); NERF_EFORMAT (recorded settings that no sampler accepts: a
 * forged file).
 * @since 0.4
 */
NERF_API int nerf_model_render_settings(const nerf_model *model,
                                        nerf_sampler_options *sampler,
                                        nerf_renderer_options *renderer);

/* ===========================================================================
 * 9. Sampler
 * ======================================================================== */

/**
 * Create a sampler.  @p opts is copied; NULL means the defaults.
 * @return NERF_OK; NERF_EINVAL for out-of-range options (counts, t_near >=
 * t_far, non-finite or negative t, lindisp with t_near = 0, NDC depths
 * beyond 1, a partly set NDC frustum, non-zero reserved fields);
 * NERF_EVERSION for a struct from a newer header with non-zero unknown
 * fields; NERF_ENOMEM.
 *
 * A sampler is immutable: any number of threads and renderers may use one
 * sampler at the same time.
 */
NERF_API int nerf_sampler_create(nerf_sampler **out,
                                 const nerf_sampler_options *opts);

/** Release a sampler.  NULL is a no-op.  No renderer may still use it. */
NERF_API void nerf_sampler_destroy(nerf_sampler *sampler);

/** Flags of the sampling and rendering calls. */
#define NERF_SAMPLE_TRAINING 0x1u /**< Random placement as in training (if
                                       the sampler's perturb is set). */

/**
 * Stratified (coarse) sample depths for @p n_rays rays.  They do not
 * depend on the rays themselves: values of t in the sampler's
 * [t_near, t_far] (NDC depths with ndc set).
 *
 * @param flags     0 for evaluation (deterministic), or
 *                  NERF_SAMPLE_TRAINING.
 * @param first_ray index of the first ray in the random streams: ray k
 *                  draws from the stream (seed, first_ray + k), so a batch
 *                  split in parts gives the same values.
 * @param u         NULL, or n_rays x n_coarse uniforms in [0, 1) to use
 *                  instead of the library's generator when training (to
 *                  compare with another implementation on identical
 *                  draws).
 * @param t_out     n_rays x n_coarse floats, increasing along each ray.
 * @return NERF_OK or NERF_EINVAL (NULL sampler or t_out).  Reentrant.
 */
NERF_API int nerf_sampler_sample_coarse(const nerf_sampler *sampler,
                                        size_t n_rays, uint32_t flags,
                                        uint64_t first_ray, const float *u,
                                        float *t_out);

/**
 * Hierarchical (fine) samples: n_fine depths drawn by inverse transform
 * from the piecewise-constant density the coarse weights define over the
 * intervals between midpoints of @p t_coarse (weights without the first
 * and last, plus 1e-5), merged with the coarse depths.
 *
 * @param t_coarse  n_rays x n_coarse increasing depths.
 * @param weights   n_rays x n_coarse compositing weights of those samples.
 * @param flags     0: evenly spaced u (evaluation); NERF_SAMPLE_TRAINING:
 *                  uniform random u when the sampler's perturb is set.
 * @param first_ray first ray's stream index, as for the coarse call.
 * @param u         NULL, or n_rays x n_fine uniforms in [0, 1] replacing
 *                  the generator's when training.
 * @param t_out     n_rays x (n_coarse + n_fine) floats: the sorted union of
 *                  coarse and fine depths.
 * @return NERF_OK; NERF_EINVAL (NULL arguments, or a sampler with
 * n_fine = 0).  Reentrant.
 */
NERF_API int nerf_sampler_sample_fine(const nerf_sampler *sampler,
                                      size_t n_rays, uint32_t flags,
                                      uint64_t first_ray,
                                      const float *t_coarse,
                                      const float *weights, const float *u,
                                      float *t_out);

/* ===========================================================================
 * 10. Renderer
 * ======================================================================== */

/**
 * Create a renderer that draws @p model with the samples of @p sampler.
 * @p opts is copied; NULL means the defaults.
 *
 * @p sampler may be NULL: the renderer then makes (and owns) a
 * sampler from the model's render settings (nerf_model_render_settings():
 * those its trainer recorded, else those its shape suggests), and when
 * @p opts is NULL too, it composites on the model's background as well,
 * so that nerf_renderer_create(&r, model, NULL, NULL) renders a model as
 * it was trained without the caller knowing its preset or scene.
 *
 * The renderer references @p model and a given @p sampler without owning
 * them: both must outlive it.  It reads the model's current weights at
 * every call, so training between renders is seen.  One model and one
 * sampler may serve several renderers.
 *
 * @return NERF_OK; NERF_EINVAL (NULL model, out-of-range
 * options, a marching sampler with a model that has no occupancy grid,
 * weights that are not finite: NERF_MODEL_HAS_NONFINITE_WEIGHTS; each
 * render call refuses them too, should training since have made them
 * so); with a NULL sampler, NERF_EFORMAT for recorded settings no sampler
 * accepts (a forged file), as nerf_model_render_settings();
 * NERF_EVERSION for an options struct from a newer header with non-zero
 * unknown fields; NERF_ENOMEM.
 * @since 0.4 for a NULL @p sampler
 */
NERF_API int nerf_renderer_create(nerf_renderer **out,
                                  const nerf_model *model,
                                  const nerf_sampler *sampler,
                                  const nerf_renderer_options *opts);

/** Release a renderer (not its model or sampler).  NULL is a no-op. */
NERF_API void nerf_renderer_destroy(nerf_renderer *renderer);

/**
 * Set (or with NULL clear) the progress callback of later render calls.
 * It is called on the calling thread after every chunk of rays.
 * @return NERF_OK, or NERF_EINVAL for a NULL renderer.
 */
NERF_API int nerf_renderer_set_progress(nerf_renderer *renderer,
                                        nerf_progress_cb cb, void *user);

/**
 * Ask the render call running on @p renderer to stop; it returns
 * NERF_ECANCELLED once its threads finish the batch of 64 rays they are
 * on.  Thread-safe: this is the one function that may be called while
 * another thread is inside a call on the same renderer (including from its
 * progress callback).  Each render call
 * clears the request when it starts, so a cancel that arrives when no call
 * is running has no effect.  NULL is a no-op.
 */
NERF_API void nerf_renderer_cancel(nerf_renderer *renderer);

/**
 * Render every pixel of @p camera (evaluation: no randomness) into the
 * caller's buffers, row by row from the top-left pixel.
 *
 * Work is split into chunks of rays spread over the renderer's threads;
 * memory use is bounded by the thread count, not the image size.
 * The output is bitwise identical for every chunk size and thread count.
 *
 * @param rgb_out        height x width x 3 floats; colours, 0..1 for a
 *                       trained model.  May be NULL.
 * @param depth_out      height x width floats: the expected depth
 *                       sum(w t), in units of t along the unnormalised
 *                       ray (depth along the optical axis for
 *                       nerf_camera rays; NDC depth in NDC), not divided
 *                       by opacity.  May be NULL.
 * @param opacity_out    height x width floats, sum(w) in [0, 1] up to
 *                       float rounding (1 + 1e-7 can occur).  May be
 *                       NULL.
 * @param pixel_capacity pixels each non-NULL buffer can hold; at least
 *                       width x height.
 * @return NERF_OK; NERF_EINVAL (NULL renderer or camera, invalid camera,
 * all outputs NULL, capacity too small); NERF_EVERSION for a camera
 * struct from a newer header with non-zero unknown fields; NERF_ENOMEM;
 * NERF_ECANCELLED (nerf_renderer_cancel() or the progress callback; the
 * buffers then hold a partial image).
 *
 * Not reentrant for one renderer: use one renderer per calling thread.
 */
NERF_API int nerf_renderer_render_image(nerf_renderer *renderer,
                                        const nerf_camera *camera,
                                        float *rgb_out, float *depth_out,
                                        float *opacity_out,
                                        size_t pixel_capacity);

/**
 * As nerf_renderer_render_image(), with the colours converted to 8 bits:
 * round(255 clamp(c, 0, 1)).
 * @param rgb_out height x width x 3 bytes (RGB).  Must not be NULL.
 * @return as nerf_renderer_render_image().
 */
NERF_API int nerf_renderer_render_image_u8(nerf_renderer *renderer,
                                           const nerf_camera *camera,
                                           uint8_t *rgb_out,
                                           float *depth_out,
                                           float *opacity_out,
                                           size_t pixel_capacity);

/**
 * Render every pixel of @p camera as nerf_renderer_render_image()
 * does, with the depth in world units instead of the raw sum(w t).
 *
 * Both depths are those of the point o + s d where the ray is expected to
 * stop, given that it stops in the scene: s = sum(w t) / sum(w), the raw
 * depth divided by the opacity, along the camera's unnormalised ray d.
 * With an NDC sampler they are world units too, and an expected NDC depth
 * of 1 or more (the point at infinity) gives +inf (docs/api-notes.md,
 * "Depth in world units").
 *
 * @param rgb_out        height x width x 3 floats, as
 *                       nerf_renderer_render_image(); may be NULL.
 * @param distance_out   height x width floats: s |d|, the distance in
 *                       world units from the camera centre (the ray's
 *                       origin) to the point, along the ray; 0 where the
 *                       opacity is 0.  May be NULL.
 * @param zdepth_out     height x width floats: s, the point's depth along
 *                       the camera's optical axis (minus its camera-space
 *                       z), in world units; 0 where the opacity is 0.  May
 *                       be NULL.
 * @param opacity_out    height x width floats, sum(w), as
 *                       nerf_renderer_render_image(); may be NULL.
 * @param pixel_capacity pixels each non-NULL buffer can hold.
 * @return as nerf_renderer_render_image() (NERF_EINVAL when every output
 * is NULL); NERF_ENOMEM.
 * Not reentrant for one renderer.
 * @since 0.5
 */
NERF_API int nerf_renderer_render_depth(nerf_renderer *renderer,
                                        const nerf_camera *camera,
                                        float *rgb_out, float *distance_out,
                                        float *zdepth_out,
                                        float *opacity_out,
                                        size_t pixel_capacity);

/**
 * Render a caller's batch of rays (evaluation: no randomness), chunked and
 * threaded as images are.
 *
 * @param origins     n_rays x 3 floats, world units.
 * @param directions  n_rays x 3 floats, unnormalised: samples lie at
 *                    o + t d and distances are scaled by |d|, which must
 *                    be > 0.
 * @param rgb_out     n_rays x 3 floats, or NULL.
 * @param depth_out   n_rays floats, sum(w t), or NULL.
 * @param opacity_out n_rays floats, or NULL.
 * @return NERF_OK; NERF_EINVAL (NULL inputs, all outputs NULL, NDC sampler
 * without ndc_focal/ndc_width/ndc_height); NERF_ENOMEM; NERF_ECANCELLED.
 */
NERF_API int nerf_renderer_render_rays(nerf_renderer *renderer,
                                       size_t n_rays, const float *origins,
                                       const float *directions,
                                       float *rgb_out, float *depth_out,
                                       float *opacity_out);

/* ===========================================================================
 * 11. Datasets and camera paths
 * ======================================================================== */

/** Which part of a scene to load. */
typedef enum nerf_split {
    NERF_SPLIT_TRAIN = 0,
    NERF_SPLIT_VAL = 1,
    NERF_SPLIT_TEST = 2
} nerf_split;

/** The layout a dataset was loaded from, as nerf_dataset_get_format() says. */
typedef enum nerf_dataset_format {
    NERF_DATASET_BLENDER = 1, /**< transforms_<split>.json or
                                   transforms.json. */
    NERF_DATASET_LLFF = 2,    /**< poses_bounds.npy and images folders. */
    NERF_DATASET_COLMAP = 3   /**< A COLMAP sparse model (sparse/0/ or
                                   sparse/) beside images folders. */
} nerf_dataset_format;

/** How nerf_dataset_load() reads a scene. */
typedef struct nerf_dataset_options {
    uint32_t struct_size;      /**< Set by nerf_dataset_options_init(). */
    uint32_t split;            /**< nerf_split; default TRAIN. */
    uint32_t downscale;        /**< Integer factor K, 1..256; default 1.
                                    Blender: each K x K block of the
                                    composited image is averaged and the
                                    intrinsics are divided by K.  LLFF
                                    and COLMAP: reads images_K/ if present, else
                                    images_M/ (images/ for M = 1) for the
                                    largest M dividing K, averaged in
                                    blocks of K / M.  Sizes are rounded
                                    down (a last partial block is
                                    dropped): 378 / 8 gives 47. */
    uint32_t skip;             /**< Keep every skip-th frame of the split,
                                    starting with the first; default 1. */
    uint32_t white_background; /**< 1 (default): composite images with
                                    alpha onto white, rgb a + (1 - a); 0:
                                    onto black, rgb a. */
    uint32_t skip_missing;     /**< Blender: 1 drops frames whose image file
                                    does not exist (with a warning); 0
                                    (default) fails naming the file. */
    uint32_t llff_holdout;     /**< The split of every format that has
                                    none of its own (LLFF, COLMAP, a
                                    single transforms.json): images
                                    (sorted by name for LLFF and COLMAP)
                                    whose index is a multiple of this
                                    form the test split (and the val
                                    split, as in the reference); the
                                    others are train.  Default 8.  0:
                                    LLFF and COLMAP hold none out (test
                                    and val are empty); a single
                                    transforms.json serves every frame to
                                    every split. */
    uint32_t forward_facing;   /**< COLMAP: 1 places the scene as LLFF places a
                                    forward-facing capture (recentred on the
                                    average pose, the nearest sparse-point depth
                                    at 1/0.75) for NDC rays, with the spiral
                                    path; nerf_dataset_space() then says NDC.  0
                                    (default): unbounded.  LLFF scenes are
                                    forward-facing either way; a Blender scene
                                    with 1 is refused.
                                    @since 0.4 */
    const nerf_hooks *hooks;   /**< Allocation and logging; NULL = defaults. */
    uint32_t ignore_masks;     /**< 1: read no mask file, so that every pixel
                                    counts (nerf_dataset_has_masks() 0), as
                                    before masks were read.  0 (default):
                                    the layout's masks, when it has any.
                                    @since 0.13 */
} nerf_dataset_options;

/**
 * Fill @p opts with defaults and record @p struct_size.
 * @return NERF_OK, or NERF_EINVAL for a NULL or too small struct.
 */
NERF_API int nerf_dataset_options_init(nerf_dataset_options *opts,
                                       size_t struct_size);
/** A run-time call, not a constant initializer: see NERF_HOOKS_INIT. */
#define NERF_DATASET_OPTIONS_INIT(o) \
    nerf_dataset_options_init((o), sizeof *(o))

/**
 * Load one split of the scene in the folder @p dir.  The layout is
 * detected from the files present, in this order: transforms_<split>.json
 * or a single transforms.json (Blender and instant-ngp scenes);
 * poses_bounds.npy (LLFF: NDC rays, nerf_dataset_is_ndc() 1); sparse/0/
 * or sparse/ holding COLMAP's cameras and images files (COLMAP).
 * Images are PNG or JPEG files read as nerf_image_read() reads them,
 * stored as float RGB in [0, 1] and composited as the options say; every
 * image the scene names is checked, whatever its split.  How each layout
 * is read, placed, bounded and split, and what is checked:
 * docs/api-notes.md, "Dataset layouts"; the files: docs/formats.md.
 * The loader logs (level INFO, through the hooks) the format, image count
 * and size, focal length, bounds and scene scale.
 *
 * @param opts NULL for the defaults.
 * @return NERF_OK; NERF_EINVAL (NULL pointer, bad options, a downscale
 * larger than the images, an LLFF or transforms.json split left empty by
 * llff_holdout, forward_facing on a Blender scene); NERF_EVERSION (options
 * from a newer header setting unknown fields); NERF_ENOENT (no such folder,
 * or a file or image of the scene missing); NERF_EUNRECOGNISED (a file, or a
 * folder in no known layout, or something other than a regular file, a
 * folder or a FIFO say, where a file or image of the scene belongs);
 * NERF_EIO (a file or image unreadable); NERF_EFORMAT (malformed JSON,
 * malformed or truncated COLMAP file, unsupported camera model, zero-length
 * quaternion, missing field, matrix of the wrong shape, NaN or infinite
 * values, entries beyond 1e6, a degenerate rotation, a focal under 1e-3
 * pixels, a distortion coefficient beyond 1000, an aabb_scale that is not a
 * power of two in 1..128, near >= far (docs/formats.md, "Camera sanity"; the
 * message names the frame and its file_path), npy of the wrong dtype, order
 * or shape, a corrupt image or one that is neither PNG nor JPEG, a bad Exif
 * orientation, images of different sizes, image count not matching the
 * poses, no frames left, a forward-facing COLMAP model without sparse points
 * in front of its cameras, an images_K/ folder whose photos are not K times
 * smaller than the poses say, an image header claiming more pixels than its
 * file holds, a mask of another size than its photo or one that is not a
 * PNG or JPEG, a mask_path that is not a file name, masks that leave out
 * every pixel of the split); NERF_ENOMEM.  A missing or unreadable mask
 * fails as a missing or unreadable image does (NERF_ENOENT, NERF_EIO,
 * NERF_EUNRECOGNISED), naming the mask and its photo.  Messages name the
 * file and the problem.
 * On failure *out is NULL.  Reentrant: separate loads may run on
 * separate threads.
 */
NERF_API int nerf_dataset_load(nerf_dataset **out, const char *dir,
                               const nerf_dataset_options *opts);

/** Release a dataset and its images.  NULL is a no-op. */
NERF_API void nerf_dataset_destroy(nerf_dataset *ds);

/** Number of images; 0 for NULL. */
NERF_API uint32_t nerf_dataset_count(const nerf_dataset *ds);

/** The nerf_dataset_format the dataset came from; 0 for NULL. */
NERF_API int nerf_dataset_get_format(const nerf_dataset *ds);

/**
 * Size in pixels of every image of the dataset (after downscaling).
 * @return NERF_OK or NERF_EINVAL (NULL pointer).
 */
NERF_API int nerf_dataset_image_size(const nerf_dataset *ds,
                                     uint32_t *width_out,
                                     uint32_t *height_out);

/**
 * Borrow image @p index: width x height x 3 floats (RGB in [0, 1]),
 * row-major from the top-left pixel.  The pointer stays valid until the
 * dataset is destroyed; do not free it.
 * @return NERF_OK or NERF_EINVAL (NULL pointer, index out of range).
 */
NERF_API int nerf_dataset_image(const nerf_dataset *ds, uint32_t index,
                                const float **rgb_out);

/**
 * 1 when some image of the loaded split has a mask (a transforms frame's
 * mask_path, an instant-ngp dynamic_mask_<stem>.png beside the image, a
 * COLMAP or LLFF masks/ folder beside images/; docs/formats.md, "Masks"),
 * else 0 (also for NULL).  Masked pixels are left out of training (the
 * trainer never draws their rays) and out of nerf-eval's scores.
 * @since 0.13
 */
NERF_API int nerf_dataset_has_masks(const nerf_dataset *ds);

/**
 * Borrow the mask of image @p index: width x height bytes, row-major from
 * the top-left pixel as nerf_dataset_image(), 1 where the pixel counts
 * and 0 where the mask leaves it out (whatever the convention of the
 * layout's files; a downscaled pixel counts only when all the pixels of
 * its block do).  An image without a mask file of a dataset with masks
 * has every byte 1.  *mask_out is NULL when the dataset has no masks
 * (nerf_dataset_has_masks() 0).  Valid until the dataset is destroyed.
 * @return NERF_OK or NERF_EINVAL (NULL pointer, index out of range).
 * @since 0.13
 */
NERF_API int nerf_dataset_mask(const nerf_dataset *ds, uint32_t index,
                               const uint8_t **mask_out);

/**
 * The camera of image @p index: pose (OpenGL axes, world units of the
 * dataset, i.e. after the LLFF rescaling and recentring, or the COLMAP
 * centring and scaling), intrinsics in pixels of the stored images, lens
 * distortion as the files give it (unchanged by downscaling: it acts on
 * normalised coordinates), size, flags 0 (rays through pixel centres; set
 * NERF_CAMERA_PIXEL_CORNER to reproduce the reference's rays).  The
 * trainer draws its rays from these cameras, so a distorted image trains
 * on its pixels' true rays.
 * @param out initialised with nerf_camera_init(); as many bytes as its
 *            struct_size are written.
 * @return NERF_OK or NERF_EINVAL (NULL pointer, index out of range,
 * uninitialised struct).
 */
NERF_API int nerf_dataset_camera(const nerf_dataset *ds, uint32_t index,
                                 nerf_camera *out);

/**
 * The interval of t to sample along the dataset's rays: 2 and 6 for
 * Blender scenes, 0 and 1 (NDC depth) for LLFF scenes, from the sparse
 * points' depths for COLMAP scenes.
 * @return NERF_OK or NERF_EINVAL (NULL pointer).
 */
NERF_API int nerf_dataset_bounds(const nerf_dataset *ds, float *near_out,
                                 float *far_out);

/**
 * 1 when the dataset's rays should be warped to normalised device
 * coordinates (forward-facing LLFF scenes), else 0 (also for NULL).  The
 * NDC frustum is that of nerf_dataset_camera(): its fx, width and height.
 */
NERF_API int nerf_dataset_is_ndc(const nerf_dataset *ds);

/**
 * The scene space a hash-grid model of this dataset should use
 * (nerf_model_options.space and bound): NDC for forward-facing (LLFF)
 * scenes with bound 1.5 (NDC x and y within [-1.5, 1.5]); UNBOUNDED for
 * scenes that extend far beyond their centre (a COLMAP model, a transforms
 * file with aabb_scale > 1), with the half side of the central cube the
 * loader placed the scene's centre in; BOX with bound 1.5 otherwise (the
 * Blender scenes).
 * @return NERF_OK or NERF_EINVAL (NULL pointer).
 * @since 0.3
 */
NERF_API int nerf_dataset_space(const nerf_dataset *ds, uint32_t *space_out,
                                float *bound_out);

/**
 * Camera @p index of @p n_views along the reference implementation's
 * spiral render path of a forward-facing scene (LLFF, or COLMAP loaded
 * with forward_facing): two turns around the average pose, looking at a
 * focus point between the nearest and farthest bounds (docs/api-notes.md,
 * "The spiral path").  The path depends on all the scene's poses, not
 * just the loaded split.  Intrinsics and size are those of the dataset's
 * images, without their lens distortion (renders are pinhole images).
 * The reference renders 120 views.
 * @param out initialised with nerf_camera_init().
 * @return NERF_OK or NERF_EINVAL (NULL pointer, not forward-facing,
 * n_views 0 or index >= n_views, uninitialised struct).  Reentrant.
 */
NERF_API int nerf_dataset_spiral_camera(const nerf_dataset *ds,
                                        uint32_t index, uint32_t n_views,
                                        nerf_camera *out);

/**
 * Flags for nerf_camera_path_options.flags.  Without them the options'
 * size and intrinsics, when set, win over the file's; with them the file's
 * win where it has any, and the options serve as the fallback.
 */
#define NERF_CAMERA_PATH_FILE_SIZE 0x1u /**< A frame whose file gives w and
                                             h keeps that size; width and
                                             height serve only frames
                                             without one. */
#define NERF_CAMERA_PATH_FILE_INTRINSICS 0x2u /**< A frame whose file gives
                                                   fl_x or camera_angle_x
                                                   keeps the file's
                                                   intrinsics; focal or
                                                   fov_x serve only frames
                                                   without them (and every
                                                   .npy pose). */

/**
 * How nerf_camera_path_load() turns a file of poses into cameras.  The
 * defaults take everything from the file, which works for a
 * transforms-style JSON that gives its image size (w, h); a .npy file
 * carries poses only and needs width, height and focal or fov_x.
 */
typedef struct nerf_camera_path_options {
    uint32_t struct_size; /**< Set by nerf_camera_path_options_init(). */
    uint32_t width;       /**< Image width in pixels, 1..65536, or 0 (the
                               default) for the file's w.  Set width and
                               height together or leave both 0.  When the
                               file gives w and h, its intrinsics are
                               scaled by width / w and height / h (the
                               field of view is kept). */
    uint32_t height;      /**< Image height in pixels, 1..65536, or 0 for
                               the file's h. */
    uint32_t flags;       /**< NERF_CAMERA_PATH_*; default 0. */
    float focal;          /**< > 0: fx = fy = focal, in pixels of the
                               rendered image, principal point at the
                               centre, replacing the file's intrinsics
                               (see NERF_CAMERA_PATH_FILE_INTRINSICS);
                               default 0 (none). */
    float fov_x;          /**< Horizontal field of view in degrees, in
                               (0, 180): as focal with focal =
                               0.5 width / tan(0.5 fov_x); default 0
                               (none).  At most one of focal and fov_x may
                               be set. */
    const nerf_hooks *hooks; /**< Allocation and logging; NULL = defaults. */
} nerf_camera_path_options;

/**
 * Fill @p opts with defaults and record @p struct_size.
 * @return NERF_OK, or NERF_EINVAL for a NULL or too small struct.
 */
NERF_API int nerf_camera_path_options_init(nerf_camera_path_options *opts,
                                           size_t struct_size);
/** A run-time call, not a constant initializer: see NERF_HOOKS_INIT. */
#define NERF_CAMERA_PATH_OPTIONS_INIT(o) \
    nerf_camera_path_options_init((o), sizeof *(o))

/**
 * Load a camera path (a sequence of poses to render) from the file
 * @p path, in one of two forms (docs/formats.md, "Camera paths", has the
 * details): a NumPy .npy file (told by its magic bytes or a ".npy" name)
 * of camera-to-world matrices in the nerf_camera convention, shape
 * (N, 3, 4), (N, 4, 4), (N, 12) or (N, 16), dtype '<f4' or '<f8', with no
 * intrinsics (the options must give width, height and focal or fov_x);
 * anything else is read as a transforms-style JSON file, as
 * nerf_dataset_load() reads them, without reading any image.
 *
 * Every matrix must be finite, representable as float, and have an
 * invertible rotation part.  Files hold at most 100000 poses.  The
 * cameras have flags 0 (rays through pixel centres).
 *
 * @param out  receives the path; release it with nerf_camera_path_destroy().
 *             NULL on failure.
 * @param opts NULL for the defaults.
 * @return NERF_OK; NERF_EINVAL (NULL pointer, bad options, no image size
 * for a file that gives none, no focal or fov_x for a .npy file);
 * NERF_EVERSION (options from a newer header setting unknown fields);
 * NERF_ENOENT (no such file); NERF_EUNRECOGNISED (not a regular file: a
 * folder, a FIFO, a device, refused without blocking);
 * NERF_EIO (the file cannot be opened or read); NERF_EFORMAT (truncated
 * or malformed file, npy dtype, order or shape not listed above, no
 * frames or more than 100000, missing field, NaN or infinite values,
 * bottom row not [0, 0, 0, 1], entries beyond 1e6, degenerate rotation,
 * focal under 1e-3 pixels: docs/formats.md, "Camera sanity"; w or h not a
 * positive whole number); NERF_ENOMEM.  Messages name the file, the frame
 * (with its file_path when it has one) and the problem.
 * Reentrant: separate loads may run on separate threads.
 */
NERF_API int nerf_camera_path_load(nerf_camera_path **out, const char *path,
                                   const nerf_camera_path_options *opts);

/** Release a camera path.  NULL is a no-op. */
NERF_API void nerf_camera_path_destroy(nerf_camera_path *camera_path);

/** Number of cameras (at least 1); 0 for NULL. */
NERF_API uint32_t nerf_camera_path_count(const nerf_camera_path *camera_path);

/**
 * Camera @p index of the path, in file order.
 * @param out initialised with nerf_camera_init(); as many bytes as its
 *            struct_size are written.
 * @return NERF_OK or NERF_EINVAL (NULL pointer, index out of range,
 * uninitialised struct).  Reentrant.
 */
NERF_API int nerf_camera_path_camera(const nerf_camera_path *camera_path,
                                     uint32_t index, nerf_camera *out);

/* ===========================================================================
 * 12. Trainer
 * ======================================================================== */

/** Sparse ranges a nerf_exchange can describe.  @since 0.5 */
#define NERF_EXCHANGE_MAX_SPARSE 4

/**
 * What a trainer tells its gradient and checksum hooks (see
 * nerf_trainer_options.worker_count) besides the numbers they exchange.
 * Versioned: the library sets struct_size; read a field only if
 * struct_size covers it (fields are only appended).
 * @since 0.5
 */
typedef struct nerf_exchange {
    uint32_t struct_size;  /**< sizeof the library's struct. */
    uint32_t worker_rank;  /**< This worker, 0..worker_count - 1. */
    uint32_t worker_count; /**< Workers of the run; 1 for a trainer alone. */
    uint32_t n_sparse;     /**< Ranges of the gradient vector that are
                                mostly zeros: the hash tables, whose entries
                                a step mostly does not touch (0 for a
                                model without one).  Elements outside them
                                are dense: nearly all nonzero. */
    uint64_t step;         /**< The step being taken: the model's step
                                count before it. */
    uint64_t sparse_begin[NERF_EXCHANGE_MAX_SPARSE]; /**< First element of
                                each sparse range (index into grads). */
    uint64_t sparse_end[NERF_EXCHANGE_MAX_SPARSE];   /**< One past its
                                last. */
    uint64_t rays;         /**< Rays this worker trained on in the step. */
    uint64_t batch_rays;   /**< Rays of the whole step, all workers. */
    char message[256];     /**< Empty on entry: a hook that fails may write
                                a NUL-terminated reason here, which the
                                trainer's error message quotes. */
} nerf_exchange;

/**
 * Gradient hook: called by every worker after the step's
 * backward pass and before the optimiser, with the model's flat gradient
 * vector @p grads of @p n floats (n = nerf_model_param_count()).  It must
 * leave in @p grads the sum of all workers' vectors, element by element,
 * the same bits on every worker (an all-reduce), so that every worker
 * applies the same update.  Each worker's gradient is already weighed by
 * the whole step's ray count, so the sum is the gradient one worker
 * would compute on the whole batch.  It runs on the thread that takes
 * the step, never on a worker thread, and must not call back into the
 * trainer.  Return 0, or nonzero to fail the step (NERF_ERROR, the
 * weights left as before it).
 * @since 0.5
 */
typedef int (*nerf_grad_hook)(void *user, float *grads, size_t n,
                              nerf_exchange *x);

/**
 * Checksum hook (nerf_trainer_options.checksum_every): on
 * entry both @p range[0] and @p range[1] hold this worker's checksum of
 * its weights (CRC-32 of the parameters' bytes); the hook must leave in
 * range[0] the smallest and in range[1] the largest over all workers,
 * the same on every worker.  Return 0, or nonzero to fail the step.
 * @since 0.5
 */
typedef int (*nerf_checksum_hook)(void *user, uint32_t range[2],
                                  nerf_exchange *x);

/** How a trainer draws and weighs its rays, fixed at creation. */
typedef struct nerf_trainer_options {
    uint32_t struct_size;     /**< Set by nerf_trainer_options_init(). */
    uint32_t batch_rays;      /**< Rays per step, drawn at random across all
                                   training images; default 1024 (the
                                   reference configuration; the paper used
                                   4096). */
    uint32_t precrop_steps;   /**< For this many first steps, draw rays only
                                   from the central crop of the images;
                                   default 500 (as the reference on Blender
                                   scenes); ignored with an NDC sampler. */
    float precrop_fraction;   /**< Side of that crop as a fraction of the
                                   image side, (0, 1]; default 0.5. */
    float raw_noise_std;      /**< Gaussian noise on raw density in
                                   training; default NERF_NOISE_AUTO (1 with
                                   an NDC sampler, else 0).  Not applied
                                   with a marching sampler. */
    int32_t white_background; /**< 1: composite renders on white, 0: black,
                                   -1 (default): as the dataset's images
                                   were (white for Blender scenes loaded
                                   with white_background). */
    uint32_t checkpoint_every; /**< nerf_trainer_run() saves the model to
                                    checkpoint_path every this many steps
                                    (and when it ends); 0 (default): only
                                    when it ends, if a path is set. */
    uint32_t reserved0;       /**< Must be 0. */
    const char *checkpoint_path; /**< Copied; NULL (default): no saves. */
    const nerf_hooks *hooks;  /**< Allocation and logging; NULL = defaults. */
    /* Zero-filled by an older caller, which gives the behaviour from
     * before these fields.
     * @since 0.2 */
    uint32_t batch_samples;   /**< 0 (default): every step takes batch_rays
                                   rays.  N > 0: a step takes rays, of the
                                   batch_rays it draws, until their samples
                                   reach N (at least one ray), so that a
                                   step's cost stays even while the count
                                   per ray changes: with a marching sampler
                                   it falls from hundreds to tens as the
                                   occupancy grid learns where the scene
                                   is.  batch_rays is then the most rays a
                                   step takes. */
    int32_t random_background; /**< 1: train on images with alpha (Blender
                                    scenes) against a random background
                                    colour per ray, the target composited
                                    onto it and the render finished on it,
                                    so that the model cannot paint empty
                                    space in the background's colour
                                    (Mueller et al.).  0 (default): the
                                    background is white_background's.
                                    Images without alpha ignore it. */
    /* Data-parallel training (docs/distributed.md).  Zero (an older
     * caller's zero fill) is a trainer alone.
     * @since 0.5 */
    uint32_t worker_rank;     /**< This worker, 0..worker_count - 1. */
    uint32_t worker_count;    /**< 0 or 1 (default): alone.  W > 1: this
                                   trainer is one of W, each with a copy
                                   of the same model (same seed, or the
                                   same checkpoint), dataset, sampler
                                   and options but its rank.  Worker r
                                   trains on its contiguous share of
                                   each step's rays and grad_hook sums
                                   the workers' gradients, so that they
                                   take the step one trainer would, up
                                   to the order of the sums
                                   (docs/api-notes.md, "Workers of a
                                   data-parallel run").  Needs
                                   grad_hook; nerf_trainer_run_for() is
                                   refused (its clock differs between
                                   workers). */
    nerf_grad_hook grad_hook; /**< Called every step before the optimiser
                                   (also for a worker alone); NULL
                                   (default): none. */
    nerf_checksum_hook checksum_hook; /**< See checksum_every. */
    void *hook_user;          /**< Passed to both hooks. */
    uint32_t checksum_every;  /**< N > 0: after every step whose count is
                                   a multiple of N, and before a
                                   trainer's first step, compare the
                                   workers' weights through
                                   checksum_hook (needed then), failing
                                   with NERF_ERROR if they differ.  0
                                   (default): never. */
    uint32_t reserved1;       /**< Must be 0. */
    /* Zero (an older caller's zero fill): saves by steps alone, as
     * before.
     * @since 0.6 */
    double checkpoint_seconds; /**< S > 0: nerf_trainer_run() and
                                    nerf_trainer_run_for() also save to
                                    checkpoint_path once S seconds have
                                    passed since the call began or since
                                    its last save, so that a run whose
                                    step count is not known beforehand (a
                                    time budget) loses at most about S
                                    seconds of training when it is killed.
                                    The clock decides when a save happens,
                                    never what is trained.  Needs
                                    checkpoint_path; 0 (default): no
                                    timed saves. */
    /* Zero (an older caller's zero fill): the model records the march it
     * trains in, as before.
     * @since 0.12 */
    uint32_t render_march_steps; /**< With a marching sampler: the march
                                    the model records for rendering
                                    (nerf_model_render_settings()), in
                                    1..65536 steps of the grid's diagonal,
                                    its max_samples scaled as by
                                    nerf_sampler_options_set_march(); a
                                    finer march than training's renders
                                    sharper for a little more time a
                                    frame (docs/api-notes.md, "A run as
                                    nerf-train sets it up").  0 (default):
                                    the sampler's own.  Ignored without
                                    marching. */
    uint32_t appearance_codes; /**< 1: learn a small appearance code per
                                    training image, which absorbs how its
                                    exposure and white balance differ from
                                    the other photos' (docs/api-notes.md,
                                    "Photos whose exposure differs"): the
                                    trainer adds them to a model without
                                    codes.  0 (default): a model without
                                    codes trains without.  A model with
                                    codes (one per image of the dataset,
                                    else refused) trains them on either
                                    way.  Not with worker_count > 1 yet.
                                    Was reserved2 before 0.13.
                                    @since 0.13 */
} nerf_trainer_options;

/**
 * Fill @p opts with defaults and record @p struct_size.
 * @return NERF_OK, or NERF_EINVAL for a NULL or too small struct.
 */
NERF_API int nerf_trainer_options_init(nerf_trainer_options *opts,
                                       size_t struct_size);
/** A run-time call, not a constant initializer: see NERF_HOOKS_INIT. */
#define NERF_TRAINER_OPTIONS_INIT(o) nerf_trainer_options_init((o), sizeof *(o))

/*
 * A run as nerf-train sets it up.  The library's defaults are the
 * reference implementation's; what nerf-train chooses beyond them for a
 * preset, a model and a dataset comes from these three calls, so that a
 * caller who makes them (after nerf_model_options_preset(), which sets the
 * preset's learning rate) trains exactly what nerf-train trains, bit for
 * bit: docs/api-notes.md, "A run as nerf-train sets it up".
 */

/**
 * Place a hash-grid model in @p dataset's scene: space and bound from
 * nerf_dataset_space() (a box for Blender scenes, NDC for forward-facing
 * ones, a contracted space for all-round captures with a far background).
 * Options of another encoding are left as they are: they read
 * coordinates anywhere.
 * @return NERF_OK; NERF_EINVAL for a NULL argument or a bad struct.
 * @since 0.12
 */
NERF_API int nerf_model_options_for_dataset(nerf_model_options *opts,
                                            const nerf_dataset *dataset);

/** Uses for nerf_sampler_options_for().  @since 0.12 */
typedef enum nerf_sampler_use {
    NERF_SAMPLER_FOR_RENDERING = 0, /**< The march the model records. */
    NERF_SAMPLER_FOR_TRAINING = 1   /**< A marching model trains in the
                                         fast preset's march (1024
                                         steps), 256 steps in NDC and
                                         contracted spaces (since 0.13.2),
                                         whatever finer one it records for
                                         rendering, so that a resumed run
                                         goes on as it began. */
} nerf_sampler_use;

/**
 * Sampling settings for @p model on @p dataset, written into the
 * sampling fields of an initialised @p opts (seed, perturb and hooks are
 * kept).  The model says how: the settings its trainer recorded, or those
 * its shape suggests (nerf_model_render_settings()), with the march @p use
 * asks for.  The dataset says where: its near and far bounds (an unbounded
 * model keeps its own far reach), its NDC setting and, for NDC, the frustum
 * of its first camera, so that renders at other sizes see the same warped
 * scene.
 * @param model NULL: keep @p opts' own counts and march (from
 *              nerf_sampler_options_preset(), say).
 * @param dataset NULL: the model's recorded bounds.
 * @param use a nerf_sampler_use.
 * @return NERF_OK; NERF_EINVAL for bad arguments; NERF_EFORMAT as
 * nerf_model_render_settings().
 * @since 0.12
 */
NERF_API int nerf_sampler_options_for(nerf_sampler_options *opts,
                                      const nerf_model *model,
                                      const nerf_dataset *dataset, int use);

/**
 * nerf-train's trainer settings for @p model, written into an initialised
 * @p opts (other fields are kept):
 *  - rays a step: those the model was trained with
 *    (nerf_model_training_batch()), else 2048 rays of at most 131072
 *    samples for a new hash-grid model, else 1024 rays;
 *  - a hash-grid model trains without the central crop and against a
 *    random background (Mueller et al.), and records a march of 1280
 *    steps for rendering (render_march_steps);
 *  - with a checkpoint_path already set and no checkpoint_every, a save
 *    every 120 seconds (checkpoint_seconds).
 * Why each: docs/api-notes.md, "A run as nerf-train sets it up".
 * @return NERF_OK; NERF_EINVAL for a NULL argument or a bad struct.
 * @since 0.12
 */
NERF_API int nerf_trainer_options_for(nerf_trainer_options *opts,
                                      const nerf_model *model);

/**
 * Figures of one training step.  Versioned: set struct_size (sizeof) before
 * passing it; the library writes only the fields it covers.
 */
typedef struct nerf_train_stats {
    uint32_t struct_size;  /**< Set by the caller. */
    uint32_t reserved0;
    uint64_t step;         /**< The model's step count after the step. */
    double loss;           /**< Coarse + fine mean squared error. */
    double psnr;           /**< PSNR (dB) of the last pass's colours. */
    double psnr_coarse;    /**< PSNR (dB) of the coarse pass. */
    double learning_rate;  /**< The rate the step used. */
    /* @since 0.2 */
    double samples_per_ray; /**< Network evaluations per ray in the step,
                                 all passes: n_coarse (+ n_coarse +
                                 n_fine with a fine pass), or with ray
                                 marching the mean count of marched
                                 samples. */
    uint64_t rays;          /**< Rays the step trained on: batch_rays, or
                                 fewer with batch_samples. */
} nerf_train_stats;

/**
 * Create a trainer that optimises @p model on the images of @p dataset
 * (a training split), placing samples with @p sampler (whose perturb
 * setting makes training samples random).  The trainer references all
 * three without owning them: they must outlive it, and nothing else may
 * use the model while a step runs.
 *
 * The whole state of a run is the model: its step count keys every random
 * choice of a step (rays, sample jitter, noise), so a model saved at step
 * k, loaded and trained on with the same dataset, sampler and options
 * continues bit for bit as the uninterrupted run would.
 *
 * With a marching sampler (march_steps > 0) the trainer also keeps the
 * model's occupancy grid current, on a schedule keyed by the model's seed
 * and saved in checkpoints (docs/api-notes.md, "Occupancy grid updates").
 *
 * A checkpoint_path is tried at once: a temporary file is created beside
 * it and removed, so that a path that cannot be written fails here, not
 * at the first save.
 *
 * The model records the data it is trained on; given a model whose record
 * differs from @p dataset, the trainer logs a NERF_LOG_WARN naming what
 * differs and trains on (docs/api-notes.md, "The training-data record").
 *
 * @return NERF_OK; NERF_EINVAL (NULL argument, bad options, empty dataset,
 * a marching sampler with a model that has no occupancy grid, weights
 * that are not finite: NERF_MODEL_HAS_NONFINITE_WEIGHTS, which Adam
 * cannot bring back); NERF_EIO (checkpoint_path cannot be written: a
 * missing folder, a path through a regular file, a folder, no
 * permission); NERF_EVERSION
 * (options from a newer header setting unknown fields); NERF_ENOMEM.
 */
NERF_API int nerf_trainer_create(nerf_trainer **out, nerf_model *model,
                                 const nerf_dataset *dataset,
                                 const nerf_sampler *sampler,
                                 const nerf_trainer_options *opts);

/** Release a trainer (not its model, dataset or sampler).  NULL: no-op. */
NERF_API void nerf_trainer_destroy(nerf_trainer *trainer);

/**
 * Take one optimisation step: draw the step's rays, render them through
 * both networks, take the squared-error loss of both passes against the
 * images, back-propagate and update the weights with Adam at the scheduled
 * learning rate.
 * @param stats_out NULL, or figures of the step (set its struct_size).
 * @return NERF_OK; NERF_EINVAL; NERF_ENOMEM (first step only: later steps
 * reuse their buffers, except that with ray marching they grow when a
 * step has more samples than any before); NERF_ERROR if the loss is not
 * finite (the weights are then left as they were before the step; the
 * message says whether they are finite, and if not where the first that
 * is not lies: "training diverged by step K: the weights are not
 * finite (...)"), if
 * the grad_hook or checksum_hook failed (the message quotes the hook's),
 * or if the workers' weights differ (see checksum_every).
 */
NERF_API int nerf_trainer_step(nerf_trainer *trainer,
                               nerf_train_stats *stats_out);

/**
 * Take @p n_steps steps, calling the progress callback (kind
 * NERF_PROGRESS_TRAIN, done and total in steps) after each and saving
 * checkpoints as the options say.
 * @param stats_out NULL, or the figures of the last step taken.
 * @return as nerf_trainer_step(); NERF_ERROR also when the weights
 * turned out not finite at a checkpoint due (which is then not written:
 * the file keeps its last good state) or at the run's end, the losses
 * having stayed finite; NERF_ECANCELLED when the callback or
 * nerf_trainer_cancel() stopped the run (after a whole step); NERF_EIO
 * when a checkpoint cannot be written, also when the run was cancelled and
 * its final save failed (the file at checkpoint_path is then the last
 * checkpoint that was written whole, or absent).
 */
NERF_API int nerf_trainer_run(nerf_trainer *trainer, uint64_t n_steps,
                              nerf_train_stats *stats_out);

/**
 * Train for about @p seconds of wall time, the learning rate
 * decaying over the steps that time allows, rather than over a step count
 * guessed beforehand.
 *
 * A model whose schedule is not FITTED (see nerf_model_schedule()) starts
 * by measuring its step rate, the rate held at NERF_PARAM_LEARNING_RATE,
 * then fixes the run's length to fit the budget: it sets
 * NERF_PARAM_DECAY_START to the current step and NERF_PARAM_DECAY_STEPS to
 * that length and records the fit in the model (state FITTED, saved in
 * checkpoints, logged at NERF_LOG_INFO).  Later in the budget the same
 * call fits the length again to the latest rate, moving DECAY_STEPS only.
 * From each fit on the run is a plain schedule: a model saved after it
 * continues bit for bit to its recorded length under nerf_trainer_run_for()
 * or nerf_trainer_run(), without measuring or fitting again.  When each
 * fit happens, and what it takes into account: docs/api-notes.md,
 * "Time-budgeted training".
 *
 * The run ends at the fitted length (NERF_OK).  Should steps turn slower
 * than measured, it ends when @p seconds and a tenth have passed
 * (NERF_ECANCELLED, the error message saying so); the model is then a
 * step of the same deterministic run, which a later call continues.
 * Progress reports (NERF_PROGRESS_TRAIN) give done in steps of this call
 * and total as the steps this call will take: projected from the rate so
 * far while measuring, fixed after.  Checkpoints are saved as by
 * nerf_trainer_run().
 *
 * @param seconds the budget, > 0 and finite, counted from this call.
 * @return as nerf_trainer_run(); NERF_EINVAL for a bad @p seconds, or
 * for a trainer that is one of several workers (worker_count > 1), each
 * of which would fit the run to its own clock.
 * @since 0.5
 */
NERF_API int nerf_trainer_run_for(nerf_trainer *trainer, double seconds,
                                  nerf_train_stats *stats_out);

/**
 * Set (or with NULL clear) the progress callback of nerf_trainer_run()
 * and nerf_trainer_run_for().
 * @return NERF_OK, or NERF_EINVAL for a NULL trainer.
 */
NERF_API int nerf_trainer_set_progress(nerf_trainer *trainer,
                                       nerf_progress_cb cb, void *user);

/**
 * Ask a running nerf_trainer_run() to stop after its current step.
 * Thread-safe; each run clears the request when it starts.  NULL: no-op.
 */
NERF_API void nerf_trainer_cancel(nerf_trainer *trainer);

/* ===========================================================================
 * 13. Built-in scene
 * ======================================================================== */

/** Values of nerf_scene_options.image_format. */
#define NERF_IMAGE_FORMAT_PNG 0u  /**< PNGs (RGBA for the object capture). */
#define NERF_IMAGE_FORMAT_JPEG 1u /**< RGB JPEGs composited on white, named
                                       .jpg in file_path: what a camera
                                       gives, with no mask. */

/** The sizes and view counts nerf_scene_write() takes (a program's help
 * can quote them: plain integers).  @since 0.11 */
#define NERF_SCENE_MIN_SIDE 8     /**< Smallest image width or height. */
#define NERF_SCENE_MAX_SIDE 4096  /**< Largest image width or height. */
#define NERF_SCENE_MAX_VIEWS 10000 /**< Most views of a split. */

/** What nerf_scene_write() produces. */
typedef struct nerf_scene_options {
    uint32_t struct_size; /**< Set by nerf_scene_options_init(). */
    uint32_t width;       /**< Image width in pixels, NERF_SCENE_MIN_SIDE..
                               NERF_SCENE_MAX_SIDE (8..4096); default 100. */
    uint32_t height;      /**< Image height in pixels, as width; default
                               100. */
    uint32_t n_train;     /**< Training views, 1..NERF_SCENE_MAX_VIEWS
                               (10000); default 100. */
    uint32_t n_val;       /**< Validation views, 0..NERF_SCENE_MAX_VIEWS;
                               default 8. */
    uint32_t n_test;      /**< Test views (a circle at 30 degrees),
                               0..NERF_SCENE_MAX_VIEWS; default 16. */
    uint32_t threads;     /**< Worker threads; 0 (default) = all cores. */
    uint32_t appearance;  /**< NERF_SCENE_APPEARANCE_*: whether the
                               training photos' exposure and white balance
                               differ; default CONSTANT.  Was reserved0
                               before 0.13.
                               @since 0.13 */
    uint64_t seed;        /**< Placement of the validation views, and the
                               appearance changes' draws; default 0. */
    const nerf_hooks *hooks; /**< Allocation and logging; NULL = defaults. */
    uint32_t capture;     /**< How the scene is photographed:
                               NERF_SCENE_CAPTURE_*; default OBJECT.
                               @since 0.3 */
    uint32_t layout;      /**< The files it is written as: NERF_SCENE_LAYOUT_*;
                               default BLENDER.  The usual pairs: OBJECT and
                               UNBOUNDED in BLENDER, FORWARD in LLFF.
                               @since 0.3 */
    uint32_t image_format; /**< NERF_IMAGE_FORMAT_*: the views' files; default
                                NERF_IMAGE_FORMAT_PNG.
                                @since 0.3 */
    uint32_t jpeg_quality; /**< JPEG quality 1..100; 0 (default) = 95.  Ignored
                                for PNG.
                                @since 0.3 */
    float k1, k2, p1, p2, k3; /**< The lens the views are photographed through
                               (nerf_camera's distortion): each pixel holds what
                               its ray through that lens sees, and the files
                               record the coefficients (the LLFF layout cannot,
                               COLMAP's OPENCV model has no k3).  Default 0: a
                               pinhole camera.
                               @since 0.3 */
    uint32_t occluders;   /**< 1: people walking through, as it were: every
                               other training view (0, 2, 4, ...) has an
                               opaque magenta disc painted over it (a thing
                               just before the lens), a fifth of the
                               picture's shorter side in radius, at a place
                               that moves from view to view; the layout
                               records its mask
                               (BLENDER and TRANSFORMS: the frame's mask_path,
                               0 = leave out; COLMAP: masks/<image>.png for
                               every image).  LLFF is refused.  Views of the
                               other splits are not painted (TRANSFORMS: the
                               loader's split is not the writer's, so some
                               painted views may land in the test split,
                               masks and all).  0 (default): none, and the
                               files are as before, byte for byte.
                               @since 0.13 */
    uint32_t texture;     /**< 1: blotches of light and dark on the solids
                               and the ground (two octaves of smooth
                               noise), which give feature matchers such as
                               COLMAP's SIFT something to find: the plain
                               solids' smooth shading gives too few.  0
                               (default): the plain scene, byte for byte as
                               before.  0 or 1.
                               @since 0.13 */
    uint32_t reserved1;   /**< Must be 0.  @since 0.13 */
} nerf_scene_options;

/** Captures of the built-in scene (nerf_scene_options.capture). */
#define NERF_SCENE_CAPTURE_OBJECT 0u    /**< The solids alone on a
    transparent background, from a hemisphere of views at distance 4. */
#define NERF_SCENE_CAPTURE_FORWARD 1u   /**< A forward-facing capture, as
    LLFF's: the solids on a ground before a backdrop 40 units away, seen
    from a jittered grid of cameras 3.2 units in front of them on one side,
    all looking the same way (within a degree), spread over 0.8 x 0.6
    units; horizontal field of view 1 radian.  Opaque. */
#define NERF_SCENE_CAPTURE_UNBOUNDED 2u /**< An all-round capture with a far
    background: the solids on a ground within a backdrop 40 units away,
    from rings of cameras 2.2 to 3 units from them looking at them;
    horizontal field of view 1 radian.  Opaque. */
#define NERF_SCENE_CAPTURE_WALK 3u      /**< The all-round world of
    UNBOUNDED seen as a video is shot: the train views, in order, walk
    once round the solids on one continuous path (2.3 to 2.9 units from
    them, rising and falling between 9 and 21 degrees of elevation,
    looking at them), so that each view overlaps the next; validation
    views anywhere on the path; test views evenly along it, half a step
    on from where the train views stand (halfway between them when there
    are as many).
    Horizontal field of view 1 radian.  Opaque.  @since 0.13 */

/** How the training photos look (nerf_scene_options.appearance).
 * @since 0.13 */
#define NERF_SCENE_APPEARANCE_CONSTANT 0u /**< All alike, as rendered. */
#define NERF_SCENE_APPEARANCE_VARIED 1u /**< Each training photo's channels
    scaled by its own exposure (2^u, u within +-0.5) and white balance
    (2^v per channel, v within +-0.15), normalised so that their mean
    over the training photos is 1 per channel: the look of a phone's
    automatic exposure.  Validation and test views keep the scene's own
    look, which a model with appearance codes renders with its neutral
    code (NERF_APPEARANCE_NEUTRAL).  Blender layout only. */

/** Layouts of the written scene (nerf_scene_options.layout). */
#define NERF_SCENE_LAYOUT_BLENDER 0u       /**< transforms_{train,val,test}
    .json and PNGs under train/, val/, test/ (RGBA for OBJECT, RGB for the
    opaque captures, whose files also record instant-ngp's aabb_scale 16
    at top level for UNBOUNDED). */
#define NERF_SCENE_LAYOUT_TRANSFORMS 1u    /**< One instant-ngp style
    transforms.json holding every view (train, then val, then test, under
    images/), with fl_x, fl_y, cx, cy, w, h, k1, k2, p1, p2, k3 and
    aabb_scale at top level (16 for the opaque captures, 2 for OBJECT).
    Loading it splits it every llff_holdout-th frame, not by the counts
    written. */
#define NERF_SCENE_LAYOUT_LLFF 2u          /**< FORWARD only:
    poses_bounds.npy and images/ (RGB PNGs, their names sorted in capture
    order), n_train + n_test views in all (n_val is not used): a loader
    holds out every 8th as LLFF has no split files.  Bounds per view are
    the 0.1 and 99.9 percentiles of its pixels' depths along the optical
    axis, as LLFF's imgs2poses takes them from the sparse points. */
#define NERF_SCENE_LAYOUT_COLMAP_TEXT 3u   /**< A COLMAP model as COLMAP's
    text files: images/ (RGB PNGs, composited onto white for OBJECT, named
    00000.png ... over the train, val and test views in that order) and
    sparse/0/ cameras.txt, images.txt, points3D.txt: one PINHOLE camera,
    every view's pose in COLMAP's convention, and sparse points where
    pixels' rays of opacity above 0.95 end in a few views, each with a
    track of the views whose ray through its projection ends there too. */
#define NERF_SCENE_LAYOUT_COLMAP_BINARY 4u /**< The same as COLMAP's binary
    files (cameras.bin, images.bin, points3D.bin). */

/**
 * Fill @p opts with defaults and record @p struct_size.
 * @return NERF_OK, or NERF_EINVAL for a NULL or too small struct.
 */
NERF_API int nerf_scene_options_init(nerf_scene_options *opts,
                                     size_t struct_size);
/** A run-time call, not a constant initializer: see NERF_HOOKS_INIT. */
#define NERF_SCENE_OPTIONS_INIT(o) nerf_scene_options_init((o), sizeof *(o))

/**
 * Write the built-in scene to the folder @p dir (created if missing) in the
 * capture and layout the options say: a few coloured solids about the
 * origin (z up), rendered by numerically exact volume rendering, alone on
 * a transparent background (OBJECT, the default: a Blender-format dataset
 * from cameras at distance 4; use near 2, far 6) or on a ground before a
 * far backdrop, every pixel opaque (FORWARD, UNBOUNDED).  With a lens
 * (k1 .. k3 not all 0) every pixel holds what its ray through the lens
 * sees.  Same options, same bytes.  The scene: docs/api-notes.md, "The
 * built-in scene"; its files: docs/formats.md, "The built-in scene".
 * @return NERF_OK; NERF_EINVAL (bad options: sizes, counts, an unknown
 * capture or layout, a layout that does not fit the capture or is not
 * supported yet); NERF_EIO (cannot create or write a file, named in the
 * message); NERF_ENOMEM.
 */
NERF_API int nerf_scene_write(const char *dir,
                              const nerf_scene_options *opts);

/* ===========================================================================
 * 14. Meshes
 * ======================================================================== */

/** How nerf_mesh_extract() colours the vertices.  @since 0.5 */
typedef enum nerf_mesh_colour {
    NERF_MESH_COLOUR_NONE = 0,  /**< No colours (nerf_mesh_colours() gives
                                     NULL; the files have none). */
    NERF_MESH_COLOUR_NORMAL = 1 /**< The radiance seen at the vertex looking
                                     at the surface head on: the model's
                                     colour at the vertex for the view
                                     direction minus the vertex normal. */
} nerf_mesh_colour;

/** File formats of nerf_mesh_write().  @since 0.5 */
typedef enum nerf_mesh_format {
    NERF_MESH_FORMAT_AUTO = 0,       /**< By the path's extension: .ply
                                          (binary), .obj; others refused. */
    NERF_MESH_FORMAT_PLY = 1,        /**< Binary little-endian PLY. */
    NERF_MESH_FORMAT_PLY_ASCII = 2,  /**< ASCII PLY. */
    NERF_MESH_FORMAT_OBJ = 3         /**< Wavefront OBJ; colours as the
                                          common "v x y z r g b" extension
                                          (r g b in [0, 1]). */
} nerf_mesh_format;

/**
 * Settings of nerf_mesh_extract() and nerf_density_grid_write().
 * The density is sampled on a grid over a box and, for a mesh, cut at the
 * threshold by marching cubes, one layer of cells at a time (memory holds
 * two planes of samples, not the whole grid).
 * @since 0.5
 */
typedef struct nerf_mesh_options {
    uint32_t struct_size;   /**< Set by nerf_mesh_options_init(). */
    uint32_t resolution;    /**< Cells along the box's longest side,
                                 1..16384; the other sides get as many as
                                 keep the cells nearest to cubes.  Default
                                 256. */
    float threshold;        /**< Density at the surface (finite); default
                                 25, the level instant-ngp and nerfstudio
                                 use for sigma (docs/export.md). */
    float box[6];           /**< x0 y0 z0 x1 y1 z1: the region sampled, in
                                 the model's space (world, or NDC for an
                                 NDC model).  All zero (the default): the
                                 model's bounds, [-bound, bound]^3 (the
                                 central cube of an unbounded model; for
                                 NDC, x and y in [-bound, bound] and z in
                                 [-1, 1]). */
    uint32_t colour;        /**< nerf_mesh_colour; default NORMAL. */
    uint32_t keep_largest;  /**< 1: keep only the connected component with
                                 the most faces; default 0. */
    uint32_t min_component_faces; /**< Drop components of fewer faces;
                                 default 0 (keep all). */
    uint32_t threads;       /**< At most this many threads sample the
                                 density; 0 (the default): the cores
                                 divided by OpenBLAS's own thread count,
                                 as the renderer's threads.  Results do
                                 not depend on it. */
    uint32_t reserved0;     /**< Must be 0. */
    nerf_progress_cb progress; /**< NULL, or called after each plane of
                                 samples (kind NERF_PROGRESS_GEOMETRY);
                                 nonzero cancels with NERF_ECANCELLED. */
    void *progress_user;    /**< Passed to progress. */
    const nerf_hooks *hooks; /**< Allocation and logging; NULL = defaults. */
} nerf_mesh_options;

/**
 * Fill @p opts with the defaults and record @p struct_size (or
 * use NERF_MESH_OPTIONS_INIT).
 * @return NERF_OK, or NERF_EINVAL for a NULL or too small struct.
 * @since 0.5
 */
NERF_API int nerf_mesh_options_init(nerf_mesh_options *opts,
                                    size_t struct_size);
/** A run-time call, not a constant initializer: see NERF_HOOKS_INIT. */
#define NERF_MESH_OPTIONS_INIT(o) nerf_mesh_options_init((o), sizeof *(o))

/**
 * Extract the surface where @p model's density crosses
 * opts->threshold, with marching cubes over the grid the options lay over
 * their box.  The density is that of the model's fine network when it has
 * one.  Where the surface stays inside the box the mesh is closed (every
 * edge in exactly two faces), triangles wound counter-clockwise seen from
 * outside (normals towards lower density); it is open where the box cuts
 * it.  Vertices are in the model's space, except for an NDC model with
 * recorded render settings (nerf_model_render_settings() with its NDC
 * frustum): its vertices are mapped back to world space (docs/export.md).
 * Normals (area-weighted face normals) always come with the mesh.
 * @param out  receives the mesh (NULL on failure); free it with
 *             nerf_mesh_destroy().  An empty mesh (no surface at that
 *             threshold) is a success.
 * @param opts NULL means the defaults.
 * @return NERF_OK; NERF_EINVAL (NULL model or out, resolution 0 or too
 * large, a box of zero volume or not finite, a threshold that is not
 * finite, unknown colour, weights that are not finite:
 * NERF_MODEL_HAS_NONFINITE_WEIGHTS); NERF_EVERSION; NERF_ECANCELLED (the
 * progress callback); NERF_ENOMEM.
 *
 * Reads the model only (as nerf_model_query()): several calls may run on
 * one model at once while nothing trains it.  Memory beyond the mesh is
 * two planes of samples and one layer of edge indices, not the grid.
 * @since 0.5
 */
NERF_API int nerf_mesh_extract(nerf_mesh **out, const nerf_model *model,
                               const nerf_mesh_options *opts);

/** Release a mesh.  NULL is a no-op.  @since 0.5 */
NERF_API void nerf_mesh_destroy(nerf_mesh *mesh);

/** Vertices of @p mesh (0 for NULL).  @since 0.5 */
NERF_API size_t nerf_mesh_vertex_count(const nerf_mesh *mesh);
/** Triangles of @p mesh (0 for NULL).  @since 0.5 */
NERF_API size_t nerf_mesh_face_count(const nerf_mesh *mesh);
/** vertex_count x 3 floats, x y z; NULL for an empty mesh.  @since 0.5 */
NERF_API const float *nerf_mesh_vertices(const nerf_mesh *mesh);
/** face_count x 3 vertex indices; NULL for an empty mesh.  @since 0.5 */
NERF_API const uint32_t *nerf_mesh_faces(const nerf_mesh *mesh);
/** vertex_count x 3 unit normals, or NULL.  @since 0.5 */
NERF_API const float *nerf_mesh_normals(const nerf_mesh *mesh);
/** vertex_count x 3 bytes r g b, or NULL (colour NONE).  @since 0.5 */
NERF_API const uint8_t *nerf_mesh_colours(const nerf_mesh *mesh);

/**
 * Write @p mesh to @p path in nerf_mesh_format @p format,
 * through a temporary file renamed over @p path.  PLY files carry
 * vertices (float x y z, float nx ny nz, uchar red green blue when the
 * mesh has them) and faces (uchar count, uint indices).
 * @return NERF_OK; NERF_EINVAL (NULL argument, unknown format, AUTO with
 * an extension other than .ply or .obj); NERF_EIO naming @p path;
 * NERF_ENOMEM.
 * @since 0.5
 */
NERF_API int nerf_mesh_write(const nerf_mesh *mesh, const char *path,
                             int format);

/* ===========================================================================
 * 15. Point clouds
 * ======================================================================== */

/** Default nerf_points_options.opacity_threshold.  @since 0.5 */
#define NERF_POINTS_DEFAULT_OPACITY 0.9f
/** Default nerf_points_options.max_points.  @since 0.5 */
#define NERF_POINTS_DEFAULT_MAX 1000000u

/**
 * How nerf_points_from_views() turns rendered views into
 * points.  Versioned: fill with nerf_points_options_init().
 * @since 0.5
 */
typedef struct nerf_points_options {
    uint32_t struct_size;      /**< Set by nerf_points_options_init(). */
    float opacity_threshold;   /**< A ray gives a point when its opacity is
                                    >= this, in [0, 1]; default
                                    NERF_POINTS_DEFAULT_OPACITY (0.9).  0
                                    keeps every ray but those of opacity 0
                                    (which have no depth). */
    uint64_t max_points;       /**< At most this many points, >= 1; default
                                    NERF_POINTS_DEFAULT_MAX (10^6).  Beyond
                                    it the points are thinned evenly in ray
                                    order (see nerf_points_from_views()). */
    uint32_t stride;           /**< Render each view at 1/stride of its
                                    resolution over the same field of view
                                    (one ray per stride x stride pixels),
                                    1..1024; default 1. */
    uint32_t reserved0;        /**< Must be 0. */
    const nerf_hooks *hooks;   /**< Allocation and logging of the point
                                    cloud; NULL = defaults. */
    nerf_progress_cb progress; /**< NULL, or called on the calling thread
                                    after every chunk of rays (kind
                                    NERF_PROGRESS_RENDER; done and total
                                    count the rays of all views); nonzero
                                    cancels: NERF_ECANCELLED. */
    void *progress_user;       /**< Passed to progress. */
} nerf_points_options;

/**
 * Fill @p opts with defaults and record @p struct_size.
 * @return NERF_OK, or NERF_EINVAL for a NULL or too small struct.
 * @since 0.5
 */
NERF_API int nerf_points_options_init(nerf_points_options *opts,
                                      size_t struct_size);
/** A run-time call, not a constant initializer: see NERF_HOOKS_INIT. */
#define NERF_POINTS_OPTIONS_INIT(o) nerf_points_options_init((o), sizeof *(o))

/**
 * A point cloud from the expected depth of rendered views.
 *
 * Each view of @p cameras (scaled down by the stride: width and height
 * divided by it, rounded up, focal lengths and principal point divided by
 * it) is rendered with @p renderer as nerf_renderer_render_depth() does.
 * Every ray whose opacity reaches the threshold and whose depth is finite
 * gives one point at o + s d (the expected termination point), coloured
 * with the ray's rendered colour (round(255 clamp(c, 0, 1))).
 *
 * Each point gets a normal from its neighbours in the same view, oriented
 * toward the camera, or (0, 0, 0) (none) where a neighbour is missing or
 * lies across a depth discontinuity.  Beyond max_points, the points are
 * thinned evenly in ray order (views in order, pixels row by row), with
 * memory bounded by 2 max_points points (docs/api-notes.md, "Point cloud
 * normals and thinning").  The result depends only on the inputs, not on
 * threads or chunking.
 *
 * The renderer's own progress callback is not called during this call.
 *
 * @param out      the new point cloud (*out is NULL on failure).
 * @param renderer any renderer; its threads render the views.
 * @param cameras  @p n_cameras cameras, each initialised (struct_size set).
 * @param opts     NULL for the defaults.
 * @return NERF_OK (possibly with no points); NERF_EINVAL (NULL arguments,
 * n_cameras 0, an invalid camera, options out of range);
 * NERF_EVERSION; NERF_ENOMEM; NERF_ECANCELLED.
 * @since 0.5
 */
NERF_API int nerf_points_from_views(nerf_points **out,
                                    nerf_renderer *renderer,
                                    const nerf_camera *cameras,
                                    size_t n_cameras,
                                    const nerf_points_options *opts);

/** The number of points; 0 for NULL.  @since 0.5 */
NERF_API size_t nerf_points_count(const nerf_points *points);

/**
 * The point cloud's arrays, valid until nerf_points_destroy():
 * positions count x 3 floats (world units), colours count x 3 bytes (RGB),
 * normals count x 3 floats (unit length, or (0, 0, 0) where none could be
 * estimated).  Any output may be NULL.  With no points they are NULL.
 * @return NERF_OK, or NERF_EINVAL for a NULL point cloud.
 * @since 0.5
 */
NERF_API int nerf_points_arrays(const nerf_points *points,
                                const float **positions,
                                const uint8_t **colours,
                                const float **normals);

/** Formats of nerf_points_write().  @since 0.5 */
typedef enum nerf_points_format {
    NERF_POINTS_PLY_BINARY = 0, /**< PLY, binary little-endian. */
    NERF_POINTS_PLY_ASCII = 1   /**< PLY, ASCII. */
} nerf_points_format;

/**
 * Write @p points to @p path as a PLY file with one "vertex"
 * element of properties float x, y, z, float nx, ny, nz (0 0 0: no normal)
 * and uchar red, green, blue, through a temporary file renamed into place.
 * @return NERF_OK; NERF_EINVAL (NULL argument, unknown format); NERF_EIO
 * (the file cannot be written, named); NERF_ENOMEM.
 * @since 0.5
 */
NERF_API int nerf_points_write(const nerf_points *points, const char *path,
                               int format);

/** Release a point cloud.  NULL is a no-op.  @since 0.5 */
NERF_API void nerf_points_destroy(nerf_points *points);

/* ===========================================================================
 * 16. Density grids
 * ======================================================================== */

/**
 * Sample @p model's density on the grid of @p opts over its box
 * and write it to @p path as a float32 .npy of shape (nz, ny, nx): C order,
 * element [k][j][i] the density at x = x0 + (i + 0.5) (x1 - x0) / nx (and
 * so on): samples at the cell centres.  Beside it goes a JSON sidecar,
 * @p path with ".npy" replaced by ".json" (or ".json" appended), holding
 * the box, the shape, the axis order and the model's space
 * (docs/formats.md).  With opts->colour NORMAL, a (nz, ny, nx, 3) float32
 * .npy of colours in [0, 1] too, named as the sidecar with "_rgb.npy":
 * the colour seen looking down the density gradient.  The whole grid is
 * held in memory: 4 bytes a sample (16 with colour).  Uses resolution,
 * box, colour, threads, progress and hooks of @p opts (NULL: defaults).
 * @return NERF_OK; NERF_EINVAL as nerf_mesh_extract() and for a NULL
 * path; NERF_EIO naming the file; NERF_ECANCELLED; NERF_ENOMEM.
 * @since 0.5
 */
NERF_API int nerf_density_grid_write(const nerf_model *model,
                                     const char *path,
                                     const nerf_mesh_options *opts);

/* ===========================================================================
 * 17. Utilities: images, arrays and metrics
 * ======================================================================== */

/** Largest width or height, in pixels, that the image functions accept. */
#define NERF_IMAGE_MAX_SIDE 16384

/**
 * Read a PNG file of any colour type (gray, gray+alpha, RGB, RGBA,
 * palette) and bit depth (1 to 16) into RGBA floats in [0, 1].
 *
 * @param rgba_out receives width x height x 4 floats, row-major from the
 *        top-left pixel, channels interleaved, straight (not premultiplied)
 *        alpha; opaque files get alpha 1.  Allocated by libnerf with the
 *        default allocator: release it with nerf_free().  Set to NULL on
 *        failure.
 *
 * 8-bit samples are returned as stored (v / 255).  16-bit samples go
 * through libpng's linear format: v / 65535 when the file has no gAMA or
 * sRGB chunk (the usual case), converted to linear light when it has one;
 * libpng premultiplies those by alpha, so the colour of a fully
 * transparent 16-bit pixel reads as 0.
 *
 * @return NERF_OK; NERF_EINVAL (NULL argument); NERF_ENOENT (no such
 * file); NERF_EUNRECOGNISED (not a regular file: a folder, a FIFO, a
 * device, refused without blocking); NERF_EIO (the file cannot be opened
 * or read); NERF_EFORMAT (not a PNG, truncated, corrupted, a side larger
 * than NERF_IMAGE_MAX_SIDE, or a header claiming more pixels than the
 * file can hold: refused before anything is allocated for them);
 * NERF_ENOMEM.  Messages start with the path.  Reentrant.
 */
NERF_API int nerf_image_read_png(const char *path, uint32_t *width_out,
                                 uint32_t *height_out, float **rgba_out);

/**
 * Read a PNG or a JPEG file, told apart by its first bytes
 * (not its name), as the dataset loaders do.  PNGs are read as by
 * nerf_image_read_png().  JPEGs (baseline, progressive or arithmetic
 * coded; YCbCr, RGB or grayscale) give v / 255 of the decoded 8-bit RGB
 * samples and alpha 1, turned upright by the Exif Orientation tag (1 to 8;
 * width and height are those of the upright picture, swapped for 5 to 8).
 *
 * @param rgba_out as for nerf_image_read_png(); release with nerf_free().
 * @return NERF_OK; NERF_EINVAL (NULL argument); NERF_ENOENT (no such
 * file); NERF_EUNRECOGNISED (not a regular file: a folder, a FIFO, a
 * device, refused without blocking); NERF_EIO (the file cannot be opened
 * or read); NERF_EFORMAT (neither a PNG nor a JPEG, truncated or
 * corrupted data (JPEG decoder warnings about the data count as errors),
 * a CMYK or YCCK JPEG, a malformed Exif block or an Orientation outside 1
 * to 8, a side larger than NERF_IMAGE_MAX_SIDE, a header claiming more
 * pixels than the file can hold); NERF_ENOMEM.  Messages start with the
 * path.  Reentrant.
 * @since 0.3
 */
NERF_API int nerf_image_read(const char *path, uint32_t *width_out,
                             uint32_t *height_out, float **rgba_out);

/**
 * Write an 8-bit PNG from float samples: each value is clamped to [0, 1]
 * and rounded to the nearest of 256 levels (NaN gives 0).  Use channels 1
 * for depth or opacity maps (scale them into [0, 1] first).
 *
 * @param channels 1 (gray), 3 (RGB) or 4 (RGBA).
 * @param pixels   width x height x channels floats, row-major from the
 *                 top-left pixel, channels interleaved.
 *
 * The file is written to a temporary name beside @p path, flushed and
 * renamed, so an existing file at @p path is only ever replaced by a
 * complete image.
 * @return NERF_OK; NERF_EINVAL (NULL pointer, zero size or a side above
 * NERF_IMAGE_MAX_SIDE, bad channel count); NERF_EIO; NERF_ENOMEM.
 * Reentrant.
 */
NERF_API int nerf_image_write_png(const char *path, uint32_t width,
                                  uint32_t height, uint32_t channels,
                                  const float *pixels);

/**
 * As nerf_image_write_png(), from 8-bit samples written as they are.
 * @param pixels width x height x channels bytes, row-major, interleaved.
 * @return as nerf_image_write_png().
 */
NERF_API int nerf_image_write_png8(const char *path, uint32_t width,
                                   uint32_t height, uint32_t channels,
                                   const uint8_t *pixels);

/**
 * Release a buffer that a libnerf function allocated for the caller (such
 * as the pixels of nerf_image_read_png()).  NULL is a no-op.  Never pass
 * it memory from anywhere else, nor buffers owned by a handle.
 */
NERF_API void nerf_free(void *ptr);

/**
 * Write @p data, an array of @p ndim (1..4) dimensions of the
 * given @p shape in C order (row-major), as a NumPy .npy file (format 1.0,
 * dtype '<f4', the header NumPy itself writes), through a temporary file
 * renamed into place.  numpy.load() reads it back.
 * @return NERF_OK; NERF_EINVAL (NULL path or shape, NULL data with a
 * non-empty shape, ndim out of range); NERF_EIO (named path); NERF_ENOMEM.
 * Reentrant.
 * @since 0.5
 */
NERF_API int nerf_npy_write_float(const char *path, const float *data,
                                  const size_t *shape, uint32_t ndim);

/**
 * Peak signal-to-noise ratio of two images with values in [0, 1]:
 * -10 log10(MSE), the mean taken over all @p count samples (every channel
 * of every pixel).  Identical images give +infinity (IEEE HUGE_VAL), not a
 * cap.
 * @param a, b  @p count floats each, in any layout (the same for both).
 * @param out   receives the PSNR in decibels.
 * @return NERF_OK; NERF_EINVAL (NULL pointer, count 0, NaN or infinite
 * values).  Reentrant.
 */
NERF_API int nerf_psnr(const float *a, const float *b, size_t count,
                       double *out);

/**
 * Structural similarity (Wang et al. 2004) as the reference NeRF
 * evaluation computes it: an 11 x 11 Gaussian window with sigma 1.5,
 * K1 = 0.01, K2 = 0.03, data range 1; local means, variances and
 * covariance by separable filtering over 'valid' positions only (no
 * padding: (width - 10) x (height - 10) windows), population (not sample)
 * variances; the SSIM map is averaged over those positions and over the
 * channels, each channel computed on its own.  Computed in double
 * precision; memory used is O(width), whatever the height.
 *
 * @param a, b      width x height x channels floats in [0, 1], row-major,
 *                  channels interleaved.
 * @param channels  1..4 (3 for RGB).
 * @param out       receives the mean SSIM, 1 for identical images.
 * @return NERF_OK; NERF_EINVAL (NULL pointer, width or height below 11,
 * bad channel count, NaN or infinite values); NERF_ENOMEM.  Reentrant.
 */
NERF_API int nerf_ssim(const float *a, const float *b, uint32_t width,
                       uint32_t height, uint32_t channels, double *out);

/**
 * nerf_psnr() over the pixels @p mask keeps: the mean squared error of
 * every channel of the pixels whose mask byte is nonzero (a dataset's
 * mask, nerf_dataset_mask()).
 * @param a, b     @p pixels x @p channels floats, channels interleaved.
 * @param mask     @p pixels bytes, 0 = leave the pixel out.
 * @param channels 1..4.
 * @return NERF_OK; NERF_EINVAL (NULL pointer, pixels 0, bad channel
 * count, NaN or infinite values, a mask that keeps no pixel).  Reentrant.
 * @since 0.13
 */
NERF_API int nerf_psnr_masked(const float *a, const float *b,
                              const uint8_t *mask, size_t pixels,
                              uint32_t channels, double *out);

/**
 * nerf_ssim() over the pixels @p mask keeps: the SSIM map averaged over
 * the 11 x 11 windows that hold no left-out pixel (mask byte 0), so that a
 * left-out pixel changes nothing.  With a mask of all ones it equals
 * nerf_ssim().
 * @param mask width x height bytes, row-major.
 * @return NERF_OK; NERF_EINVAL (as nerf_ssim(), a NULL mask, no window
 * free of left-out pixels); NERF_ENOMEM.  Reentrant.
 * @since 0.13
 */
NERF_API int nerf_ssim_masked(const float *a, const float *b,
                              const uint8_t *mask, uint32_t width,
                              uint32_t height, uint32_t channels,
                              double *out);

/* ===========================================================================
 * 18. Baked models
 * ======================================================================== */

typedef struct nerf_bake nerf_bake; /**< A model baked for fast renders. */

/**
 * Options of nerf_bake_create().  Versioned: fill with
 * nerf_bake_options_init() (or NERF_BAKE_OPTIONS_INIT), then set fields.
 * @since 0.14
 */
typedef struct nerf_bake_options {
    uint32_t struct_size;   /**< Set by nerf_bake_options_init(). */
    uint32_t subdivisions;  /**< Baked voxels along each edge of an
                                 occupancy cell, 1..16; default 6 (a
                                 128-cell grid bakes at 768 voxels
                                 across; before 0.15, 4). */
    uint32_t sh_degree;     /**< Degree of the spherical harmonics that
                                 hold each point's colour as seen from
                                 every direction, 0..2 (0: one colour
                                 whatever the view); default 1. */
    uint32_t directions;    /**< Directions each point's colour is
                                 evaluated in to fit them, at least
                                 (sh_degree + 1)^2, at most 1024; default
                                 8.  The bake's time grows with it. */
    uint64_t max_bytes;     /**< Refuse a bake larger than this (NERF_ENOMEM,
                                 saying how large it would be); default
                                 2 GiB. */
    uint32_t march_steps;   /**< Steps of a render across the bound's
                                 diagonal; default 512 (before 0.15, 0);
                                 0: steps of one voxel's edge. */
    uint32_t appearance;    /**< Which appearance code colours the bake
                                 (nerf_renderer_options.appearance):
                                 NERF_APPEARANCE_NEUTRAL (the default) or a
                                 training image's. */
    nerf_progress_cb progress; /**< NULL, or called as the bake goes (kind
                                 NERF_PROGRESS_BAKE); nonzero cancels with
                                 NERF_ECANCELLED. */
    void *progress_user;    /**< Passed to progress. */
    const nerf_hooks *hooks; /**< Allocation and logging; NULL = defaults. */
} nerf_bake_options;

/**
 * Fill @p opts with the defaults and record @p struct_size (or use
 * NERF_BAKE_OPTIONS_INIT).
 * @return NERF_OK, or NERF_EINVAL for a NULL or too small struct.
 * @since 0.14
 */
NERF_API int nerf_bake_options_init(nerf_bake_options *opts,
                                    size_t struct_size);
#define NERF_BAKE_OPTIONS_INIT(o) nerf_bake_options_init((o), sizeof *(o))

/**
 * Bake @p model: on every cell its occupancy grid marks occupied, the
 * density and the colour as seen from every direction (fitted with
 * spherical harmonics) at the corners of subdivisions^3 voxels, so that a
 * render looks them up instead of evaluating the networks
 * (docs/viewer.md, "The baked model").  The bake copies what it needs: the
 * model may change or go afterwards.  The renders composite on the
 * model's recorded background (nerf_model_render_settings()).
 *
 * Bakes a model with an occupancy grid (the fast preset) whose space is a
 * box (a Blender-like scene, the built-in one) or NDC (a forward-facing
 * scene, marched in the frustum its trainer recorded); other models
 * (without a grid, or unbounded) are refused with NERF_EINVAL, saying
 * why.
 * @return NERF_OK; NERF_EINVAL (NULL argument, options out of range, a
 * model it cannot bake, weights that are not finite); NERF_ENOMEM (out of
 * memory, or a bake above max_bytes); NERF_ECANCELLED; NERF_EVERSION for
 * an options struct from a newer header with non-zero unknown fields.
 * @since 0.14
 */
NERF_API int nerf_bake_create(nerf_bake **out, const nerf_model *model,
                              const nerf_bake_options *opts);

/** Release a bake.  NULL is a no-op.  @since 0.14 */
NERF_API void nerf_bake_destroy(nerf_bake *bake);

/** What a bake holds: nerf_bake_stats(). @since 0.14 */
typedef struct nerf_bake_stats {
    uint32_t struct_size;   /**< Set by the caller (sizeof). */
    uint32_t resolution;    /**< Voxels across the bound. */
    uint64_t bricks;        /**< Occupancy cells baked. */
    uint64_t points;        /**< Points whose colour was fitted. */
    uint64_t bytes;         /**< Memory the bake holds. */
} nerf_bake_stats;

/**
 * Fill @p stats (its struct_size set by the caller).
 * @return NERF_OK, or NERF_EINVAL (NULL argument or bad struct).
 * @since 0.14
 */
NERF_API int nerf_bake_stats_get(const nerf_bake *bake,
                                 nerf_bake_stats *stats);

/**
 * Render every pixel of @p camera from the bake, with the outputs of
 * nerf_renderer_render_image() (colour composited on the background,
 * depth as sum(w t) along the unnormalised ray, opacity).  Work is spread
 * over the library's threads; the output is the same bits for every
 * thread count.  Reentrant: several threads may render one bake at once.
 * @return NERF_OK; NERF_EINVAL (NULL bake or camera, invalid camera, all
 * outputs NULL, capacity too small); NERF_EVERSION as
 * nerf_renderer_render_image().
 * @since 0.14
 */
NERF_API int nerf_bake_render_image(const nerf_bake *bake,
                                    const nerf_camera *camera,
                                    float *rgb_out, float *depth_out,
                                    float *opacity_out,
                                    size_t pixel_capacity);

#ifdef __cplusplus
}
#endif

#endif /* NERF_H */
