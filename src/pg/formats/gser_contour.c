/*
 * gser_contour.c
 *		The contour lines of a TIN written as one PostGIS value: a
 *		MULTILINESTRING Z whose every vertex has its line's level as Z.
 *
 * The layout (gser_format.h): the header with the Z flag and, when there is
 * a line, a float box (x, y and z bounds rounded outward, as PostGIS writes
 * it, so that no function has to walk the vertices to find it), then
 * MULTILINESTRING and its count, then each LINESTRING with its count and
 * x, y, z triples.  The lines come from the core in their order (level by
 * level), each written once by this thread, with an interrupt check every
 * few thousand lines: copying is fast beside the contouring, which ran on
 * the engine's threads.
 */
#include "postgres.h"

#include <math.h>

#include "miscadmin.h"

#include "tdc_pg.h"
#include "gser_format.h"

#define LINES_PER_CHECK		4096

static void
put_header(char *out, Size size, int32 srid, bool hasbox)
{
	unsigned char *h = (unsigned char *) VARDATA(out);
	uint32		s = (uint32) srid & 0x1fffff;

	SET_VARSIZE(out, size);
	h[0] = (unsigned char) (s >> 16);
	h[1] = (unsigned char) (s >> 8);
	h[2] = (unsigned char) s;
	h[3] = GF_VERSION | GF_Z | (hasbox ? GF_BBOX : 0);
}

static inline char *
put_u32(char *p, uint32 v)
{
	memcpy(p, &v, sizeof(v));
	return p + sizeof(v);
}

/*
 * The value; room: the bytes tdc_delaunay.max_memory leaves for it
 * (PG_UINT64_MAX: no limit).
 */
struct varlena *
tdc_gser_contours(const tdc_tin *tin, int32 srid, uint64 room, const char *fname)
{
	size_t		npoints,
				nlines = tdc_tin_contour_count(tin, &npoints);
	uint64		size = VARHDRSZ + G_HEADER + 8 + (nlines > 0 ? 6 * sizeof(float) : 0) +
		(uint64) nlines * 8 + (uint64) npoints * 3 * sizeof(double);
	struct varlena *out;
	char	   *p;
	double		lo[3] = {INFINITY, INFINITY, INFINITY},
				hi[3] = {-INFINITY, -INFINITY, -INFINITY};

	if (size > (uint64) tdc_guc_max_result_bytes)
		ereport(ERROR,
				(errcode(ERRCODE_PROGRAM_LIMIT_EXCEEDED),
				 errmsg("%s: %zu contour lines of %zu vertices make a value of %llu bytes, over the limit of %d bytes for a single value",
						fname, nlines, npoints, (unsigned long long) size, tdc_guc_max_result_bytes),
				 errhint("Use a larger interval, or contour the area in parts.")));
	if (size > room)
		tdc_report_memory_limit(fname, psprintf("the contour lines' value of %llu bytes",
												(unsigned long long) size), size, 0);

	/* the box first: the extent of every point and level */
	for (size_t i = 0; i < nlines; i++)
	{
		double		level;
		size_t		n;
		bool		closed;
		const double *xy = tdc_tin_contour_line(tin, i, &level, &n, &closed);

		for (size_t k = 0; k < n; k++)
		{
			lo[0] = Min(lo[0], xy[2 * k]);
			hi[0] = Max(hi[0], xy[2 * k]);
			lo[1] = Min(lo[1], xy[2 * k + 1]);
			hi[1] = Max(hi[1], xy[2 * k + 1]);
		}
		lo[2] = Min(lo[2], level);
		hi[2] = Max(hi[2], level);
		if ((i & (LINES_PER_CHECK - 1)) == 0)
			CHECK_FOR_INTERRUPTS();
	}

	out = palloc((Size) size);
	tdc_advise_result(out, (Size) size);
	put_header((char *) out, (Size) size, srid, nlines > 0);
	p = VARDATA(out) + G_HEADER;
	if (nlines > 0)
	{
		float		box[6] = {tdc_float_down(lo[0]), tdc_float_up(hi[0]),
			tdc_float_down(lo[1]), tdc_float_up(hi[1]),
		tdc_float_down(lo[2]), tdc_float_up(hi[2])};

		memcpy(p, box, sizeof(box));
		p += sizeof(box);
	}
	p = put_u32(p, G_MULTILINE);
	p = put_u32(p, (uint32) nlines);
	for (size_t i = 0; i < nlines; i++)
	{
		double		level;
		size_t		n;
		bool		closed;
		const double *xy = tdc_tin_contour_line(tin, i, &level, &n, &closed);

		p = put_u32(p, G_LINE);
		p = put_u32(p, (uint32) n);
		for (size_t k = 0; k < n; k++)
		{
			memcpy(p, xy + 2 * k, 2 * sizeof(double));
			memcpy(p + 2 * sizeof(double), &level, sizeof(double));
			p += 3 * sizeof(double);
		}
		if ((i & (LINES_PER_CHECK - 1)) == 0)
			CHECK_FOR_INTERRUPTS();
	}
	Assert(p == (char *) out + size);
	return out;
}
