/*
 * layout_probe: print the size and the offset and size of every field of
 * every public struct of nerf.h, and the values of the public constants,
 * as one JSON object.  tests/test_layout.py compares them with the ctypes
 * mirrors of the Python binding.
 *
 * Output: {"structs": {"nerf_hooks": {"size": 48, "fields":
 *          {"struct_size": [0, 4], ...}}, ...}, "constants": {...}}
 */
#include <nerf.h>

#include <stddef.h>
#include <stdio.h>

static int first_struct = 1;
static int first_field;
static int first_const = 1;

static void begin_struct(const char *name, size_t size)
{
    printf("%s\n  \"%s\": {\"size\": %zu, \"fields\": {", first_struct ? "" : ",",
           name, size);
    first_struct = 0;
    first_field = 1;
}

static void field(const char *name, size_t offset, size_t size)
{
    printf("%s\"%s\": [%zu, %zu]", first_field ? "" : ", ", name, offset,
           size);
    first_field = 0;
}

static void end_struct(void)
{
    printf("}}");
}

static void constant(const char *name, long long value)
{
    printf("%s\n  \"%s\": %lld", first_const ? "" : ",", name, value);
    first_const = 0;
}

#define BEGIN(type) begin_struct(#type, sizeof(type))
#define FIELD(type, f) field(#f, offsetof(type, f), sizeof(((type *)0)->f))
#define CONST(name) constant(#name, (long long)(name))

