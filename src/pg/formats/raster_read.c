/*
 * raster_read.c
 *		Reading a template raster: its geometry (size, geotransform, SRID)
 *		and one band's pixel type and nodata value, from PostGIS's stored
 *		raster format (raster_format.h), without PostGIS's library.
 *
 * A template is often a big value: a band of 1000 x 1000 doubles is 8 MB,
 * stored out of line and maybe compressed, and only its first bytes matter.
 * So the value is never detoasted whole.  tdc_raster_parse works on a
 * prefix of the value and says how long a prefix it needs when the one it
 * got is too short; tdc_raster_read asks PostgreSQL for that prefix
 * (PG_DETOAST_DATUM_SLICE fetches only the TOAST chunks that hold it, and
 * decompresses only up to it) and parses again.  Band 1 takes one slice of
 * 256 bytes; band k, the prefix up to its header, which runs through the
 * pixels of the bands before it (their lengths follow from the header, so
 * at most one more slice per out-of-database band before it, whose path has
 * to be read to find where it ends).
 *
 * What is checked, since a value is only as good as whatever wrote it: the
 * format version (0), the band number (1 to the band count; an ERROR that
 * names both), every pixel type on the way (PostGIS's twelve numbers), and
 * that every band up to the wanted one ends inside the value (its pixels,
 * or its path's NUL).  A corrupt value is an ERROR naming the byte, never a
 * read outside the slice.  The wanted band must be stored in the database:
 * an out-of-database band (a file path that PostGIS opens through GDAL) is
 * an ERROR, as nothing here reads files.  Nothing is done with the pixels,
 * so a header-only check suffices: as PostGIS, the reader does not insist
 * on the padding after the last band.
 *
 * Every multi-byte number is read with memcpy: a slice's data start 4
 * bytes after an 8-byte-aligned palloc chunk, so the doubles are not
 * aligned, and the format is in the machine's byte order anyway.
 */
#include "postgres.h"

#include <math.h>

#include "access/detoast.h"

#include "tdc_pg.h"
#include "raster_format.h"

/* The first slice: the header and the first band's header, with room. */
#define FIRST_SLICE			256

const char *
tdc_raster_pixtype_name(int pixtype)
{
	static const char *const names[RT_PT_COUNT] = {
		"1BB", "2BUI", "4BUI", "8BSI", "8BUI", "16BSI", "16BUI",
		"32BSI", "32BUI", "16BF", "32BF", "64BF"
	};

	return pixtype >= 0 && pixtype < RT_PT_COUNT ? names[pixtype] : "?";
}

/*
 * The parse works on positions in the whole value (its varlena header
 * included, as the format's alignment counts from there); "data" holds the
 * bytes from position VARHDRSZ on.
 */
typedef struct Prefix
{
	const char *data;
	Size		have;			/* bytes in data */
	Size		total;			/* the value's size, header included */
	const char *fname;
} Prefix;

static pg_noreturn void
corrupt(const Prefix *p, const char *what, uint64 pos)
{
	ereport(ERROR,
			(errcode(ERRCODE_DATA_CORRUPTED),
			 errmsg("%s: corrupt raster value: %s at byte %llu of %llu",
					p->fname, what, (unsigned long long) pos,
					(unsigned long long) p->total)));
}

/* Is [pos, pos + n) in the prefix?  pos >= VARHDRSZ. */
static inline bool
in_prefix(const Prefix *p, uint64 pos, uint64 n)
{
	return pos + n <= (uint64) p->have + VARHDRSZ;
}

static inline const char *
at(const Prefix *p, uint64 pos)
{
	return p->data + (pos - VARHDRSZ);
}

static uint16
get_u16(const Prefix *p, uint64 pos)
{
	uint16		v;

	memcpy(&v, at(p, pos), sizeof(v));
	return v;
}

static double
get_f64(const Prefix *p, uint64 pos)
{
	double		v;

	memcpy(&v, at(p, pos), sizeof(v));
	return v;
}

/*
 * The nodata value at pos as PostGIS reads it (rt_raster_deserialize): the
 * sub-byte types masked to their bits, the others widened to double.
 */
