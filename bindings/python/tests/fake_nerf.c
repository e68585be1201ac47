/*
 * A stand-in for libnerf that reports major version 1, for the loader
 * test: the binding must refuse it at import time with a clear message.
 */
#if defined(__GNUC__)
#  define FAKE_API __attribute__((visibility("default")))
#else
#  define FAKE_API
#endif

FAKE_API unsigned nerf_version_number(void);

FAKE_API unsigned nerf_version_number(void)
{
    return 10203u; /* 1.2.3 */
}
