/* PLY output of point clouds: the mesh writer's, without faces. */
#include "mesh_write.h"
#include "points.h"

NERF_API int nerf_points_write(const nerf_points *points, const char *path,
                               int format)
{
    static const char fn[] = "nerf_points_write";
    if (points == NULL || path == NULL) {
        return nerf__error(NERF_EINVAL, "%s: points and path must not be "
                           "NULL", fn);
    }
    if (format != NERF_POINTS_PLY_BINARY && format != NERF_POINTS_PLY_ASCII) {
        return nerf__error(NERF_EINVAL, "%s: %s: unknown format %d", fn,
                           path, format);
    }
    /* A point without a normal has (0, 0, 0), so every point has one. */
    const nerf__mesh_arrays a = {
        points->count, 0, points->positions, points->normals,
        points->colours, NULL,
        "libnerf point cloud: normal 0 0 0 means none"};
    return nerf__mesh_write_ply(&points->env, path, &a,
                                format == NERF_POINTS_PLY_ASCII);
}
