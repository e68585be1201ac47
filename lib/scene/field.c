#include "field.h"

#include <math.h>
#include <stdbool.h>
#include <stdint.h>
#include <stdlib.h>

/* Density deep inside a solid, and the width of its soft edge (in scene
 * units): with sigma 60 a ray crossing 0.05 units is already 95% opaque,
 * while the edge keeps the field smooth enough for a network to fit. */
#define SIGMA_MAX 60.0f
#define EDGE 0.015f

/* Integration steps per edge width (see nerf__scene_render_ray). */
#ifndef STEPS_PER_EDGE
#define STEPS_PER_EDGE 3.0
#endif

/* The ground's checker repeats every GROUND_PERIOD units; steps along a
 * ray move at most a GROUND_STEPS-th of it sideways. */
#define GROUND_PERIOD 0.8
#define GROUND_STEPS 24.0
#define PI 3.14159265358979323846

/* Sideways steps over the textured ground: this many per lattice cell,
 * so that a blotch is not skipped between two samples. */
#define TEXTURE_STEPS 6.0

typedef enum { SPHERE, BOX, TORUS } kind;

typedef struct solid {
    kind k;
    float c[3];  /* centre */
    float s[3];  /* radius / half extents / (major, minor) radii */
    float rgb[3];
} solid;

static const solid solids_[] = {
    {SPHERE, {0.45f, -0.2f, 0.1f}, {0.45f, 0, 0}, {0.85f, 0.2f, 0.15f}},
    {BOX, {-0.5f, 0.35f, -0.05f}, {0.3f, 0.3f, 0.4f}, {0.2f, 0.65f, 0.25f}},
    {TORUS, {0.0f, 0.0f, -0.55f}, {0.8f, 0.12f, 0}, {0.95f, 0.8f, 0.2f}},
    {SPHERE, {-0.35f, -0.6f, 0.45f}, {0.25f, 0, 0}, {0.2f, 0.35f, 0.9f}},
};

static float sdf(const solid *s, const float x[3])
{
    float p[3] = {x[0] - s->c[0], x[1] - s->c[1], x[2] - s->c[2]};
    switch (s->k) {
    case SPHERE:
        return sqrtf(p[0] * p[0] + p[1] * p[1] + p[2] * p[2]) - s->s[0];
    case BOX: {
        float out = 0.0f, in = -1e30f;
        for (int i = 0; i < 3; i++) {
            float q = fabsf(p[i]) - s->s[i];
            out += q > 0.0f ? q * q : 0.0f;
            in = q > in ? q : in;
        }
        return out > 0.0f ? sqrtf(out) : in;
    }
    case TORUS: {
        float ring = sqrtf(p[0] * p[0] + p[1] * p[1]) - s->s[0];
        return sqrtf(ring * ring + p[2] * p[2]) - s->s[1];
    }
    }
    return 1e30f;
}

static float mixf(float a, float b, float s)
{
    return a + (b - a) * s;
}

/* A value in [0, 1) for each lattice point, the same on every machine
 * (integer arithmetic only).  The multipliers are odd numbers with well
 * mixed bits, the four 32-bit primes the xxHash format publishes; the
 * mixing around them is only what a lattice needs. */
static float lattice(int32_t i, int32_t j, int32_t k)
{
    uint32_t h = (uint32_t)i * 0x9e3779b1u;
    h = (h ^ (uint32_t)j) * 0x85ebca77u;
    h = (h ^ (uint32_t)k) * 0xc2b2ae3du;
    h ^= h >> 15;
    h *= 0x27d4eb2fu;
    h ^= h >> 13;
    return (float)(h >> 8) * (1.0f / 16777216.0f);
}

static float smooth(float t)
{
    return t * t * (3.0f - 2.0f * t);
}

/* Value noise: the lattice's values blended smoothly between lattice
 * points, continuous so that the field stays one a network can fit. */
static float noise(float x, float y, float z)
{
    float fx = floorf(x), fy = floorf(y), fz = floorf(z);
    int32_t i = (int32_t)fx, j = (int32_t)fy, k = (int32_t)fz;
    float u = smooth(x - fx), v = smooth(y - fy), w = smooth(z - fz);
    float c[2][2];
    for (int a = 0; a < 2; a++) {
        for (int b = 0; b < 2; b++) {
            c[a][b] = mixf(lattice(i + a, j + b, k),
                           lattice(i + a, j + b, k + 1), w);
        }
    }
    return mixf(mixf(c[0][0], c[0][1], v), mixf(c[1][0], c[1][1], v), u);
}

