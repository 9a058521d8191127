/*
 * pcpatch_read.c
 *		The X, Y and Z of a pgpointcloud pcpatch value, decoded in pure C.
 *
 * A stored patch (pgpointcloud's SERIALIZED_PATCH; the facts here are from
 * its pc_pgsql.c, pc_bytes.c and pc_dimstats.c) is, in the machine's byte
 * order:
 *
 *	uint32 varlena size, uint32 pcid, uint32 compression, uint32 npoints,
 *	float8 xmin, xmax, ymin, ymax, then at byte 48 the statistics (three
 *	uncompressed points: min, max, average) and the points.
 *
 * pgpointcloud sizes the value as BUFFERALIGN(sizeof header) - 1 + stats +
 * points, so up to 15 bytes of zeros follow the points; we only require
 * that the points end inside the value.
 *
 * Compression none: npoints uncompressed points, each dimension at its
 * offset in position order.  Compression dimensional: one block per
 * dimension in position order, each a uint8 compression, a uint32 length
 * and that many bytes:
 *	- none: npoints values;
 *	- run-length: (uint8 count, value) pairs whose counts add up to npoints;
 *	- significant bits: words as wide as the value (1, 2, 4 or 8 bytes):
 *	  the number of unique low bits b, the common value c, then each value's
 *	  b low bits packed from the most significant bit of each word down,
 *	  running on into the next word; a value is c | its bits;
 *	- zlib: a zlib stream of the npoints values.
 * Compression laz needs LAZperf, which Debian's pgpointcloud is built
 * without: refused with its own code so that the SQL side can say so.
 *
 * A value is the raw number times scale (when scale is not 1) plus offset
 * (when it is not 0), exactly as pgpointcloud's pc_value_scale_offset
 * computes it, so that PC_Get and this reader give the same double.
 *
 * Every length is checked before it is read: the fuzz target
 * (fuzz/fuzz_pcpatch.c) feeds this file arbitrary bytes.  The header's
 * point count is a uint32 the caller would reserve memory for, so
 * tdc_pc_patch_check first bounds it by what the X, Y and Z blocks can
 * hold, and a forged count is refused as a truncation.  The caller gives
 * the output arrays (npoints places each) and a scratch area of
 * tdc_pc_scratch_bytes; nothing here allocates but zlib's stream state,
 * released before returning.
 */
#include <math.h>
#include <stdbool.h>
#include <stdio.h>
#include <string.h>

#include <zlib.h>

#include "formats/pcpatch_format.h"


int
tdc_pc_patch_header(const uint8_t *buf, size_t len, TdcPcHeader *h,
					char *err, size_t errlen)
{
	if (len < TDC_PC_HEADER_BYTES)
		return tdc_pc_fail(err, errlen, TDC_PC_ERR_TRUNCATED,
					"%zu bytes, shorter than a patch header (%d)", len, TDC_PC_HEADER_BYTES);
	memcpy(&h->pcid, buf + 4, 4);
	memcpy(&h->compression, buf + 8, 4);
	memcpy(&h->npoints, buf + 12, 4);
	return TDC_PC_OK;
}

/*
 * What both passes begin with: the header, a compression we read, and the
 * statistics (three uncompressed points) skipped; *pos is where the points
 * begin.
 */
static int
patch_start(const uint8_t *buf, size_t len, const TdcPcSchema *s, TdcPcHeader *h,
			size_t *pos, char *err, size_t errlen)
{
	int			rc;

	if ((rc = tdc_pc_patch_header(buf, len, h, err, errlen)) != TDC_PC_OK)
		return rc;
	if (h->compression == TDC_PC_LAZ)
		return tdc_pc_fail(err, errlen, TDC_PC_ERR_LAZ, "a LAZ-compressed patch");
	if (h->compression != TDC_PC_NONE && h->compression != TDC_PC_DIMENSIONAL)
		return tdc_pc_fail(err, errlen, TDC_PC_ERR_COMPRESSION,
						   "unknown patch compression %u", h->compression);
	if (len - TDC_PC_HEADER_BYTES < 3 * s->point_size)
		return tdc_pc_fail(err, errlen, TDC_PC_ERR_TRUNCATED,
						   "%zu bytes, too short for the patch statistics", len);
	*pos = TDC_PC_HEADER_BYTES + 3 * s->point_size;
	return TDC_PC_OK;
}

