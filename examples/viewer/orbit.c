#include "orbit.h"

#include <math.h>

/* Keeps the view direction away from the up axis, where look-at has no
 * defined roll (about 86 degrees). */
#define PITCH_LIMIT 1.5
#define DISTANCE_MIN 1e-3
#define DISTANCE_MAX 1e4
#define TWO_PI 6.283185307179586

static double dot3(const float a[3], const float b[3])
{
    return (double)a[0] * b[0] + (double)a[1] * b[1] + (double)a[2] * b[2];
}

static void cross3(const float a[3], const float b[3], float out[3])
{
    out[0] = a[1] * b[2] - a[2] * b[1];
    out[1] = a[2] * b[0] - a[0] * b[2];
    out[2] = a[0] * b[1] - a[1] * b[0];
}

static void normalize3(float v[3])
{
    double n = sqrt(dot3(v, v));
    if (n > 0.0) {
        for (int k = 0; k < 3; k++) {
            v[k] = (float)(v[k] / n);
        }
    }
}

void orbit_init(orbit *o, const float target[3], const float up[3],
                const float ax[3], const float eye[3])
{
    float v[3];
    for (int k = 0; k < 3; k++) {
        o->target[k] = target[k];
        o->up[k] = up[k];
        v[k] = eye[k] - target[k];
    }
    normalize3(o->up);
    /* Gram-Schmidt: ax may come from a slightly tilted camera. */
    double along = dot3(ax, o->up);
    for (int k = 0; k < 3; k++) {
        o->ax[k] = (float)(ax[k] - along * o->up[k]);
    }
    normalize3(o->ax);
    cross3(o->up, o->ax, o->ay);
    o->distance = sqrt(dot3(v, v));
    if (o->distance < DISTANCE_MIN) {
        o->distance = DISTANCE_MIN;
        o->yaw = o->pitch = 0.0;
        return;
    }
    o->yaw = atan2(dot3(v, o->ay), dot3(v, o->ax));
    o->pitch = 0.0;
    orbit_rotate(o, 0.0, asin(dot3(v, o->up) / o->distance));
}

void orbit_rotate(orbit *o, double dyaw, double dpitch)
{
    o->yaw = fmod(o->yaw + dyaw, TWO_PI);
    o->pitch = fmin(fmax(o->pitch + dpitch, -PITCH_LIMIT), PITCH_LIMIT);
}

void orbit_zoom(orbit *o, double factor)
{
    o->distance = fmin(fmax(o->distance * factor, DISTANCE_MIN), DISTANCE_MAX);
}

void orbit_eye(const orbit *o, float eye[3])
{
    double h = cos(o->pitch) * o->distance;
    double cy = cos(o->yaw) * h, sy = sin(o->yaw) * h;
    double z = sin(o->pitch) * o->distance;
    for (int k = 0; k < 3; k++) {
        eye[k] = (float)(o->target[k] + cy * o->ax[k] + sy * o->ay[k] +
                         z * o->up[k]);
    }
}

int orbit_pose(const orbit *o, nerf_camera *cam)
{
    float eye[3];
    orbit_eye(o, eye);
    return nerf_camera_look_at(cam, eye, o->target, o->up);
}

void orbit_pan(orbit *o, double right, double up)
{
    nerf_camera cam;
    NERF_CAMERA_INIT(&cam);
    if (orbit_pose(o, &cam) != NERF_OK) {
        return;
    }
    /* c2w is row-major 3x4: column 0 is the camera's right axis, column 1
     * its up axis. */
    for (int k = 0; k < 3; k++) {
        o->target[k] +=
            (float)(right * cam.c2w[4 * k + 0] + up * cam.c2w[4 * k + 1]);
    }
}
