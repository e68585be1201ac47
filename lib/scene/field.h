/*
 * The built-in scene as a continuous field: a few coloured solids whose
 * density rises smoothly across their surfaces.  It is the ground truth of
 * the built-in dataset, so tests can compare a trained model with it.
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

/* Density at x, and the colour there (rgb may be NULL). */
float nerf__scene_field(const float x[3], float rgb[3]);

/*
 * Integrate the volume rendering equation along o + t d for t in
 * [near, far] with steps much finer than the solids' edges, so the result
 * is exact to about 1e-3.  Returns the opacity; rgb receives sum w c (not
 * yet composited on a background) and depth sum w t.
 */
float nerf__scene_render_ray(const float o[3], const float d[3], float near,
                             float far, float rgb[3], float *depth);

#endif
