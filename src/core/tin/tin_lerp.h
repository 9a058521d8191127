/*
 * tin_lerp.h
 *		The linear height on an edge and in a triangle, from coordinates and
 *		heights alone: the one formula of every linear value the core
 *		computes, the whole TIN's (tin_locate.c) and a bounded run's
 *		(terrain/raster.c), so that both give the same double.
 */
#ifndef TDC_TIN_LERP_H
#define TDC_TIN_LERP_H

/*
 * Linear along the edge p0-p1 at q (on it): from the end first in (x, y)
 * order, whichever the caller names first, so that both triangles beside
 * the edge give the same value.
 */
extern double tin_lerp_xy(const double *p0, double z0, const double *p1, double z1,
						  const double *q);

/*
 * Linear in the triangle p[0], p[1], p[2] (counter-clockwise) at q (inside
 * it): barycentric from its first vertex in (x, y) order, the others in
 * counter-clockwise order after it, so that the value does not depend on
 * which vertex the caller starts from.
 */
extern double tin_face_xy(const double *const p[3], const double z[3], const double *q);

#endif							/* TDC_TIN_LERP_H */