/*
 * Blotches: two octaves of noise pushed towards 0 or 1.  SIFT, which
 * COLMAP places photos with, finds its keypoints at blobs and corners of
 * contrast; the plain scene's smooth shading gives it some 20 a photo,
 * too few to match.  Irregular blotches a few pixels across give it
 * hundreds, and unlike a checker they do not repeat, so that a feature
 * matches its own place only.
 */
static float blotch(float x, float y, float z, float spacing)
{
    float s = 1.0f / spacing;
    float n = 0.65f * noise(x * s, y * s, z * s) +
              0.35f * noise(x * s * 2.3f + 17.0f, y * s * 2.3f + 5.0f,
                            z * s * 2.3f + 11.0f);
    return 0.5f + 0.5f * tanhf(8.0f * (n - 0.5f));
}

/* Add the solids' density at x to *total and their density-weighted
 * colour to acc; textured: with blotches. */
static void solids(const float x[3], bool textured, float *total,
                   float acc[3])
{
    for (unsigned i = 0; i < sizeof solids_ / sizeof solids_[0]; i++) {
        float d = sdf(&solids_[i], x);
        if (d > 8.0f * EDGE) {
            continue; /* the sigmoid below is < 4e-4 of SIGMA_MAX there */
        }
        float sigma = SIGMA_MAX / (1.0f + expf(d / EDGE));
        *total += sigma;
        /* Shade by height so that each solid has some texture to learn. */
        float shade = 0.75f + 0.25f * tanhf(2.0f * (x[2] - solids_[i].c[2]));
        if (textured) {
            shade *= 0.45f + 0.75f * blotch(x[0], x[1], x[2],
                                            NERF__SCENE_TEXTURE_SOLID);
        }
        for (int c = 0; c < 3; c++) {
            acc[c] += sigma * solids_[i].rgb[c] * shade;
        }
    }
}

/*
 * The ground: a soft checker whose contrast fades with the distance from
 * the solids, so that the far ground, which covers few pixels, is a smooth
 * tone a network can fit, while the near one shows parallax.
 */
static void ground(const float x[3], bool textured, float *total,
                   float acc[3])
{
    float h = x[2] - NERF__SCENE_GROUND_Z;
    if (h > 8.0f * NERF__SCENE_GROUND_EDGE) {
        return;
    }
    float sigma = SIGMA_MAX / (1.0f + expf(h / NERF__SCENE_GROUND_EDGE));
    const float k = (float)(2.0 * PI / GROUND_PERIOD);
    float u = sinf(k * x[0]) * sinf(k * x[1]);
    float rho2 = x[0] * x[0] + x[1] * x[1];
    float contrast = 1.0f / (1.0f + rho2 / 36.0f);
    float s = 0.5f + 0.5f * contrast * tanhf(4.0f * u);
    /* A slow change of tone across the far ground. */
    float tone = 0.9f + 0.1f * sinf(0.15f * x[0] + 0.1f * x[1]);
    if (textured) {
        /* Fading as the checker does, for the same reason. */
        float b = blotch(x[0], x[1], 0.0f, NERF__SCENE_TEXTURE_GROUND);
        tone *= 1.0f + contrast * (0.7f * b - 0.5f);
    }
    static const float dark[3] = {0.30f, 0.36f, 0.22f};
    static const float light[3] = {0.62f, 0.56f, 0.42f};
    *total += sigma;
    for (int c = 0; c < 3; c++) {
        acc[c] += sigma * tone * mixf(dark[c], light[c], s);
    }
}

/*
 * The backdrop: a sky brightening towards the horizon, a ridge of hills
 * whose height varies with the azimuth, and a sun, so that its pixels
 * differ and a model must place them at their depth.
 */