static void structs(void)
{
    BEGIN(nerf_hooks);
    FIELD(nerf_hooks, struct_size);
    FIELD(nerf_hooks, log_level);
    FIELD(nerf_hooks, alloc);
    FIELD(nerf_hooks, free);
    FIELD(nerf_hooks, alloc_user);
    FIELD(nerf_hooks, log_cb);
    FIELD(nerf_hooks, log_user);
    end_struct();

    BEGIN(nerf_model_options);
    FIELD(nerf_model_options, struct_size);
    FIELD(nerf_model_options, encoding);
    FIELD(nerf_model_options, pos_frequencies);
    FIELD(nerf_model_options, dir_frequencies);
    FIELD(nerf_model_options, encoding_flags);
    FIELD(nerf_model_options, depth);
    FIELD(nerf_model_options, width);
    FIELD(nerf_model_options, skip_layer);
    FIELD(nerf_model_options, view_width);
    FIELD(nerf_model_options, use_viewdirs);
    FIELD(nerf_model_options, use_fine);
    FIELD(nerf_model_options, reserved0);
    FIELD(nerf_model_options, seed);
    FIELD(nerf_model_options, hooks);
    FIELD(nerf_model_options, dir_encoding);
    FIELD(nerf_model_options, sh_degree);
    FIELD(nerf_model_options, hash_levels);
    FIELD(nerf_model_options, hash_features);
    FIELD(nerf_model_options, hash_log2_size);
    FIELD(nerf_model_options, hash_min_resolution);
    FIELD(nerf_model_options, hash_max_resolution);
    FIELD(nerf_model_options, bound);
    FIELD(nerf_model_options, geo_features);
    FIELD(nerf_model_options, view_depth);
    FIELD(nerf_model_options, density_activation);
    FIELD(nerf_model_options, matmul);
    FIELD(nerf_model_options, space);
    FIELD(nerf_model_options, reserved2);
    FIELD(nerf_model_options, learning_rate);
    end_struct();

    BEGIN(nerf_scene_options);
    FIELD(nerf_scene_options, struct_size);
    FIELD(nerf_scene_options, width);
    FIELD(nerf_scene_options, height);
    FIELD(nerf_scene_options, n_train);
    FIELD(nerf_scene_options, n_val);
    FIELD(nerf_scene_options, n_test);
    FIELD(nerf_scene_options, threads);
    FIELD(nerf_scene_options, appearance);
    FIELD(nerf_scene_options, seed);
    FIELD(nerf_scene_options, hooks);
    FIELD(nerf_scene_options, capture);
    FIELD(nerf_scene_options, layout);
    FIELD(nerf_scene_options, image_format);
    FIELD(nerf_scene_options, jpeg_quality);
    FIELD(nerf_scene_options, k1);
    FIELD(nerf_scene_options, k2);
    FIELD(nerf_scene_options, p1);
    FIELD(nerf_scene_options, p2);
    FIELD(nerf_scene_options, k3);
    FIELD(nerf_scene_options, occluders);
    FIELD(nerf_scene_options, texture);
    FIELD(nerf_scene_options, reserved1);
    end_struct();

    BEGIN(nerf_camera);
    FIELD(nerf_camera, struct_size);
    FIELD(nerf_camera, flags);
    FIELD(nerf_camera, width);
    FIELD(nerf_camera, height);
    FIELD(nerf_camera, c2w);
    FIELD(nerf_camera, fx);
    FIELD(nerf_camera, fy);
    FIELD(nerf_camera, cx);
    FIELD(nerf_camera, cy);
    FIELD(nerf_camera, k1);
    FIELD(nerf_camera, k2);
    FIELD(nerf_camera, p1);
    FIELD(nerf_camera, p2);
    FIELD(nerf_camera, k3);
    end_struct();

    BEGIN(nerf_sampler_options);
    FIELD(nerf_sampler_options, struct_size);
    FIELD(nerf_sampler_options, n_coarse);
    FIELD(nerf_sampler_options, n_fine);
    FIELD(nerf_sampler_options, perturb);
    FIELD(nerf_sampler_options, lindisp);
    FIELD(nerf_sampler_options, paper_bins);
    FIELD(nerf_sampler_options, ndc);
    FIELD(nerf_sampler_options, reserved0);
    FIELD(nerf_sampler_options, t_near);
    FIELD(nerf_sampler_options, t_far);
    FIELD(nerf_sampler_options, ndc_focal);
    FIELD(nerf_sampler_options, ndc_width);
    FIELD(nerf_sampler_options, ndc_height);
    FIELD(nerf_sampler_options, reserved1);
    FIELD(nerf_sampler_options, seed);
    FIELD(nerf_sampler_options, hooks);
    FIELD(nerf_sampler_options, march_steps);
    FIELD(nerf_sampler_options, max_samples);
    end_struct();

    BEGIN(nerf_progress);
    FIELD(nerf_progress, struct_size);
    FIELD(nerf_progress, kind);
    FIELD(nerf_progress, done);
    FIELD(nerf_progress, total);
    FIELD(nerf_progress, elapsed);
    FIELD(nerf_progress, loss);
    FIELD(nerf_progress, psnr);
    end_struct();

    BEGIN(nerf_renderer_options);
    FIELD(nerf_renderer_options, struct_size);
    FIELD(nerf_renderer_options, white_background);
    FIELD(nerf_renderer_options, raw_noise_std);
    FIELD(nerf_renderer_options, chunk_rays);
    FIELD(nerf_renderer_options, threads);
    FIELD(nerf_renderer_options, appearance);
    FIELD(nerf_renderer_options, hooks);
    end_struct();

    BEGIN(nerf_points_options);
    FIELD(nerf_points_options, struct_size);
    FIELD(nerf_points_options, opacity_threshold);
    FIELD(nerf_points_options, max_points);
    FIELD(nerf_points_options, stride);
    FIELD(nerf_points_options, reserved0);
    FIELD(nerf_points_options, hooks);
    FIELD(nerf_points_options, progress);
    FIELD(nerf_points_options, progress_user);
    end_struct();

    BEGIN(nerf_mesh_options);
    FIELD(nerf_mesh_options, struct_size);
    FIELD(nerf_mesh_options, resolution);
    FIELD(nerf_mesh_options, threshold);
    FIELD(nerf_mesh_options, box);
    FIELD(nerf_mesh_options, colour);
    FIELD(nerf_mesh_options, keep_largest);
    FIELD(nerf_mesh_options, min_component_faces);
    FIELD(nerf_mesh_options, threads);
    FIELD(nerf_mesh_options, reserved0);
    FIELD(nerf_mesh_options, progress);
    FIELD(nerf_mesh_options, progress_user);
    FIELD(nerf_mesh_options, hooks);
    end_struct();

    BEGIN(nerf_bake_options);
    FIELD(nerf_bake_options, struct_size);
    FIELD(nerf_bake_options, subdivisions);
    FIELD(nerf_bake_options, sh_degree);
    FIELD(nerf_bake_options, directions);
    FIELD(nerf_bake_options, max_bytes);
    FIELD(nerf_bake_options, march_steps);
    FIELD(nerf_bake_options, appearance);
    FIELD(nerf_bake_options, progress);
    FIELD(nerf_bake_options, progress_user);
    FIELD(nerf_bake_options, hooks);
    end_struct();

    BEGIN(nerf_bake_stats);
    FIELD(nerf_bake_stats, struct_size);
    FIELD(nerf_bake_stats, resolution);
    FIELD(nerf_bake_stats, bricks);
    FIELD(nerf_bake_stats, points);
    FIELD(nerf_bake_stats, bytes);
    end_struct();

    BEGIN(nerf_dataset_options);
    FIELD(nerf_dataset_options, struct_size);
    FIELD(nerf_dataset_options, split);
    FIELD(nerf_dataset_options, downscale);
    FIELD(nerf_dataset_options, skip);
    FIELD(nerf_dataset_options, white_background);
    FIELD(nerf_dataset_options, skip_missing);
    FIELD(nerf_dataset_options, llff_holdout);
    FIELD(nerf_dataset_options, forward_facing);
    FIELD(nerf_dataset_options, hooks);
    FIELD(nerf_dataset_options, ignore_masks);
    end_struct();

    BEGIN(nerf_trainer_options);
    FIELD(nerf_trainer_options, struct_size);
    FIELD(nerf_trainer_options, batch_rays);
    FIELD(nerf_trainer_options, precrop_steps);
    FIELD(nerf_trainer_options, precrop_fraction);
    FIELD(nerf_trainer_options, raw_noise_std);
    FIELD(nerf_trainer_options, white_background);
    FIELD(nerf_trainer_options, checkpoint_every);
    FIELD(nerf_trainer_options, reserved0);
    FIELD(nerf_trainer_options, checkpoint_path);
    FIELD(nerf_trainer_options, hooks);
    FIELD(nerf_trainer_options, batch_samples);
    FIELD(nerf_trainer_options, random_background);
    FIELD(nerf_trainer_options, worker_rank);
    FIELD(nerf_trainer_options, worker_count);
    FIELD(nerf_trainer_options, grad_hook);
    FIELD(nerf_trainer_options, checksum_hook);
    FIELD(nerf_trainer_options, hook_user);
    FIELD(nerf_trainer_options, checksum_every);
    FIELD(nerf_trainer_options, reserved1);
    FIELD(nerf_trainer_options, checkpoint_seconds);
    FIELD(nerf_trainer_options, render_march_steps);
    FIELD(nerf_trainer_options, appearance_codes);
    end_struct();

    BEGIN(nerf_exchange);
    FIELD(nerf_exchange, struct_size);
    FIELD(nerf_exchange, worker_rank);
    FIELD(nerf_exchange, worker_count);
    FIELD(nerf_exchange, n_sparse);
    FIELD(nerf_exchange, step);
    FIELD(nerf_exchange, sparse_begin);
    FIELD(nerf_exchange, sparse_end);
    FIELD(nerf_exchange, rays);
    FIELD(nerf_exchange, batch_rays);
    FIELD(nerf_exchange, message);
    end_struct();

    BEGIN(nerf_train_stats);
    FIELD(nerf_train_stats, struct_size);
    FIELD(nerf_train_stats, reserved0);
    FIELD(nerf_train_stats, step);
    FIELD(nerf_train_stats, loss);
    FIELD(nerf_train_stats, psnr);
    FIELD(nerf_train_stats, psnr_coarse);
    FIELD(nerf_train_stats, learning_rate);
    FIELD(nerf_train_stats, samples_per_ray);
    FIELD(nerf_train_stats, rays);
    end_struct();

    BEGIN(nerf_schedule);
    FIELD(nerf_schedule, struct_size);
    FIELD(nerf_schedule, state);
    FIELD(nerf_schedule, budget_seconds);
    FIELD(nerf_schedule, steps_per_second);
    FIELD(nerf_schedule, fit_step);
    FIELD(nerf_schedule, total_steps);
    end_struct();

    BEGIN(nerf_camera_path_options);
    FIELD(nerf_camera_path_options, struct_size);
    FIELD(nerf_camera_path_options, width);
    FIELD(nerf_camera_path_options, height);
    FIELD(nerf_camera_path_options, flags);
    FIELD(nerf_camera_path_options, focal);
    FIELD(nerf_camera_path_options, fov_x);
    FIELD(nerf_camera_path_options, hooks);
    end_struct();
}

