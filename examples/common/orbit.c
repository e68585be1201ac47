#include "orbit.h"

#include <math.h>

int orbit_camera(uint32_t i, uint32_t n, uint32_t width, uint32_t height,
                 nerf_camera *cam)
{
    const double pi = 3.14159265358979;
    const double elev = 30.0 * pi / 180, az = 2.0 * pi * i / n;
    const float eye[3] = {(float)(4.0 * cos(elev) * cos(az)),
                          (float)(4.0 * cos(elev) * sin(az)),
                          (float)(4.0 * sin(elev))};
    const float target[3] = {0, 0, 0}, up[3] = {0, 0, 1};
    NERF_CAMERA_INIT(cam);
    cam->width = width;
    cam->height = height;
    cam->fx = cam->fy = (float)(0.5 * width / tan(0.5 * ORBIT_FOV));
    cam->cx = 0.5f * (float)width;
    cam->cy = 0.5f * (float)height;
    return nerf_camera_look_at(cam, eye, target, up);
}