/*
 * Before the caller sets aside room for the header's point count: does
 * the layout leave room for that many points?  Uncompressed: the bytes
 * must hold them.  Dimensional: every block must fit in the value, and
 * those of X, Y and Z may not hold fewer than npoints (a run-length block's counts are
 * summed; significant bits with b > 0 bits hold at most 8 bits a byte; a
 * zlib stream inflates at most 1032 times, deflate's limit).  Only a
 * block of significant bits with no unique bit, or an empty patch, holds
 * any count.  So a forged count is refused as the truncation it is,
 * before memory is taken for it; tdc_pc_patch_decode checks the rest.
 */
int
tdc_pc_patch_check(const uint8_t *buf, size_t len, const TdcPcSchema *s,
				   char *err, size_t errlen)
{
	TdcPcHeader h;
	int			rc;
	size_t		pos = 0;
	uint64_t	n;

	if ((rc = patch_start(buf, len, s, &h, &pos, err, errlen)) != TDC_PC_OK)
		return rc;
	n = h.npoints;
	if (h.compression == TDC_PC_NONE)
	{
		if ((len - pos) / s->point_size < n)
			return tdc_pc_fail(err, errlen, TDC_PC_ERR_TRUNCATED,
							   "%zu bytes, too short for %u points of %zu bytes",
							   len, h.npoints, s->point_size);
		return TDC_PC_OK;
	}
	for (int d = 0; d < s->ndims; d++)
	{
		const TdcPcDim *dim = &s->dims[d];
		uint64_t	w = (uint64_t) dim->size,
					most = UINT64_MAX;
		uint32_t	size;
		const uint8_t *b;

		if (len - pos < 5)
			return tdc_pc_fail(err, errlen, TDC_PC_ERR_TRUNCATED,
							   "the patch ends before dimension \"%s\"", dim->name);
		memcpy(&size, buf + pos + 1, 4);
		b = buf + pos + 5;
		if (len - pos - 5 < size)
			return tdc_pc_fail(err, errlen, TDC_PC_ERR_TRUNCATED,
							   "the patch ends inside dimension \"%s\"", dim->name);
		switch (buf[pos])
		{
			case TDC_PC_DIM_NONE:
				most = size / w;
				break;
			case TDC_PC_DIM_RLE:
				most = 0;
				for (uint64_t k = 0; k + 1 + w <= size; k += 1 + w)
					most += b[k];
				break;
			case TDC_PC_DIM_SIGBITS:
				if (size >= 2 * w)
				{
					uint64_t	nbits = 0;

					memcpy(&nbits, b, (size_t) w);	/* the low bytes */
					if (nbits > 0)
						most = (size - 2 * w) * 8 / nbits;
				}
				break;
			case TDC_PC_DIM_ZLIB:
				most = ((uint64_t) size * 1032 + 64) / w;
				break;
			default:
				return tdc_pc_fail(err, errlen, TDC_PC_ERR_COMPRESSION,
								   "dimension \"%s\": unknown dimension compression %d",
								   dim->name, buf[pos]);
		}
		/* X, Y and Z are what the decoder must fill (it reads no other block's bytes) */
		if (most < n && (d == s->x || d == s->y || d == s->z))
			return tdc_pc_fail(err, errlen, TDC_PC_ERR_TRUNCATED,
							   "dimension \"%s\" cannot hold the %u points the header says",
							   dim->name, h.npoints);
		pos += 5 + (size_t) size;
	}
	return TDC_PC_OK;
}

