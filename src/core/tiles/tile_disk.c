/*
 * tile_disk.c
 *		The rounded boxes behind Lemma 1 of a tile (tile_final.c): a box
 *		that surely holds the closed circumdisk of a triangle, and two ways
 *		to shrink it to the part of the disk that can hold points.
 *
 * Lemma 1 (docs/design/tiles.md) asks whether a triangle's closed
 * circumdisk is known: it meets C, the convex polygon around all points,
 * only where the tile was given every point.  The disk is computed in
 * doubles, so each function here returns a box that holds the true region
 * whatever the rounding, with its error bound worked out beside it: a box
 * too large only makes a tile ask for more points, a box too small would
 * make it keep a triangle that is not global.  Near the global hull a
 * sliver's disk is huge and its computed centre far off, while only a thin
 * part of the disk lies inside C: tdc_disk_clip_box cuts the box by a line
 * that supports C, tdc_disk_segment_box bounds the circular segment over a
 * certified hull edge without the centre at all.  Pure functions of their
 * arguments; the exact decisions (orientations) stay in tile_final.c.
 */
#include <math.h>
#include <stdbool.h>

#include "tile_disk.h"

#define EPS		0x1p-53

/*
 * Conservative bounding box of the closed circumdisk of counter-clockwise
 * a, b, c: the true disk lies inside box.  Returns false when the computed
 * orientation is too uncertain to bound the centre.
 *
 * Error bound: with t = b - a and s = c - a rounded (relative error eps each),
 * d = tx sy - ty sx is off by at most 4 eps P (P = |tx sy| + |ty sx|); we
 * take eta = 8 eps P / d as its relative error and require eta <= 1/4.  The
 * numerators nx = sy |t|^2 - ty |s|^2 (and ny) are off by at most 9 eps N
 * (N the same sum of absolute values); taken as 12 eps N.  The centre offset
 * u = n / 2d is then off by at most (12 eps N / 2d + eta |u|) / (1 - eta)
 * + eps |u|, taken as twice the bracket plus 4 eps |u|; the radius by the
 * sum of both offsets' errors plus 4 eps r; translating back and the final
 * additions by 4 eps of the magnitudes involved.  The result is doubled.
 */
bool
tdc_disk_box(const double *a, const double *b, const double *c, double box[4], double disk[3])
{
	double		tx = b[0] - a[0],
				ty = b[1] - a[1],
				sx = c[0] - a[0],
				sy = c[1] - a[1];
	double		p1 = tx * sy,
				p2 = ty * sx;
	double		d = p1 - p2,
				eta;
	double		t2,
				s2,
				nx,
				ny,
				Nx,
				Ny,
				ux,
				uy,
				ex,
				ey,
				r,
				er,
				cx,
				cy,
				mx,
				my;

	if (!(d > 0))
		return false;
	eta = 8 * EPS * (fabs(p1) + fabs(p2)) / d;
	if (!(eta <= 0.25))
		return false;
	t2 = tx * tx + ty * ty;
	s2 = sx * sx + sy * sy;
	nx = sy * t2 - ty * s2;
	ny = tx * s2 - sx * t2;
	Nx = fabs(sy) * t2 + fabs(ty) * s2;
	Ny = fabs(tx) * s2 + fabs(sx) * t2;
	ux = nx / (2 * d);
	uy = ny / (2 * d);
	ex = 2 * (12 * EPS * Nx / (2 * d) + eta * fabs(ux)) + 4 * EPS * fabs(ux);
	ey = 2 * (12 * EPS * Ny / (2 * d) + eta * fabs(uy)) + 4 * EPS * fabs(uy);
	r = sqrt(ux * ux + uy * uy);
	er = ex + ey + 4 * EPS * r;
	cx = a[0] + ux;
	cy = a[1] + uy;
	mx = 2 * (ex + er + 4 * EPS * (fabs(a[0]) + fabs(ux) + r)) + 0x1p-1000;
	my = 2 * (ey + er + 4 * EPS * (fabs(a[1]) + fabs(uy) + r)) + 0x1p-1000;
	box[0] = cx - r - mx;
	box[1] = cy - r - my;
	box[2] = cx + r + mx;
	box[3] = cy + r + my;
	/* the disk of radius r + max(mx, my) about the computed centre holds the true one */
	disk[0] = cx;
	disk[1] = cy;
	disk[2] = r + fmax(mx, my);
	return isfinite(disk[2]) && isfinite(box[0]) && isfinite(box[1]) && isfinite(box[2]) && isfinite(box[3]);
}

/*
 * Shrink box, a bounding box of the disk (centre disk[0..1], radius
 * disk[2]), to a bounding box of the part of the disk on the closed left of
 * the line a -> b: the circular segment beyond the chord.  A flat triangle
 * along the global hull has a huge circle that bulges out of C; only its
 * thin segment inside C must be known.
 *
 * Rounding: s, the centre's signed distance to the line (positive on the
 * left), is off by less than es (the unit vectors and the difference carry a
 * few eps of the magnitudes involved; es takes 16), so s + es bounds it from
 * above, which only widens the segment.  The half-chord w = sqrt(R^2 - s^2)
 * gets 8 eps R^2 under the root, more than the rounding of the difference.
 * The extreme points of the disk are kept whenever they may lie on the left.
 * The resulting box is padded by 16 eps of the magnitudes involved.
 */