static void constants(void)
{
    CONST(NERF_OK);
    CONST(NERF_ERROR);
    CONST(NERF_EINVAL);
    CONST(NERF_ENOMEM);
    CONST(NERF_EIO);
    CONST(NERF_EFORMAT);
    CONST(NERF_ECANCELLED);
    CONST(NERF_EVERSION);
    CONST(NERF_ENOENT);
    CONST(NERF_EUNRECOGNISED);
    CONST(NERF_VERSION_MAJOR);
    CONST(NERF_LOG_ERROR);
    CONST(NERF_LOG_WARN);
    CONST(NERF_LOG_INFO);
    CONST(NERF_LOG_DEBUG);
    CONST(NERF_ENCODING_FREQUENCY);
    CONST(NERF_ENCODING_INCLUDE_INPUT);
    CONST(NERF_ENCODING_SCALE_PI);
    CONST(NERF_PRESET_REFERENCE);
    CONST(NERF_PRESET_TINY);
    CONST(NERF_MATMUL_FP32);
    CONST(NERF_MATMUL_BF16);
    CONST(NERF_MATMUL_FP32_ONEDNN);
    CONST(NERF_SPACE_BOX);
    CONST(NERF_SPACE_NDC);
    CONST(NERF_SPACE_UNBOUNDED);
    CONST(NERF_MODEL_HAS_OPTIMIZER);
    CONST(NERF_MODEL_HAS_OCCUPANCY);
    CONST(NERF_MODEL_HAS_RENDER_SETTINGS);
    CONST(NERF_MODEL_HAS_DATA_RECORD);
    CONST(NERF_NETWORK_COARSE);
    CONST(NERF_NETWORK_FINE);
    CONST(NERF_PARAM_LEARNING_RATE);
    CONST(NERF_PARAM_LEARNING_RATE_FINAL);
    CONST(NERF_PARAM_DECAY_STEPS);
    CONST(NERF_PARAM_ADAM_BETA1);
    CONST(NERF_PARAM_ADAM_BETA2);
    CONST(NERF_PARAM_ADAM_EPS);
    CONST(NERF_CAMERA_PIXEL_CORNER);
    CONST(NERF_SAMPLE_TRAINING);
    CONST(NERF_PROGRESS_RENDER);
    CONST(NERF_PROGRESS_TRAIN);
    CONST(NERF_SPLIT_TRAIN);
    CONST(NERF_SPLIT_VAL);
    CONST(NERF_SPLIT_TEST);
    CONST(NERF_DATASET_BLENDER);
    CONST(NERF_DATASET_LLFF);
    CONST(NERF_DATASET_COLMAP);
    CONST(NERF_SCENE_CAPTURE_OBJECT);
    CONST(NERF_SCENE_CAPTURE_FORWARD);
    CONST(NERF_SCENE_CAPTURE_UNBOUNDED);
    CONST(NERF_SCENE_LAYOUT_BLENDER);
    CONST(NERF_SCENE_LAYOUT_TRANSFORMS);
    CONST(NERF_SCENE_LAYOUT_LLFF);
    CONST(NERF_SCENE_LAYOUT_COLMAP_TEXT);
    CONST(NERF_SCENE_LAYOUT_COLMAP_BINARY);
    CONST(NERF_IMAGE_MAX_SIDE);
    CONST(NERF_CAMERA_PATH_FILE_SIZE);
    CONST(NERF_CAMERA_PATH_FILE_INTRINSICS);
    CONST(NERF_SCENE_LAYOUT_BLENDER);
    CONST(NERF_SCENE_LAYOUT_TRANSFORMS);
}

int main(void)
{
    printf("{\"structs\": {");
    structs();
    printf("\n},\n\"constants\": {");
    constants();
    printf("\n},\n\"noise_auto\": %.9g}\n", (double)NERF_NOISE_AUTO);
    return 0;
}
