/*
 * The built-in scene as a continuous field: a few coloured solids whose
 * density rises smoothly across their surfaces, alone (the object capture)
 * or standing on a ground in front of a far backdrop (the forward-facing
 * and all-round captures, whose photos are opaque everywhere).  It is the
 * ground truth of the built-in dataset, so tests can compare a trained
 * model with it.
 */
#ifndef NERF_SCENE_FIELD_H
#define NERF_SCENE_FIELD_H

/* Every solid lies inside this sphere about the origin. */
#define NERF__SCENE_RADIUS 1.6f

/* The cameras of the built-in dataset (scene_writer.c) are this far from
 * the origin, looking at it, with the lego scene's horizontal field of
 * view (radians), so that the built-in scene frames alike. */
#define NERF__SCENE_CAMERA_RADIUS 4.0
#define NERF__SCENE_CAMERA_ANGLE_X 0.6911112070083618

/* The surroundings: the ground is the half-space z < GROUND_Z, the
 * backdrop everything farther than BACKDROP_R from the origin, each with
 * a soft edge of the given width (the backdrop's wide, as a far surface's
 * may be: it covers few pixels per unit).  A ray from within 10 units of
 * the origin with |d| >= 1 (every camera ray) is opaque, to 1e-6, by
 * t = WORLD_FAR. */
#define NERF__SCENE_GROUND_Z (-0.75f)
#define NERF__SCENE_GROUND_EDGE 0.02f
#define NERF__SCENE_BACKDROP_R 40.0f
#define NERF__SCENE_BACKDROP_EDGE 0.5f
#define NERF__SCENE_WORLD_FAR 60.0f

/* What the field holds: SOLIDS or SURROUNDED, and TEXTURED or'ed in for
 * nerf_scene_options.texture. */
typedef enum nerf__scene_world {
    NERF__SCENE_SOLIDS = 0,     /* the solids in a transparent void */
    NERF__SCENE_SURROUNDED = 1, /* the solids, the ground and the backdrop */
    NERF__SCENE_TEXTURED = 2    /* blotches on the solids and the ground */
} nerf__scene_world;

/* The blotches' lattice spacing (scene units): on the solids, and on the
 * ground, whose far parts cover fewer pixels. */
#define NERF__SCENE_TEXTURE_SOLID 0.07f
#define NERF__SCENE_TEXTURE_GROUND 0.12f

/* Density at x, and the colour there (rgb may be NULL): the solids. */
float nerf__scene_field(const float x[3], float rgb[3]);

/* The same in the given world. */
float nerf__scene_field_in(nerf__scene_world world, const float x[3],
                           float rgb[3]);

/*
 * Integrate the volume rendering equation along o + t d for t in
 * [near, far] with steps much finer than the edges the ray crosses, so
 * the result is exact to about 1e-3.  Returns the opacity; rgb receives
 * sum w c (not yet composited on a background) and depth sum w t.
 */
float nerf__scene_render_ray(const float o[3], const float d[3], float near,
                             float far, float rgb[3], float *depth);

/*
 * The same in the given world.  Where the field is provably zero (outside
 * the solids' sphere, above the ground's edge, inside the backdrop's) the
 * ray is skipped; elsewhere each stretch gets the finest step of the
 * parts it crosses, the far backdrop's being as coarse as its wide edge
 * allows.
 */
float nerf__scene_render_ray_in(nerf__scene_world world, const float o[3],
                                const float d[3], float near, float far,
                                float rgb[3], float *depth);

#endif