static double
get_nodata(const Prefix *p, uint64 pos, int pixtype)
{
	const char *s = at(p, pos);

	switch (pixtype)
	{
		case RT_PT_1BB:
			return (uint8) s[0] & RT_1BB_MAX;
		case RT_PT_2BUI:
			return (uint8) s[0] & RT_2BUI_MAX;
		case RT_PT_4BUI:
			return (uint8) s[0] & RT_4BUI_MAX;
		case RT_PT_8BSI:
			return (int8) s[0];
		case RT_PT_8BUI:
			return (uint8) s[0];
		case RT_PT_16BSI:
			{
				int16		v;

				memcpy(&v, s, sizeof(v));
				return v;
			}
		case RT_PT_16BUI:
			{
				uint16		v;

				memcpy(&v, s, sizeof(v));
				return v;
			}
		case RT_PT_32BSI:
			{
				int32		v;

				memcpy(&v, s, sizeof(v));
				return v;
			}
		case RT_PT_32BUI:
			{
				uint32		v;

				memcpy(&v, s, sizeof(v));
				return v;
			}
		case RT_PT_16BF:
			{
				uint16		h;
				int			e;
				double		m;

				memcpy(&h, s, sizeof(h));
				e = (h >> 10) & 0x1F;
				m = h & 0x3FF;
				if (e == 0x1F)
					m = m != 0 ? NAN : INFINITY;
				else if (e == 0)
					m = ldexp(m, -24);	/* subnormal: m * 2^-14 / 2^10 */
				else
					m = ldexp(m + 1024, e - 25);
				return (h & 0x8000) ? -m : m;
			}
		case RT_PT_32BF:
			{
				float		v;

				memcpy(&v, s, sizeof(v));
				return v;
			}
		case RT_PT_64BF:
			return get_f64(p, pos);
	}
	return 0;					/* not reached: pixtype was checked */
}

/*
 * Parse the first "have" bytes after the varlena header of a raster value
 * of "total" bytes (header included) for band "band" (1-based).  Returns 0
 * with *info filled in, or the number of bytes after the header that it
 * needs to see (more than have, at most total - VARHDRSZ).  An ERROR for a
 * band number out of range, an out-of-database band and a corrupt value.
 */