/* The filter's values, then one dimension's raw values out of zlib. */
size_t
tdc_pc_scratch_bytes(const TdcPcSchema *s, uint32_t npoints)
{
	return (size_t) npoints * 2 * sizeof(double);
}

/* The raw value held in the low bytes of w, as a double. */
static double
raw_value(uint64_t w, TdcPcInterp interp)
{
	switch (interp)
	{
		case TDC_PC_INT8:
			return (double) (int8_t) (uint8_t) w;
		case TDC_PC_UINT8:
			return (double) (uint8_t) w;
		case TDC_PC_INT16:
			return (double) (int16_t) (uint16_t) w;
		case TDC_PC_UINT16:
			return (double) (uint16_t) w;
		case TDC_PC_INT32:
			return (double) (int32_t) (uint32_t) w;
		case TDC_PC_UINT32:
			return (double) (uint32_t) w;
		case TDC_PC_INT64:
			return (double) (int64_t) w;
		case TDC_PC_UINT64:
			return (double) w;
		case TDC_PC_FLOAT:
			{
				uint32_t	u = (uint32_t) w;
				float		f;

				memcpy(&f, &u, 4);
				return (double) f;
			}
		case TDC_PC_DOUBLE:
			{
				double		d;

				memcpy(&d, &w, 8);
				return d;
			}
	}
	return 0;
}

/* The word of size bytes at p, in the machine's order. */
static uint64_t
load_word(const uint8_t *p, int size)
{
	switch (size)
	{
		case 1:
			return p[0];
		case 2:
			{
				uint16_t	v;

				memcpy(&v, p, 2);
				return v;
			}
		case 4:
			{
				uint32_t	v;

				memcpy(&v, p, 4);
				return v;
			}
		default:
			{
				uint64_t	v;

				memcpy(&v, p, 8);
				return v;
			}
	}
}

/*
 * The scaled value; volatile-free but written as two statements that the
 * build keeps apart (-ffp-contract=off), as pgpointcloud's are.
 */
static double
scaled(const TdcPcDim *d, uint64_t w)
{
	double		v = raw_value(w, d->interp);

	if (d->scale != 1)
		v *= d->scale;
	if (d->offset != 0)
		v += d->offset;
	return v;
}

/* Write value i of a dimension: to its place among x,y (stride 2) or z. */
typedef struct Out
{
	double	   *base;
	size_t		stride;
}			Out;

