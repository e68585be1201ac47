#include "orbit.h"

#include <math.h>

double orbit_bound(void)
{
    nerf_model_options mo;
    NERF_MODEL_OPTIONS_INIT(&mo);
    return (double)mo.bound;
}

double orbit_distance(void)
{
    return orbit_bound() / sin(0.5 * ORBIT_FOV);
}

int orbit_camera_at(uint32_t i, uint32_t n, uint32_t width, uint32_t height,
                    double distance, nerf_camera *cam)
{
    const double pi = 3.14159265358979;
    const double elev = ORBIT_ELEVATION, az = 2.0 * pi * i / n;
    const float eye[3] = {(float)(distance * cos(elev) * cos(az)),
                          (float)(distance * cos(elev) * sin(az)),
                          (float)(distance * sin(elev))};
    const float target[3] = {0, 0, 0}, up[3] = {0, 0, 1};
    /* The field of view across the smaller side: the larger one sees
     * more, and the object stays whole whatever the aspect ratio. */
    const uint32_t side = width < height ? width : height;
    NERF_CAMERA_INIT(cam);
    cam->width = width;
    cam->height = height;
    cam->fx = cam->fy = (float)(0.5 * side / tan(0.5 * ORBIT_FOV));
    cam->cx = 0.5f * (float)width;
    cam->cy = 0.5f * (float)height;
    return nerf_camera_look_at(cam, eye, target, up);
}

int orbit_camera(uint32_t i, uint32_t n, uint32_t width, uint32_t height,
                 nerf_camera *cam)
{
    return orbit_camera_at(i, n, width, height, orbit_distance(), cam);
}
