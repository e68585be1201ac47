#include <pthread.h>
#include <stdio.h>

#include "dispatch.h"
#include "nerf.h"
#include "nerf_config.h"

NERF_API unsigned nerf_version_number(void)
{
    return NERF_VERSION_NUMBER;
}

NERF_API const char *nerf_version_string(void)
{
    return NERF_VERSION_STRING;
}

static char info[512];
static pthread_once_t info_once = PTHREAD_ONCE_INIT;

/* The build, then the kernels this process runs (common/dispatch.h), which
 * a bug report needs as much: they differ between machines. */
static void make_info(void)
{
    const char *said = nerf__dispatch_overrides();
    snprintf(info, sizeof info,
             "libnerf " NERF_VERSION_STRING
             "; blas " NERF_CONFIG_BLAS
             "; libpng " NERF_CONFIG_PNG_VERSION
             "; libjpeg " NERF_CONFIG_JPEG_VERSION
             "; zlib " NERF_CONFIG_ZLIB_VERSION
             "; cjson " NERF_CONFIG_CJSON_VERSION
             "; bf16 " NERF_CONFIG_BF16
             "; " NERF_CONFIG_BUILDTYPE " build"
             "; kernels %s%s%s%s",
             nerf__isa_name(nerf__isa()), said[0] ? " (" : "", said,
             said[0] ? ")" : "");
}

NERF_API const char *nerf_build_info(void)
{
    pthread_once(&info_once, make_info);
    return info;
}
