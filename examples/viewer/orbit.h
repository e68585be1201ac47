/*
 * An orbit camera: a point the view circles around, a distance and two
 * angles measured in a frame with a fixed "up" axis.  Pure arithmetic, no
 * SDL, so the headless screenshot path shares it.
 */
#ifndef NERF_VIEWER_ORBIT_H
#define NERF_VIEWER_ORBIT_H

#include <nerf.h>

typedef struct orbit {
    float target[3]; /* the point looked at and circled around */
    float up[3];     /* world direction that stays up on screen */
    float ax[3];     /* horizontal direction of yaw 0 */
    float ay[3];     /* horizontal direction of yaw +90 degrees */
    double yaw;      /* radians about up, from ax towards ay */
    double pitch;    /* radians above the horizontal plane */
    double distance; /* from target to eye, world units */
} orbit;

/* An orbit around target with the given up axis and horizontal axis ax
 * (made orthogonal to up), whose eye starts at eye. */
void orbit_init(orbit *o, const float target[3], const float up[3],
                const float ax[3], const float eye[3]);

/* Turn by dyaw and dpitch radians; pitch stays short of the poles, where
 * the up axis would be parallel to the view. */
void orbit_rotate(orbit *o, double dyaw, double dpitch);

/* Move the target (and the eye with it) by right and up world units along
 * the camera's own right and up axes. */
void orbit_pan(orbit *o, double right, double up);

/* Multiply the distance by factor, within sane bounds. */
void orbit_zoom(orbit *o, double factor);

/* The eye position. */
void orbit_eye(const orbit *o, float eye[3]);

/* Set cam's pose (c2w only) to the orbit's view. */
int orbit_pose(const orbit *o, nerf_camera *cam);

#endif
