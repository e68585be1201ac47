/*
 * The enums of nerf.h, for tests/abi/abi-check.sh.  Functions take enum
 * values as int (docs/api-conventions.md), so the library's debug
 * information never mentions the enums and abidiff on libnerf.so alone
 * cannot see a renumbered status code or preset.  One variable of each
 * enum type makes the enum part of this module's ABI instead; the check
 * fails when nerf.h declares an enum this list lacks.
 */
#include <nerf.h>

nerf_status nerf_abi_status;
nerf_log_level nerf_abi_log_level;
nerf_encoding_kind nerf_abi_encoding_kind;
nerf_density_activation nerf_abi_density_activation;
nerf_preset nerf_abi_preset;
nerf_matmul nerf_abi_matmul;
nerf_space nerf_abi_space;
nerf_sampler_use nerf_abi_sampler_use;
nerf_network nerf_abi_network;
nerf_param nerf_abi_param;
nerf_progress_kind nerf_abi_progress_kind;
nerf_split nerf_abi_split;
nerf_dataset_format nerf_abi_dataset_format;
nerf_points_format nerf_abi_points_format;
nerf_schedule_state nerf_abi_schedule_state;
nerf_mesh_colour nerf_abi_mesh_colour;
nerf_mesh_format nerf_abi_mesh_format;
