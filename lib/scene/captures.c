/*
 * The cameras of the forward-facing, all-round and walk captures of the
 * built-in scene.  Both stand well clear of the solids (within 1.1 units of the
 * origin) and above the ground, so no camera starts inside the field.
 */
#include <math.h>

#include "rng.h"
#include "scene_internal.h"

#define PI 3.14159265358979323846
#define DEG (PI / 180.0)

/* The forward capture: a plane of cameras FORWARD_DISTANCE in front of
 * the origin (at y = -distance), FORWARD_WIDTH x FORWARD_HEIGHT units,
 * centred a little above the origin. */
#define FORWARD_DISTANCE 3.2
#define FORWARD_WIDTH 0.8
#define FORWARD_HEIGHT 0.6
#define FORWARD_CENTRE_Z 0.1
/* Hand-held: up to a third of a grid cell off its place, up to 0.05 units
 * nearer or farther, the view turned by up to a degree. */
#define FORWARD_JITTER 0.3
#define FORWARD_DEPTH_JITTER 0.05
#define FORWARD_TURN (1.0 * DEG)

/* Random streams of the rng, apart from the object capture's (77 + i). */
#define STREAM_FORWARD 1000000u
#define STREAM_UNBOUNDED 2000000u
#define STREAM_WALK 3000000u

static void intrinsics(const nerf_scene_options *o, nerf_camera *cam)
{
    NERF_CAMERA_INIT(cam);
    cam->width = o->width;
    cam->height = o->height;
    cam->fx = cam->fy = (float)(0.5 * o->width /
                                tan(0.5 * NERF__SCENE_WIDE_ANGLE_X));
    cam->cx = 0.5f * (float)o->width;
    cam->cy = 0.5f * (float)o->height;
}

static void look(nerf_camera *cam, const double eye[3], const double at[3])
{
    const float e[3] = {(float)eye[0], (float)eye[1], (float)eye[2]};
    const float t[3] = {(float)at[0], (float)at[1], (float)at[2]};
    const float up[3] = {0, 0, 1};
    /* Cannot fail: every view is far from vertical and from its target. */
    nerf_camera_look_at(cam, e, t, up);
}

/*
 * Train views (and every view of the LLFF layout, which has no splits)
 * walk a grid of cols x rows row by row, turning back at each row's end
 * as one walks along a wall with a camera; validation views are anywhere
 * on the plane; test views circle its centre, as a spiral path does.
 */
void nerf__scene_forward_camera(const nerf_scene_options *o, int split,
                                uint32_t i, uint32_t n, nerf_camera *cam)
{
    intrinsics(o, cam);
    nerf__rng r = nerf__rng_make(o->seed, STREAM_FORWARD + 3u * i +
                                              (uint32_t)split);
    double u, v; /* in [-0.5, 0.5] across the plane */
    if (split == 0) {
        double aspect = FORWARD_WIDTH / FORWARD_HEIGHT;
        uint32_t cols = (uint32_t)ceil(sqrt((double)n * aspect));
        uint32_t rows = (n + cols - 1) / cols;
        uint32_t row = i / cols, col = i % cols;
        if (row % 2 == 1) {
            col = cols - 1 - col;
        }
        u = (col + 0.5 + FORWARD_JITTER * (2.0 * nerf__rng_uniform_d(&r) - 1.0)) /
                cols - 0.5;
        v = (row + 0.5 + FORWARD_JITTER * (2.0 * nerf__rng_uniform_d(&r) - 1.0)) /
                rows - 0.5;
    } else if (split == 1) {
        u = nerf__rng_uniform_d(&r) - 0.5;
        v = nerf__rng_uniform_d(&r) - 0.5;
    } else {
        double a = 2.0 * PI * i / n;
        u = 0.35 * cos(a);
        v = 0.35 * sin(a);
    }
    double eye[3] = {u * FORWARD_WIDTH,
                     -FORWARD_DISTANCE + FORWARD_DEPTH_JITTER *
                                             (2.0 * nerf__rng_uniform_d(&r) - 1.0),
                     FORWARD_CENTRE_Z - v * FORWARD_HEIGHT};
    double turn_x = FORWARD_TURN * (2.0 * nerf__rng_uniform_d(&r) - 1.0);
    double turn_z = FORWARD_TURN * (2.0 * nerf__rng_uniform_d(&r) - 1.0);
    double at[3] = {eye[0] + tan(turn_x), eye[1] + 1.0, eye[2] + tan(turn_z)};
    look(cam, eye, at);
}