static void backdrop(const float x[3], float *total, float acc[3])
{
    float r = sqrtf(x[0] * x[0] + x[1] * x[1] + x[2] * x[2]);
    float h = NERF__SCENE_BACKDROP_R - r;
    if (h > 8.0f * NERF__SCENE_BACKDROP_EDGE) {
        return;
    }
    float sigma = SIGMA_MAX / (1.0f + expf(h / NERF__SCENE_BACKDROP_EDGE));
    float sz = x[2] / r;
    float el = asinf(sz < -1.0f ? -1.0f : sz > 1.0f ? 1.0f : sz);
    float az = atan2f(x[1], x[0]);
    static const float horizon[3] = {0.86f, 0.90f, 0.95f};
    static const float zenith[3] = {0.30f, 0.50f, 0.88f};
    static const float hill[3] = {0.34f, 0.44f, 0.36f};
    float up = el / 0.6f;
    up = up < 0.0f ? 0.0f : up > 1.0f ? 1.0f : up;
    float ridge = 0.10f + 0.05f * sinf(3.0f * az + 1.0f) +
                  0.03f * sinf(7.0f * az + 2.0f);
    float on_hill = 0.5f + 0.5f * tanhf((ridge - el) / 0.02f);
    float shade = 0.85f + 0.15f * sinf(5.0f * az);
    /* The sun, a soft disc about 0.1 radians wide. */
    float sun_dir[3] = {0.62f, 0.70f, 0.35f};
    float cosang = (x[0] * sun_dir[0] + x[1] * sun_dir[1] + x[2] * sun_dir[2]) /
                   (r * 1.0009f);
    float sun = expf((cosang - 1.0f) * 200.0f);
    *total += sigma;
    for (int c = 0; c < 3; c++) {
        float v = mixf(mixf(horizon[c], zenith[c], up), hill[c] * shade,
                       on_hill);
        v = mixf(v, 1.0f, 0.9f * sun);
        acc[c] += sigma * v;
    }
}

float nerf__scene_field_in(nerf__scene_world world, const float x[3],
                           float rgb[3])
{
    float total = 0.0f, acc[3] = {0, 0, 0};
    const bool textured = (world & NERF__SCENE_TEXTURED) != 0;
    solids(x, textured, &total, acc);
    if (world & NERF__SCENE_SURROUNDED) {
        ground(x, textured, &total, acc);
        backdrop(x, &total, acc);
    }
    if (rgb) {
        for (int c = 0; c < 3; c++) {
            rgb[c] = total > 0.0f ? acc[c] / total : 0.0f;
        }
    }
    return total;
}

float nerf__scene_field(const float x[3], float rgb[3])
{
    return nerf__scene_field_in(NERF__SCENE_SOLIDS, x, rgb);
}

/* A stretch [t0, t1] of a ray and the longest step it allows. */
typedef struct stretch {
    double t0, t1, dt;
} stretch;

/* Chord of the ball |x| <= r along o + t d: false if the ray misses it. */
static bool chord(const float o[3], const float d[3], double r, double *t0,
                  double *t1)
{
    double dd = (double)d[0] * d[0] + (double)d[1] * d[1] + (double)d[2] * d[2];
    double od = (double)o[0] * d[0] + (double)o[1] * d[1] + (double)o[2] * d[2];
    double oo = (double)o[0] * o[0] + (double)o[1] * o[1] + (double)o[2] * o[2];
    double disc = od * od - dd * (oo - r * r);
    if (disc <= 0.0) {
        return false;
    }
    *t0 = (-od - sqrt(disc)) / dd;
    *t1 = (-od + sqrt(disc)) / dd;
    return true;
}

/*
 * Midpoint rule over the stretches, in order, each cut into equal steps
 * no longer than its dt; transmittance carries from one to the next.
 */
static float integrate(nerf__scene_world world, const float o[3],
                       const float d[3], const stretch *s, int n,
                       double norm, float rgb[3], float *depth)
{
    double T = 1.0, acc[3] = {0, 0, 0}, dep = 0.0;
    for (int j = 0; j < n && T > 1e-6; j++) {
        double t0 = s[j].t0, t1 = s[j].t1;
        int steps = (int)ceil((t1 - t0) / s[j].dt);
        double dt = (t1 - t0) / steps;
        for (int i = 0; i < steps && T > 1e-6; i++) {
            double t = t0 + (i + 0.5) * dt;
            float x[3] = {(float)(o[0] + t * d[0]), (float)(o[1] + t * d[1]),
                          (float)(o[2] + t * d[2])};
            float c[3];
            float sigma = nerf__scene_field_in(world, x, c);
            if (sigma <= 0.0f) {
                continue;
            }
            double alpha = 1.0 - exp(-(double)sigma * dt * norm);
            double w = T * alpha;
            for (int k = 0; k < 3; k++) {
                acc[k] += w * c[k];
            }
            dep += w * t;
            T *= 1.0 - alpha;
        }
    }
    for (int k = 0; k < 3; k++) {
        rgb[k] = (float)acc[k];
    }
    *depth = (float)dep;
    return (float)(1.0 - T);
}

float nerf__scene_render_ray(const float o[3], const float d[3], float near,
                             float far, float rgb[3], float *depth)
{
    return nerf__scene_render_ray_in(NERF__SCENE_SOLIDS, o, d, near, far, rgb,
                                     depth);
}

