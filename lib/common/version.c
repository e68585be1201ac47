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

NERF_API const char *nerf_build_info(void)
{
    return "libnerf " NERF_VERSION_STRING
           "; blas " NERF_CONFIG_BLAS
           "; libpng " NERF_CONFIG_PNG_VERSION
           "; libjpeg " NERF_CONFIG_JPEG_VERSION
           "; zlib " NERF_CONFIG_ZLIB_VERSION
           "; cjson " NERF_CONFIG_CJSON_VERSION
           "; bf16 " NERF_CONFIG_BF16
           "; " NERF_CONFIG_BUILDTYPE " build";
}