void
tdc_disk_clip_box(const double *disk, const double *a, const double *b, double box[4])
{
	double		tx = b[0] - a[0],
				ty = b[1] - a[1],
				L = sqrt(tx * tx + ty * ty),
				ux,
				uy,
				nx,
				ny,
				R = disk[2],
				s,
				es,
				w,
				mx,
				my,
				pad,
				c[4];
	static const double dirs[4][2] = {{-1, 0}, {0, -1}, {1, 0}, {0, 1}};

	if (!(L > 0) || !isfinite(L))
		return;
	ux = tx / L;
	uy = ty / L;
	nx = -uy;
	ny = ux;
	s = nx * (disk[0] - a[0]) + ny * (disk[1] - a[1]);
	es = 16 * EPS * (fabs(disk[0]) + fabs(disk[1]) + fabs(a[0]) + fabs(a[1])) + 0x1p-1000;
	s += es;
	if (!(s < R) || !(s > -R))
		return;					/* all of the disk may be on the left: no gain */
	w = sqrt(fmax(0, R * R - s * s) + 8 * EPS * R * R) * (1 + 4 * EPS);
	mx = disk[0] - s * nx;
	my = disk[1] - s * ny;
	c[0] = fmin(mx - w * ux, mx + w * ux);
	c[2] = fmax(mx - w * ux, mx + w * ux);
	c[1] = fmin(my - w * uy, my + w * uy);
	c[3] = fmax(my - w * uy, my + w * uy);
	for (int k = 0; k < 4; k++)
		if ((nx * dirs[k][0] + ny * dirs[k][1]) * R + s >= -8 * EPS * R)
		{
			double		px = disk[0] + dirs[k][0] * R,
						py = disk[1] + dirs[k][1] * R;

			c[0] = fmin(c[0], px);
			c[1] = fmin(c[1], py);
			c[2] = fmax(c[2], px);
			c[3] = fmax(c[3], py);
		}
	pad = 16 * EPS * (fabs(disk[0]) + fabs(disk[1]) + R + w + fabs(s)) + 0x1p-1000;
	box[0] = fmax(box[0], c[0] - pad);
	box[1] = fmax(box[1], c[1] - pad);
	box[2] = fmin(box[2], c[2] + pad);
	box[3] = fmin(box[3], c[3] + pad);
}

/*
 * Shrink box, holding the part inside C of the circumdisk D of triangle
 * a, b, c (counter-clockwise), when a -> b is a certified global hull edge:
 * C lies on the closed left of ab, as c does, so D n C lies in the circular
 * segment cut off by the chord ab on c's side.  When the angle at c is
 * obtuse that segment is the minor one: it projects onto the chord within
 * [a, b] and its height is the sagitta h = (L/2) tan(phi/2), phi = pi - the
 * angle at c, and tan(phi/2) <= tan(phi) = cross / -dot of a - c, b - c.
 * This uses no circumcentre: a sliver along a long hull edge has a circle
 * of radius 1e8 whose computed centre carries an error far larger than the
 * segment's height, and tdc_disk_clip_box's chord, widened by that error, reaches
 * past the edge's ends into regions the tile does not know.
 *
 * Rounding: t = a - c and s = b - c carry eps relative error each, the
 * products and sums a few more; cross and dot are taken off by at most
 * 8 eps of their sums of absolute products, the angle is called obtuse
 * only when dot stays negative by twice that, and h is then bounded with
 * the worst cross, the least |dot|, L grown by 4 eps, times 2 for slack.
 */
void
tdc_disk_segment_box(const double *a, const double *b, const double *c, double box[4])
{
	double		tx = a[0] - c[0],
				ty = a[1] - c[1],
				sx = b[0] - c[0],
				sy = b[1] - c[1];
	double		cross = tx * sy - ty * sx,
				ecross = 8 * EPS * (fabs(tx * sy) + fabs(ty * sx)),
				dot = tx * sx + ty * sy,
				edot = 8 * EPS * (fabs(tx * sx) + fabs(ty * sy)),
				lx = b[0] - a[0],
				ly = b[1] - a[1],
				L = sqrt(lx * lx + ly * ly) * (1 + 4 * EPS),
				h,
				pad,
				r[4];

	if (!(dot < -2 * edot) || !isfinite(L))
		return;
	h = 2 * (L / 2) * (fabs(cross) + ecross) / (-dot - edot);
	if (!isfinite(h))
		return;
	h = h * (1 + 16 * EPS) + 0x1p-1000;
	pad = 16 * EPS * (fabs(a[0]) + fabs(a[1]) + fabs(b[0]) + fabs(b[1]) + h) + 0x1p-1000;
	/* the rectangle over ab of height h on its left, any direction covered by +-h */
	r[0] = fmin(a[0], b[0]) - h - pad;
	r[1] = fmin(a[1], b[1]) - h - pad;
	r[2] = fmax(a[0], b[0]) + h + pad;
	r[3] = fmax(a[1], b[1]) + h + pad;
	box[0] = fmax(box[0], r[0]);
	box[1] = fmax(box[1], r[1]);
	box[2] = fmin(box[2], r[2]);
	box[3] = fmin(box[3], r[3]);
}