/* Decode one dimensional block (data, size bytes) into out. */
static int
decode_block(int comp, const uint8_t *data, size_t size, const TdcPcDim *d,
			 uint32_t n, Out out, uint8_t *zbuf, char *err, size_t errlen)
{
	size_t		w = (size_t) d->size;

	switch (comp)
	{
		case TDC_PC_DIM_NONE:
			if (size != (size_t) n * w)
				return tdc_pc_fail(err, errlen, TDC_PC_ERR_CORRUPT,
							"dimension \"%s\": %zu bytes for %u uncompressed values",
							d->name, size, n);
			for (uint32_t i = 0; i < n; i++)
				out.base[i * out.stride] = scaled(d, load_word(data + i * w, d->size));
			return TDC_PC_OK;
		case TDC_PC_DIM_RLE:
			{
				size_t		pos = 0;
				uint32_t	i = 0;

				while (pos < size)
				{
					uint8_t		count;
					double		v;

					if (size - pos < 1 + w)
						return tdc_pc_fail(err, errlen, TDC_PC_ERR_CORRUPT,
									"dimension \"%s\": a run-length block ends inside a run", d->name);
					count = data[pos];
					if (count > n - i)
						return tdc_pc_fail(err, errlen, TDC_PC_ERR_CORRUPT,
									"dimension \"%s\": runs of more than %u values", d->name, n);
					v = scaled(d, load_word(data + pos + 1, d->size));
					for (uint8_t k = 0; k < count; k++)
						out.base[(i++) * out.stride] = v;
					pos += 1 + w;
				}
				if (i != n)
					return tdc_pc_fail(err, errlen, TDC_PC_ERR_CORRUPT,
								"dimension \"%s\": runs of %u values, not %u", d->name, i, n);
				return TDC_PC_OK;
			}
		case TDC_PC_DIM_SIGBITS:
			{
				unsigned	bits = (unsigned) w * 8;
				uint64_t	nbits,
							common;
				uint64_t	need;
				uint64_t	bitpos = 0;

				if (size < 2 * w)
					return tdc_pc_fail(err, errlen, TDC_PC_ERR_CORRUPT,
								"dimension \"%s\": a significant-bits block without its header", d->name);
				nbits = load_word(data, d->size);
				common = load_word(data + w, d->size);
				if (nbits > bits)
					return tdc_pc_fail(err, errlen, TDC_PC_ERR_CORRUPT,
								"dimension \"%s\": %llu significant bits in a %u-bit value",
								d->name, (unsigned long long) nbits, bits);
				need = ((uint64_t) nbits * n + bits - 1) / bits * w;
				if (need > size - 2 * w)
					return tdc_pc_fail(err, errlen, TDC_PC_ERR_CORRUPT,
								"dimension \"%s\": %zu bytes for %u values of %llu bits",
								d->name, size, n, (unsigned long long) nbits);
				data += 2 * w;
				for (uint32_t i = 0; i < n; i++)
				{
					uint64_t	v = 0;
					unsigned	left = (unsigned) nbits;

					/* take the value's bits from one word or two */
					while (left > 0)
					{
						uint64_t	word = load_word(data + (bitpos / bits) * w, d->size);
						unsigned	avail = bits - (unsigned) (bitpos % bits);
						unsigned	take = left < avail ? left : avail;
						uint64_t	part = (word >> (avail - take)) &
							(take == 64 ? ~(uint64_t) 0 : (((uint64_t) 1 << take) - 1));

						v = take == 64 ? part : (v << take) | part;
						left -= take;
						bitpos += take;
					}
					out.base[i * out.stride] = scaled(d, v | common);
				}
				return TDC_PC_OK;
			}
		case TDC_PC_DIM_ZLIB:
			{
				z_stream	zs;
				int			rc;
				size_t		want = (size_t) n * w;
				bool		ok;

				if (want == 0)
					return TDC_PC_OK;	/* nothing to inflate into */
				memset(&zs, 0, sizeof(zs));
				if (inflateInit(&zs) != Z_OK)
					return tdc_pc_fail(err, errlen, TDC_PC_ERR_CORRUPT, "zlib could not start");
				zs.next_in = (Bytef *) data;
				zs.avail_in = (uInt) size;
				zs.next_out = zbuf;
				zs.avail_out = (uInt) want;
				rc = inflate(&zs, Z_FINISH);
				ok = rc == Z_STREAM_END && zs.avail_out == 0;
				inflateEnd(&zs);
				if (!ok)
					return tdc_pc_fail(err, errlen, TDC_PC_ERR_CORRUPT,
								"dimension \"%s\": the zlib stream does not hold %u values",
								d->name, n);
				for (uint32_t i = 0; i < n; i++)
					out.base[i * out.stride] = scaled(d, load_word(zbuf + i * w, d->size));
				return TDC_PC_OK;
			}
	}
	return tdc_pc_fail(err, errlen, TDC_PC_ERR_COMPRESSION,
				"dimension \"%s\": unknown dimension compression %d", d->name, comp);
}

/*
 * The points of the patch buf (len bytes, its varlena header included)
 * under schema s: x,y into xy, z into z, only those that pass f, in their
 * order; *nkept says how many.  xy, z and scratch are the caller's, for
 * the header's npoints.
 */