Size
tdc_raster_parse(const char *data, Size have, Size total, int band,
				 TdcRasterInfo *info, const char *fname)
{
	Prefix		p = {data, Min(have, total - Min(total, VARHDRSZ)), total, fname};
	uint64		pos;
	uint16		version;

	if (total < RT_HEADER_BYTES)
		corrupt(&p, "the value is shorter than the 64-byte raster header", total);
	if (!in_prefix(&p, VARHDRSZ, RT_HEADER_BYTES - VARHDRSZ))
		return Min(FIRST_SLICE, total - VARHDRSZ);

	version = get_u16(&p, RT_OFF_VERSION);
	if (version != RT_FORMAT_VERSION)
		ereport(ERROR,
				(errcode(ERRCODE_DATA_CORRUPTED),
				 errmsg("%s: raster format version %u is not supported (only %d)",
						fname, version, RT_FORMAT_VERSION)));
	info->nbands = get_u16(&p, RT_OFF_NBANDS);
	info->gt[0] = get_f64(&p, RT_OFF_IPX);
	info->gt[1] = get_f64(&p, RT_OFF_SCALEX);
	info->gt[2] = get_f64(&p, RT_OFF_SKEWX);
	info->gt[3] = get_f64(&p, RT_OFF_IPY);
	info->gt[4] = get_f64(&p, RT_OFF_SKEWY);
	info->gt[5] = get_f64(&p, RT_OFF_SCALEY);
	memcpy(&info->srid, at(&p, RT_OFF_SRID), sizeof(info->srid));
	info->width = get_u16(&p, RT_OFF_WIDTH);
	info->height = get_u16(&p, RT_OFF_HEIGHT);

	if (band < 1 || band > info->nbands)
		ereport(ERROR,
				(errcode(ERRCODE_INVALID_PARAMETER_VALUE),
				 errmsg("%s: the raster has no band %d", fname, band),
				 errdetail("It has %u band%s.", info->nbands,
						   info->nbands == 1 ? "" : "s")));

	pos = RT_HEADER_BYTES;
	for (int k = 1;; k++)
	{
		uint8		flags;
		int			pixtype;
		int			pb;
		uint64		end;

		/* the band's first byte, its padding and its nodata value */
		if (pos >= total)
			corrupt(&p, psprintf("band %d starts past the end", k), pos);
		if (!in_prefix(&p, pos, Min(16, total - pos)))
			return Min(pos + 16, total) - VARHDRSZ;
		flags = (uint8) *at(&p, pos);
		pixtype = flags & RT_BAND_PIXTYPE_MASK;
		pb = tdc_raster_pixel_bytes(pixtype);
		if (pb == 0)
			corrupt(&p, psprintf("band %d has pixel type %d, which PostGIS does not know",
								 k, pixtype), pos);
		if (pos + 2 * pb > total)
			corrupt(&p, psprintf("band %d's nodata value is cut off", k), pos);

		if (k == band)
		{
			if (flags & RT_BAND_OFFDB)
				ereport(ERROR,
						(errcode(ERRCODE_FEATURE_NOT_SUPPORTED),
						 errmsg("%s: band %d of the raster is stored out of the database",
								fname, band),
						 errdetail("Its pixels are in a file that PostGIS reads through GDAL; a template band must be stored in the database."),
						 errhint("Use a band made by ST_AddBand, or copy the band in with ST_AddBand(ST_MakeEmptyRaster(rast), rast, %d).",
								 band)));
			/* as PostGIS: the flags and the value, whatever the pixels */
			if ((uint64) info->width * info->height * pb > total - (pos + 2 * pb))
				corrupt(&p, psprintf("band %d's pixels run past the end", k), pos);
			info->band = band;
			info->b.pixtype = pixtype;
			info->b.hasnodata = (flags & RT_BAND_HASNODATA) != 0;
			info->b.isnodata = info->b.hasnodata && (flags & RT_BAND_ISNODATA) != 0;
			info->b.nodata = get_nodata(&p, pos + pb, pixtype);
			return 0;
		}

		if (flags & RT_BAND_OFFDB)
		{
			/* band number, then the path up to its NUL */
			uint64		path = pos + 2 * pb + 1;
			const char *nul;

			if (path >= total)
				corrupt(&p, psprintf("band %d's file path is cut off", k), pos);
			if (!in_prefix(&p, path, 1))
				return Min(path + 4096, total) - VARHDRSZ;
			nul = memchr(at(&p, path), '\0', p.have + VARHDRSZ - path);
			if (nul == NULL)
			{
				uint64		seen = (uint64) p.have + VARHDRSZ;

				if (seen >= total)
					corrupt(&p, psprintf("band %d's file path has no end", k), path);
				/* twice as far: a path is rarely long, but may be */
				return Min(Max(seen * 2, path + 4096), total) - VARHDRSZ;
			}
			end = path + (uint64) (nul - at(&p, path)) + 1;
		}
		else
		{
			end = pos + 2 * pb + (uint64) info->width * info->height * pb;
			if (end > total)
				corrupt(&p, psprintf("band %d's pixels run past the end", k), pos);
		}
		pos = TYPEALIGN(8, end);
	}
}

/*
 * Read band "band" (1-based) of the raster argument d into *info, fetching
 * as short a prefix of the value as the band's header allows.
 */
void
tdc_raster_read(Datum d, int band, TdcRasterInfo *info, const char *fname)
{
	Size		total = toast_raw_datum_size(d);
	Size		want = Min(FIRST_SLICE, total - Min(total, VARHDRSZ));

	for (;;)
	{
		struct varlena *slice = PG_DETOAST_DATUM_SLICE(d, 0, (int32) want);
		Size		got = VARSIZE_ANY_EXHDR(slice);
		Size		need;

		if (got < want)
			ereport(ERROR,
					(errcode(ERRCODE_DATA_CORRUPTED),
					 errmsg("%s: corrupt raster value: %zu bytes stored where its size says %zu",
							fname, got + VARHDRSZ, total)));
		need = tdc_raster_parse(VARDATA_ANY(slice), got, total, band, info, fname);
		if ((Pointer) slice != DatumGetPointer(d))
			pfree(slice);
		if (need == 0)
			return;
		/* the parse asks only for more than it had, within the value */
		Assert(need > got && need <= total - VARHDRSZ);
		want = need;
	}
}
