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
SIZE(nerf_model_options, 64);

#endif

/* Status codes and enum values are ABI too. */
_Static_assert(NERF_OK == 0 && NERF_ERROR == -1 && NERF_EINVAL == -2 &&
               NERF_ENOMEM == -3 && NERF_EIO == -4 && NERF_EFORMAT == -5 &&
               NERF_ECANCELLED == -6 && NERF_EVERSION == -7,
               "status codes renumbered");
_Static_assert(NERF_PARAM_LEARNING_RATE == 100 && NERF_PARAM_ADAM_EPS == 105,
               "parameter keys renumbered");
_Static_assert(NERF_PRESET_REFERENCE == 1 && NERF_PRESET_TINY == 2,
               "presets renumbered");

int main(void)
{
    printf("ok   public struct layouts%s\n",
           UINTPTR_MAX == UINT64_MAX ? "" : " (not LP64: only enums checked)");
    return 0;
}
