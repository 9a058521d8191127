/*
 * tin_lerp.c
 *		The linear height on an edge and in a triangle (tin_lerp.h).
 *
 * Both are plain floating point, so the order of every operation is part
 * of the value: a pixel of a bounded run's grid equals the whole TIN's
 * only because both call these two functions with the vertices in the
 * same canonical order, which the functions choose themselves.  The build
 * never contracts a * b + c into a fused multiply-add (-ffp-contract=off),
 * so the same operations give the same double on every x86-64 and arm64.
 */
#include "engine/predicates.h"
#include "tin_lerp.h"

double
tin_lerp_xy(const double *p0, double z0, const double *p1, double z1, const double *q)
{
	double		dx,
				dy,
				u;

	if (tdc_lex_less(p1, p0))
	{
		const double *t = p0;
		double		tz = z0;

		p0 = p1;
		p1 = t;
		z0 = z1;
		z1 = tz;
	}
	dx = p1[0] - p0[0];
	dy = p1[1] - p0[1];
	u = ((q[0] - p0[0]) * dx + (q[1] - p0[1]) * dy) / (dx * dx + dy * dy);
	if (!(u > 0))
		u = 0;
	if (u > 1)
		u = 1;
	return z0 + u * (z1 - z0);
}

double
tin_face_xy(const double *const p[3], const double z[3], const double *q)
{
	const double *pa,
			   *pb,
			   *pc;
	double		za,
				zb,
				zc,
				ux,
				uy,
				vx,
				vy,
				wx,
				wy,
				det,
				s,
				t;
	int			k = 0;

	if (tdc_lex_less(p[1], p[k]))
		k = 1;
	if (tdc_lex_less(p[2], p[k]))
		k = 2;
	pa = p[k];
	pb = p[(k + 1) % 3];
	pc = p[(k + 2) % 3];
	za = z[k];
	zb = z[(k + 1) % 3];
	zc = z[(k + 2) % 3];
	ux = pb[0] - pa[0];
	uy = pb[1] - pa[1];
	vx = pc[0] - pa[0];
	vy = pc[1] - pa[1];
	wx = q[0] - pa[0];
	wy = q[1] - pa[1];
	det = ux * vy - uy * vx;
	s = (wx * vy - wy * vx) / det;
	t = (ux * wy - uy * wx) / det;
	return za + s * (zb - za) + t * (zc - za);
}