/*
 * Train views: three rings, low and far to high and near, taking turns so
 * that any prefix of the views goes all round; validation views anywhere
 * between the rings; test views a circle between them, as the Blender
 * scenes' test split is.
 */
void nerf__scene_unbounded_camera(const nerf_scene_options *o, int split,
                                  uint32_t i, uint32_t n, nerf_camera *cam)
{
    /* Low enough that even the highest ring sees the backdrop above the
     * ground in 4:3 views. */
    static const double elevation[3] = {6.0 * DEG, 15.0 * DEG, 24.0 * DEG};
    static const double radius[3] = {3.0, 2.6, 2.2};
    intrinsics(o, cam);
    double az, el, rad;
    if (split == 0) {
        uint32_t ring = i % 3, per_ring = (n + 2) / 3;
        az = 2.0 * PI * ((i / 3) + ring / 3.0) / per_ring;
        el = elevation[ring];
        rad = radius[ring];
    } else if (split == 1) {
        nerf__rng r = nerf__rng_make(o->seed, STREAM_UNBOUNDED + i);
        double s = nerf__rng_uniform_d(&r);
        az = 2.0 * PI * nerf__rng_uniform_d(&r);
        el = elevation[0] + s * (elevation[2] - elevation[0]);
        rad = radius[0] + s * (radius[2] - radius[0]);
    } else {
        az = 2.0 * PI * i / n;
        el = 15.0 * DEG;
        rad = 2.6;
    }
    double eye[3] = {rad * cos(el) * cos(az), rad * cos(el) * sin(az),
                     rad * sin(el)};
    const double at[3] = {0.0, 0.0, 0.0};
    look(cam, eye, at);
}

/* Where the walk is at s in [0, 1): one turn round the solids, nearer and
 * farther twice and higher and lower three times, as a person walking
 * round them with a phone would be, and never so fast that a view of 60
 * in a turn loses sight of what the one before saw. */
static void walk_at(double s, double eye[3])
{
    double az = 2.0 * PI * s;
    double rad = 2.6 + 0.3 * sin(4.0 * PI * s);
    double el = (15.0 + 6.0 * sin(6.0 * PI * s + 1.0)) * DEG;
    eye[0] = rad * cos(el) * cos(az);
    eye[1] = rad * cos(el) * sin(az);
    eye[2] = rad * sin(el);
}

/*
 * Train views in path order, i of n at i / n of the turn, so that written
 * in order they make a video; validation views anywhere on the path; test
 * views halfway between train views' places when the counts match, so
 * that none is seen in training.
 */
void nerf__scene_walk_camera(const nerf_scene_options *o, int split,
                             uint32_t i, uint32_t n, nerf_camera *cam)
{
    intrinsics(o, cam);
    double s;
    if (split == 0) {
        s = (double)i / n;
    } else if (split == 1) {
        nerf__rng r = nerf__rng_make(o->seed, STREAM_WALK + i);
        s = nerf__rng_uniform_d(&r);
    } else {
        s = (i + 0.5) / n;
    }
    double eye[3];
    walk_at(s, eye);
    /* Looking a little above the ground's centre, so that the solids sit
     * in the middle of the view with the ground below them. */
    const double at[3] = {0.0, 0.0, -0.1};
    look(cam, eye, at);
}
