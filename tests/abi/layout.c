/*
 * Frozen layouts of the public structs on LP64.  A failing assertion here
 * means a change broke the ABI: fields may only be appended, and only with
 * a new assertion for each.
 */
#include <nerf.h>

#include <stddef.h>
#include <stdint.h>
#include <stdio.h>

#define FROZEN(type, field, off) \
    _Static_assert(offsetof(type, field) == (off), #type "." #field " moved")
#define SIZE(type, size) _Static_assert(sizeof(type) == (size), #type " resized")

#if UINTPTR_MAX == UINT64_MAX

FROZEN(nerf_hooks, struct_size, 0);
FROZEN(nerf_hooks, log_level, 4);
FROZEN(nerf_hooks, alloc, 8);
FROZEN(nerf_hooks, free, 16);
FROZEN(nerf_hooks, alloc_user, 24);
FROZEN(nerf_hooks, log_cb, 32);
FROZEN(nerf_hooks, log_user, 40);
SIZE(nerf_hooks, 48);

FROZEN(nerf_model_options, struct_size, 0);
FROZEN(nerf_model_options, encoding, 4);
FROZEN(nerf_model_options, pos_frequencies, 8);
FROZEN(nerf_model_options, dir_frequencies, 12);
FROZEN(nerf_model_options, encoding_flags, 16);
FROZEN(nerf_model_options, depth, 20);
FROZEN(nerf_model_options, width, 24);
FROZEN(nerf_model_options, skip_layer, 28);
FROZEN(nerf_model_options, view_width, 32);
FROZEN(nerf_model_options, use_viewdirs, 36);
FROZEN(nerf_model_options, use_fine, 40);
FROZEN(nerf_model_options, reserved0, 44);
FROZEN(nerf_model_options, seed, 48);
FROZEN(nerf_model_options, hooks, 56);
/* Appended in 0.2. */
FROZEN(nerf_model_options, dir_encoding, 64);
FROZEN(nerf_model_options, sh_degree, 68);
FROZEN(nerf_model_options, hash_levels, 72);
FROZEN(nerf_model_options, hash_features, 76);
FROZEN(nerf_model_options, hash_log2_size, 80);
FROZEN(nerf_model_options, hash_min_resolution, 84);
FROZEN(nerf_model_options, hash_max_resolution, 88);
FROZEN(nerf_model_options, bound, 92);
FROZEN(nerf_model_options, geo_features, 96);
FROZEN(nerf_model_options, view_depth, 100);
FROZEN(nerf_model_options, density_activation, 104);
/* matmul took the place of reserved1, which had to be 0 (fp32). */
FROZEN(nerf_model_options, matmul, 108);
FROZEN(nerf_model_options, space, 112);
/* Appended in 0.12: reserved2 took the padding before learning_rate. */
FROZEN(nerf_model_options, reserved2, 116);
FROZEN(nerf_model_options, learning_rate, 120);
SIZE(nerf_model_options, 128);

FROZEN(nerf_scene_options, struct_size, 0);
FROZEN(nerf_scene_options, width, 4);
FROZEN(nerf_scene_options, height, 8);
FROZEN(nerf_scene_options, n_train, 12);
FROZEN(nerf_scene_options, n_val, 16);
FROZEN(nerf_scene_options, n_test, 20);
FROZEN(nerf_scene_options, threads, 24);
/* reserved0 until 0.13. */
FROZEN(nerf_scene_options, appearance, 28);
FROZEN(nerf_scene_options, seed, 32);
FROZEN(nerf_scene_options, hooks, 40);
FROZEN(nerf_scene_options, capture, 48);
FROZEN(nerf_scene_options, layout, 52);
FROZEN(nerf_scene_options, image_format, 56);
FROZEN(nerf_scene_options, jpeg_quality, 60);
FROZEN(nerf_scene_options, k1, 64);
FROZEN(nerf_scene_options, k2, 68);
FROZEN(nerf_scene_options, p1, 72);
FROZEN(nerf_scene_options, p2, 76);
FROZEN(nerf_scene_options, k3, 80);
/* Appended in 0.13: occluders took the padding after k3. */
FROZEN(nerf_scene_options, occluders, 84);
FROZEN(nerf_scene_options, texture, 88);
FROZEN(nerf_scene_options, reserved1, 92);
SIZE(nerf_scene_options, 96);

FROZEN(nerf_camera, struct_size, 0);
FROZEN(nerf_camera, flags, 4);
FROZEN(nerf_camera, width, 8);
FROZEN(nerf_camera, height, 12);
FROZEN(nerf_camera, c2w, 16);
FROZEN(nerf_camera, fx, 64);
FROZEN(nerf_camera, fy, 68);
FROZEN(nerf_camera, cx, 72);
FROZEN(nerf_camera, cy, 76);
/* Appended in 0.2. */
FROZEN(nerf_camera, k1, 80);
FROZEN(nerf_camera, k2, 84);
FROZEN(nerf_camera, p1, 88);
FROZEN(nerf_camera, p2, 92);
FROZEN(nerf_camera, k3, 96);
SIZE(nerf_camera, 100);

FROZEN(nerf_camera_path_options, struct_size, 0);
FROZEN(nerf_camera_path_options, width, 4);
FROZEN(nerf_camera_path_options, height, 8);
FROZEN(nerf_camera_path_options, flags, 12);
FROZEN(nerf_camera_path_options, focal, 16);
FROZEN(nerf_camera_path_options, fov_x, 20);
FROZEN(nerf_camera_path_options, hooks, 24);
SIZE(nerf_camera_path_options, 32);

FROZEN(nerf_sampler_options, struct_size, 0);
FROZEN(nerf_sampler_options, n_coarse, 4);
FROZEN(nerf_sampler_options, n_fine, 8);
FROZEN(nerf_sampler_options, perturb, 12);
FROZEN(nerf_sampler_options, lindisp, 16);
FROZEN(nerf_sampler_options, paper_bins, 20);
FROZEN(nerf_sampler_options, ndc, 24);
FROZEN(nerf_sampler_options, reserved0, 28);
FROZEN(nerf_sampler_options, t_near, 32);
FROZEN(nerf_sampler_options, t_far, 36);
FROZEN(nerf_sampler_options, ndc_focal, 40);
FROZEN(nerf_sampler_options, ndc_width, 44);
FROZEN(nerf_sampler_options, ndc_height, 48);
FROZEN(nerf_sampler_options, reserved1, 52);
FROZEN(nerf_sampler_options, seed, 56);
FROZEN(nerf_sampler_options, hooks, 64);
/* Appended in 0.2. */
FROZEN(nerf_sampler_options, march_steps, 72);
FROZEN(nerf_sampler_options, max_samples, 76);
SIZE(nerf_sampler_options, 80);

FROZEN(nerf_progress, struct_size, 0);
FROZEN(nerf_progress, kind, 4);
FROZEN(nerf_progress, done, 8);
FROZEN(nerf_progress, total, 16);
FROZEN(nerf_progress, elapsed, 24);
FROZEN(nerf_progress, loss, 32);
FROZEN(nerf_progress, psnr, 40);
SIZE(nerf_progress, 48);

FROZEN(nerf_renderer_options, struct_size, 0);
FROZEN(nerf_renderer_options, white_background, 4);
FROZEN(nerf_renderer_options, raw_noise_std, 8);
FROZEN(nerf_renderer_options, chunk_rays, 12);
FROZEN(nerf_renderer_options, threads, 16);
/* reserved0 until 0.13. */
FROZEN(nerf_renderer_options, appearance, 20);
FROZEN(nerf_renderer_options, hooks, 24);
SIZE(nerf_renderer_options, 32);

/* Since 0.5. */
FROZEN(nerf_points_options, struct_size, 0);
FROZEN(nerf_points_options, opacity_threshold, 4);
FROZEN(nerf_points_options, max_points, 8);
FROZEN(nerf_points_options, stride, 16);
FROZEN(nerf_points_options, reserved0, 20);
FROZEN(nerf_points_options, hooks, 24);
FROZEN(nerf_points_options, progress, 32);
FROZEN(nerf_points_options, progress_user, 40);
SIZE(nerf_points_options, 48);

FROZEN(nerf_mesh_options, struct_size, 0);
FROZEN(nerf_mesh_options, resolution, 4);
FROZEN(nerf_mesh_options, threshold, 8);
FROZEN(nerf_mesh_options, box, 12);
FROZEN(nerf_mesh_options, colour, 36);
FROZEN(nerf_mesh_options, keep_largest, 40);
FROZEN(nerf_mesh_options, min_component_faces, 44);
FROZEN(nerf_mesh_options, threads, 48);
FROZEN(nerf_mesh_options, reserved0, 52);
FROZEN(nerf_mesh_options, progress, 56);
FROZEN(nerf_mesh_options, progress_user, 64);
FROZEN(nerf_mesh_options, hooks, 72);
SIZE(nerf_mesh_options, 80);

FROZEN(nerf_bake_options, struct_size, 0);
FROZEN(nerf_bake_options, subdivisions, 4);
FROZEN(nerf_bake_options, sh_degree, 8);
FROZEN(nerf_bake_options, directions, 12);
FROZEN(nerf_bake_options, max_bytes, 16);
FROZEN(nerf_bake_options, march_steps, 24);
FROZEN(nerf_bake_options, appearance, 28);
FROZEN(nerf_bake_options, progress, 32);
FROZEN(nerf_bake_options, progress_user, 40);
FROZEN(nerf_bake_options, hooks, 48);
SIZE(nerf_bake_options, 56);

FROZEN(nerf_bake_stats, struct_size, 0);
FROZEN(nerf_bake_stats, resolution, 4);
FROZEN(nerf_bake_stats, bricks, 8);
FROZEN(nerf_bake_stats, points, 16);
FROZEN(nerf_bake_stats, bytes, 24);
SIZE(nerf_bake_stats, 32);

FROZEN(nerf_dataset_options, struct_size, 0);
FROZEN(nerf_dataset_options, split, 4);
FROZEN(nerf_dataset_options, downscale, 8);
FROZEN(nerf_dataset_options, skip, 12);
FROZEN(nerf_dataset_options, white_background, 16);
FROZEN(nerf_dataset_options, skip_missing, 20);
FROZEN(nerf_dataset_options, llff_holdout, 24);
FROZEN(nerf_dataset_options, forward_facing, 28);
FROZEN(nerf_dataset_options, hooks, 32);
FROZEN(nerf_dataset_options, ignore_masks, 40);
SIZE(nerf_dataset_options, 48);

FROZEN(nerf_trainer_options, struct_size, 0);
FROZEN(nerf_trainer_options, batch_rays, 4);
FROZEN(nerf_trainer_options, precrop_steps, 8);
FROZEN(nerf_trainer_options, precrop_fraction, 12);
FROZEN(nerf_trainer_options, raw_noise_std, 16);
FROZEN(nerf_trainer_options, white_background, 20);
FROZEN(nerf_trainer_options, checkpoint_every, 24);
FROZEN(nerf_trainer_options, reserved0, 28);
FROZEN(nerf_trainer_options, checkpoint_path, 32);
FROZEN(nerf_trainer_options, hooks, 40);
/* Appended in 0.2. */
FROZEN(nerf_trainer_options, batch_samples, 48);
FROZEN(nerf_trainer_options, random_background, 52);
/* Appended in 0.5. */
FROZEN(nerf_trainer_options, worker_rank, 56);
FROZEN(nerf_trainer_options, worker_count, 60);
FROZEN(nerf_trainer_options, grad_hook, 64);
FROZEN(nerf_trainer_options, checksum_hook, 72);
FROZEN(nerf_trainer_options, hook_user, 80);
FROZEN(nerf_trainer_options, checksum_every, 88);
FROZEN(nerf_trainer_options, reserved1, 92);
/* Appended in 0.6. */
FROZEN(nerf_trainer_options, checkpoint_seconds, 96);
/* Appended in 0.12. */
FROZEN(nerf_trainer_options, render_march_steps, 104);
/* reserved2 until 0.13. */
FROZEN(nerf_trainer_options, appearance_codes, 108);
SIZE(nerf_trainer_options, 112);

/* New in 0.5. */
FROZEN(nerf_exchange, struct_size, 0);
FROZEN(nerf_exchange, worker_rank, 4);
FROZEN(nerf_exchange, worker_count, 8);
FROZEN(nerf_exchange, n_sparse, 12);
FROZEN(nerf_exchange, step, 16);
FROZEN(nerf_exchange, sparse_begin, 24);
FROZEN(nerf_exchange, sparse_end, 56);
FROZEN(nerf_exchange, rays, 88);
FROZEN(nerf_exchange, batch_rays, 96);
FROZEN(nerf_exchange, message, 104);
SIZE(nerf_exchange, 360);

FROZEN(nerf_train_stats, struct_size, 0);
FROZEN(nerf_train_stats, reserved0, 4);
FROZEN(nerf_train_stats, step, 8);
FROZEN(nerf_train_stats, loss, 16);
FROZEN(nerf_train_stats, psnr, 24);
FROZEN(nerf_train_stats, psnr_coarse, 32);
FROZEN(nerf_train_stats, learning_rate, 40);
/* Appended in 0.2. */
FROZEN(nerf_train_stats, samples_per_ray, 48);
FROZEN(nerf_train_stats, rays, 56);
SIZE(nerf_train_stats, 64);

/* Since 0.5. */
FROZEN(nerf_schedule, struct_size, 0);
FROZEN(nerf_schedule, state, 4);
FROZEN(nerf_schedule, budget_seconds, 8);
FROZEN(nerf_schedule, steps_per_second, 16);
FROZEN(nerf_schedule, fit_step, 24);
FROZEN(nerf_schedule, total_steps, 32);
SIZE(nerf_schedule, 40);

#endif

/* Status codes and enum values are ABI too. */
_Static_assert(NERF_OK == 0 && NERF_ERROR == -1 && NERF_EINVAL == -2 &&
               NERF_ENOMEM == -3 && NERF_EIO == -4 && NERF_EFORMAT == -5 &&
               NERF_ECANCELLED == -6 && NERF_EVERSION == -7 &&
               NERF_ENOENT == -8 && NERF_EUNRECOGNISED == -9,
               "status codes renumbered");
_Static_assert(NERF_PARAM_LEARNING_RATE == 100 && NERF_PARAM_ADAM_EPS == 105,
               "parameter keys renumbered");
_Static_assert(NERF_PRESET_REFERENCE == 1 && NERF_PRESET_TINY == 2,
               "presets renumbered");
_Static_assert(NERF_CAMERA_PATH_FILE_SIZE == 0x1u &&
               NERF_CAMERA_PATH_FILE_INTRINSICS == 0x2u,
               "camera path flags renumbered");
_Static_assert(NERF_CAMERA_PIXEL_CORNER == 0x1u &&
               NERF_SAMPLE_TRAINING == 0x1u && NERF_PROGRESS_RENDER == 1,
               "render flags renumbered");

_Static_assert(NERF_MODEL_HAS_OPTIMIZER == 0x1u &&
               NERF_MODEL_HAS_OCCUPANCY == 0x2u &&
               NERF_MODEL_HAS_RENDER_SETTINGS == 0x4u &&
               NERF_MODEL_HAS_DATA_RECORD == 0x8u &&
               NERF_MODEL_HAS_NONFINITE_WEIGHTS == 0x40u,
               "model content bits renumbered");

_Static_assert(NERF_SPLIT_TRAIN == 0 && NERF_SPLIT_VAL == 1 &&
               NERF_SPLIT_TEST == 2, "splits renumbered");
_Static_assert(NERF_DATASET_BLENDER == 1 && NERF_DATASET_LLFF == 2,
               "dataset formats renumbered");
_Static_assert(NERF_IMAGE_MAX_SIDE == 16384, "image size limit changed");
_Static_assert(NERF_POINTS_PLY_BINARY == 0 && NERF_POINTS_PLY_ASCII == 1,
               "point cloud formats renumbered");
_Static_assert(NERF_PROGRESS_GEOMETRY == 3 && NERF_MESH_COLOUR_NORMAL == 1 &&
               NERF_MESH_FORMAT_PLY == 1 && NERF_MESH_FORMAT_PLY_ASCII == 2 &&
               NERF_MESH_FORMAT_OBJ == 3, "geometry enums renumbered");

int main(void)
{
    printf("ok   public struct layouts%s\n",
           UINTPTR_MAX == UINT64_MAX ? "" : " (not LP64: only enums checked)");
    return 0;
}