int
tdc_pc_patch_decode(const uint8_t *buf, size_t len, const TdcPcSchema *s,
					const TdcPcFilter *f, double *xy, double *z,
					void *scratch, size_t *nkept, char *err, size_t errlen)
{
	TdcPcHeader h;
	int			rc;
	size_t		pos = 0;
	uint32_t	n;
	double	   *fv = (double *) scratch;
	uint8_t    *zbuf = (uint8_t *) scratch;
	bool		filtering = f != NULL && f->dim >= 0;

	*nkept = 0;
	if ((rc = patch_start(buf, len, s, &h, &pos, err, errlen)) != TDC_PC_OK)
		return rc;
	n = h.npoints;
	/* the filter's values go after the zlib buffer's n values */
	if (filtering)
		fv = (double *) scratch + n;

	if (h.compression == TDC_PC_NONE)
	{
		if ((len - pos) / s->point_size < n)
			return tdc_pc_fail(err, errlen, TDC_PC_ERR_TRUNCATED,
						"%zu bytes, too short for %u points of %zu bytes", len, n, s->point_size);
		for (uint32_t i = 0; i < n; i++)
		{
			const uint8_t *pt = buf + pos + (size_t) i * s->point_size;
			const TdcPcDim *dx = &s->dims[s->x],
					   *dy = &s->dims[s->y],
					   *dz = &s->dims[s->z];

			xy[2 * i] = scaled(dx, load_word(pt + dx->offset_bytes, dx->size));
			xy[2 * i + 1] = scaled(dy, load_word(pt + dy->offset_bytes, dy->size));
			z[i] = scaled(dz, load_word(pt + dz->offset_bytes, dz->size));
			if (filtering)
			{
				const TdcPcDim *df = &s->dims[f->dim];

				fv[i] = scaled(df, load_word(pt + df->offset_bytes, df->size));
			}
		}
	}
	else
	{
		for (int d = 0; d < s->ndims; d++)
		{
			uint8_t		comp;
			uint32_t	size;
			Out			out = {NULL, 1};

			if (len - pos < 5)
				return tdc_pc_fail(err, errlen, TDC_PC_ERR_TRUNCATED,
							"the patch ends before dimension \"%s\"", s->dims[d].name);
			comp = buf[pos];
			memcpy(&size, buf + pos + 1, 4);
			pos += 5;
			if (len - pos < size)
				return tdc_pc_fail(err, errlen, TDC_PC_ERR_TRUNCATED,
							"the patch ends inside dimension \"%s\"", s->dims[d].name);
			if (d == s->x)
				out = (Out) {xy, 2};
			else if (d == s->y)
				out = (Out) {xy + 1, 2};
			else if (d == s->z)
				out = (Out) {z, 1};
			else if (filtering && d == f->dim)
				out = (Out) {fv, 1};
			if (out.base != NULL)
			{
				rc = decode_block(comp, buf + pos, size, &s->dims[d], n, out, zbuf, err, errlen);
				if (rc != TDC_PC_OK)
					return rc;
				/* a filter on X, Y or Z itself reads their values */
				if (filtering && d == f->dim && out.base != fv)
					for (uint32_t i = 0; i < n; i++)
						fv[i] = out.base[i * out.stride];
			}
			else if (comp > TDC_PC_DIM_ZLIB)
				return tdc_pc_fail(err, errlen, TDC_PC_ERR_COMPRESSION,
							"dimension \"%s\": unknown dimension compression %d",
							s->dims[d].name, comp);
			pos += size;
		}
	}

	/* the filter, then the coordinates' check, in place */
	{
		size_t		k = 0;

		for (uint32_t i = 0; i < n; i++)
		{
			if (filtering)
			{
				bool		keep = false;

				for (int j = 0; j < f->nvals; j++)
					if (fv[i] == f->vals[j])
						keep = true;
				if (!keep)
					continue;
			}
			if (!isfinite(xy[2 * i]) || !isfinite(xy[2 * i + 1]) || !isfinite(z[i]))
				return tdc_pc_fail(err, errlen, TDC_PC_ERR_NONFINITE,
							"point %u has a coordinate that is not finite", i + 1);
			xy[2 * k] = xy[2 * i];
			xy[2 * k + 1] = xy[2 * i + 1];
			z[k] = z[i];
			k++;
		}
		*nkept = k;
	}
	return TDC_PC_OK;
}
