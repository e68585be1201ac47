#include "env.h"
#include "options.h"

#include <stdarg.h>
#include <stdio.h>
#include <string.h>

/*
 * The process default is silent: a library embedded in someone else's
 * program should not write to its terminal unless asked.
 */
static nerf_log_cb default_cb;
static void *default_user;
static int default_level = NERF_LOG_INFO;

NERF_API void nerf_log_set_default(nerf_log_cb cb, void *user, int max_level)
{
    default_cb = cb;
    default_user = user;
    default_level = max_level;
}

NERF_API void nerf_log_stderr(int level, const char *msg, void *user)
{
    static const char *const names[] = {"error", "warning", "info", "debug"};
    (void)user;
    const char *name = level >= 0 && level <= NERF_LOG_DEBUG ? names[level] : "log";
    fprintf(stderr, "libnerf: %s: %s\n", name, msg);
}

NERF_API int nerf_hooks_init(nerf_hooks *hooks, size_t struct_size)
{
    nerf_hooks defaults;
    memset(&defaults, 0, sizeof defaults);
    defaults.log_level = NERF_LOG_INFO;
    return nerf__options_init(hooks, struct_size, &defaults, sizeof defaults,
                              "nerf_hooks");
}

void nerf__env_default(nerf__env *env)
{
    memset(env, 0, sizeof *env);
    env->log_level = NERF_LOG_INFO;
}

int nerf__env_from_hooks(nerf__env *env, const nerf_hooks *hooks)
{
    nerf__env_default(env);
    if (hooks == NULL) {
        return NERF_OK;
    }
    nerf_hooks h;
    nerf_hooks_init(&h, sizeof h);
    int rc = nerf__options_read(&h, sizeof h, hooks, "nerf_hooks");
    if (rc != NERF_OK) {
        return rc;
    }
    if ((h.alloc == NULL) != (h.free == NULL)) {
        return nerf__error(NERF_EINVAL,
                           "nerf_hooks: alloc and free must both be set or both be NULL");
    }
    env->alloc = h.alloc;
    env->free = h.free;
    env->alloc_user = h.alloc_user;
    env->log_cb = h.log_cb;
    env->log_user = h.log_user;
    env->log_level = h.log_level;
    return NERF_OK;
}

void nerf__log(const nerf__env *env, int level, const char *fmt, ...)
{
    nerf_log_cb cb = default_cb;
    void *user = default_user;
    int max = default_level;
    if (env && env->log_cb) {
        cb = env->log_cb;
        user = env->log_user;
        max = env->log_level;
    }
    if (cb == NULL || level > max) {
        return;
    }
    char msg[1024];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(msg, sizeof msg, fmt, ap);
    va_end(ap);
    cb(level, msg, user);
}