static int compare_double(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

float nerf__scene_render_ray_in(nerf__scene_world world, const float o[3],
                                const float d[3], float near, float far,
                                float rgb[3], float *depth)
{
    rgb[0] = rgb[1] = rgb[2] = 0.0f;
    *depth = 0.0f;
    double dd = (double)d[0] * d[0] + (double)d[1] * d[1] + (double)d[2] * d[2];
    double norm = sqrt(dd);
    /*
     * Where each part of the field can be non-zero, and the step it needs
     * there: STEPS_PER_EDGE steps per edge width crossed, the ray crossing
     * a solid's or the backdrop's edge at most at rate |d| and the
     * ground's at rate |d_z|.  Four times as many steps moved no
     * composited value of a 100x100 view of the solids by more than
     * 1.5e-4, a twenty-fifth of an 8-bit level.
     */
    enum { MAX_PARTS = 4 };
    stretch part[MAX_PARTS];
    int n_parts = 0;
    double a, b;
    /* Only the part of the ray inside the bounding sphere can meet a solid. */
    if (chord(o, d, NERF__SCENE_RADIUS, &a, &b)) {
        part[n_parts++] = (stretch){a, b, (EDGE / STEPS_PER_EDGE) / norm};
    }
    if (world & NERF__SCENE_SURROUNDED) {
        /* The ground is zero above its edge: z > GROUND_Z + 8 edges. */
        double top = (double)NERF__SCENE_GROUND_Z +
                     8.0 * NERF__SCENE_GROUND_EDGE - o[2];
        double dt = (GROUND_PERIOD / GROUND_STEPS) / norm;
        if (world & NERF__SCENE_TEXTURED) {
            double fine = (NERF__SCENE_TEXTURE_GROUND / TEXTURE_STEPS) / norm;
            dt = fine < dt ? fine : dt;
        }
        if (d[2] != 0.0f) {
            double cross = (double)NERF__SCENE_GROUND_EDGE /
                           (STEPS_PER_EDGE * fabs((double)d[2]));
            dt = cross < dt ? cross : dt;
        }
        double at = d[2] != 0.0f ? top / d[2] : 0.0;
        if (d[2] < 0.0f) {
            part[n_parts++] = (stretch){at, INFINITY, dt};
        } else if (d[2] > 0.0f) {
            part[n_parts++] = (stretch){-INFINITY, at, dt};
        } else if (top >= 0.0) {
            part[n_parts++] = (stretch){-INFINITY, INFINITY, dt};
        }
        /* The backdrop is zero inside radius R - 8 edges. */
        double inner = (double)NERF__SCENE_BACKDROP_R -
                       8.0 * NERF__SCENE_BACKDROP_EDGE;
        dt = (NERF__SCENE_BACKDROP_EDGE / STEPS_PER_EDGE) / norm;
        if (chord(o, d, inner, &a, &b)) {
            part[n_parts++] = (stretch){-INFINITY, a, dt};
            part[n_parts++] = (stretch){b, INFINITY, dt};
        } else {
            part[n_parts++] = (stretch){-INFINITY, INFINITY, dt};
        }
    }
    if (n_parts == 0) {
        return 0.0f;
    }
    /*
     * Cut [near, far] at every end of a part; each piece gets the finest
     * step of the parts covering it, and pieces no part covers are empty.
     */
    double cut[2 * MAX_PARTS + 2];
    int n_cuts = 0;
    cut[n_cuts++] = near;
    cut[n_cuts++] = far;
    for (int k = 0; k < n_parts; k++) {
        for (int e = 0; e < 2; e++) {
            double t = e == 0 ? part[k].t0 : part[k].t1;
            if (t > near && t < far) {
                cut[n_cuts++] = t;
            }
        }
    }
    qsort(cut, (size_t)n_cuts, sizeof *cut, compare_double);
    stretch piece[2 * MAX_PARTS + 1];
    int n_pieces = 0;
    for (int k = 0; k + 1 < n_cuts; k++) {
        if (!(cut[k + 1] > cut[k])) {
            continue;
        }
        double mid = 0.5 * (cut[k] + cut[k + 1]), dt = INFINITY;
        for (int p = 0; p < n_parts; p++) {
            if (part[p].t0 <= mid && mid <= part[p].t1 && part[p].dt < dt) {
                dt = part[p].dt;
            }
        }
        if (dt < INFINITY) {
            piece[n_pieces++] = (stretch){cut[k], cut[k + 1], dt};
        }
    }
    return integrate(world, o, d, piece, n_pieces, norm, rgb, depth);
}
