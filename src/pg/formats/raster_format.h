/*
 * raster_format.h
 *		PostGIS's raster value (the postgis_raster extension's "raster"
 *		type) as tdc_delaunay reads a template of it (raster_read.c) and
 *		writes a one-band result (raster_write.c).  Not installed.
 *
 * The stored value, every number in the machine's byte order (PostGIS
 * copies its C struct and its pixel arrays with memcpy; RFC1 in PostGIS's
 * doc/ describes the format, rt_serialize.c implements it):
 *
 *	offset	bytes
 *	0		4	varlena header (the value's size, as every varlena)
 *	4		2	format version, 0 (the only one PostGIS has written)
 *	6		2	number of bands
 *	8		8	scale x (pixel width)		GDAL gt[1]
 *	16		8	scale y (pixel height)		gt[5]
 *	24		8	insertion point x			gt[0]
 *	32		8	insertion point y			gt[3]
 *	40		8	skew x						gt[2]
 *	48		8	skew y						gt[4]
 *	56		4	SRID (signed; 0 unknown)
 *	60		2	width (columns)
 *	62		2	height (rows)
 *	64		bands, one after the other, each starting at a multiple of 8:
 *		1	pixel type (low 4 bits) and flags (high 4 bits)
 *		p-1	zeros, p the pixel type's size in bytes, so that what follows
 *			is aligned to p
 *		p	the nodata value in the pixel type (meaningful when HASNODATA)
 *		in-database band: width * height pixels of p bytes, row by row
 *			from the top-left pixel (row 0 at the insertion point)
 *		out-of-database band: 1 byte band number (0-based), then the
 *			file's path, NUL-terminated
 *		zeros up to the next multiple of 8 (from offset 0)
 *
 * Pixel (col, row) covers the parallelogram whose corner (col, row) is
 *	x = ipx + col * scalex + row * skewx
 *	y = ipy + col * skewy + row * scaley
 * (PostGIS's rt_raster_get_geotransform_matrix gives the same six numbers in
 * GDAL's order, which TdcRasterInfo.gt keeps.)  The sub-byte types (1BB,
 * 2BUI, 4BUI) take one byte per pixel; PostGIS masks their nodata byte to
 * the type's bits when it reads it.  16BF (IEEE half) exists from PostGIS
 * 3.7 on; its number 9 was unused before, so the numbering of the other
 * types is the same in every version.
 */
#ifndef TDC_RASTER_FORMAT_H
#define TDC_RASTER_FORMAT_H

#include "tdc_pg.h"

/* Pixel types: PostGIS's rt_pixtype numbers. */
#define RT_PT_1BB			0
#define RT_PT_2BUI			1
#define RT_PT_4BUI			2
#define RT_PT_8BSI			3
#define RT_PT_8BUI			4
#define RT_PT_16BSI			5
#define RT_PT_16BUI			6
#define RT_PT_32BSI			7
#define RT_PT_32BUI			8
#define RT_PT_16BF			9
#define RT_PT_32BF			10
#define RT_PT_64BF			11
#define RT_PT_COUNT			12

/* The high bits of a band's first byte. */
#define RT_BAND_PIXTYPE_MASK	0x0F
#define RT_BAND_OFFDB		0x80
#define RT_BAND_HASNODATA	0x40
#define RT_BAND_ISNODATA	0x20	/* every pixel is nodata */

/* Offsets in the value, its varlena header included. */
#define RT_OFF_VERSION		4
#define RT_OFF_NBANDS		6
#define RT_OFF_SCALEX		8
#define RT_OFF_SCALEY		16
#define RT_OFF_IPX			24
#define RT_OFF_IPY			32
#define RT_OFF_SKEWX		40
#define RT_OFF_SKEWY		48
#define RT_OFF_SRID			56
#define RT_OFF_WIDTH		60
#define RT_OFF_HEIGHT		62
#define RT_HEADER_BYTES		64

#define RT_FORMAT_VERSION	0

/* The largest values of the sub-byte types (PostGIS's POSTGIS_RT_*MAX). */
#define RT_1BB_MAX			1
#define RT_2BUI_MAX			3
#define RT_4BUI_MAX			15
/* The largest finite half (PostGIS's POSTGIS_RT_16F_MAX). */
#define RT_16BF_MAX			65504.0f

/* A band's pixel type and nodata value. */
typedef struct TdcRasterBand
{
	int			pixtype;		/* RT_PT_* */
	bool		hasnodata;
	bool		isnodata;		/* flagged as nodata throughout */
	double		nodata;			/* as PostGIS reads it (masked, widened) */
} TdcRasterBand;

/* A raster's geometry, and one band of it. */
typedef struct TdcRasterInfo
{
	int32		srid;
	uint16		width;
	uint16		height;
	uint16		nbands;
	double		gt[6];			/* GDAL's order: ipx, scalex, skewx, ipy, skewy, scaley */
	int			band;			/* 1-based number of "b" */
	TdcRasterBand b;
} TdcRasterInfo;

/* Bytes per pixel of a pixel type; 0 for a number that is none. */
static inline int
tdc_raster_pixel_bytes(int pixtype)
{
	static const int8 bytes[RT_PT_COUNT] = {1, 1, 1, 1, 1, 2, 2, 4, 4, 2, 4, 8};

	return pixtype >= 0 && pixtype < RT_PT_COUNT ? bytes[pixtype] : 0;
}

/* PostGIS's name of a pixel type ("8BUI"), "?" for none. */
extern const char *tdc_raster_pixtype_name(int pixtype);

/* raster_read.c */
extern Size tdc_raster_parse(const char *data, Size have, Size total, int band,
							 TdcRasterInfo *info, const char *fname);
extern void tdc_raster_read(Datum d, int band, TdcRasterInfo *info,
							const char *fname);

/* raster_write.c */
extern double tdc_raster_nodata_value(int pixtype, double nodata);
extern double tdc_raster_pixel_value(int pixtype, double nodata, double v);
extern uint64 tdc_raster_value_size(uint32 width, uint32 height, int pixtype);

/* A one-band raster value being written. */
typedef struct TdcRasterWriter
{
	struct varlena *value;
	char	   *pixels;			/* width * height pixels, aligned to their size */
	int			pixtype;
	double		nodata;			/* as stored (tdc_raster_nodata_value) */
	Size		npixels;
	uint32		width;
} TdcRasterWriter;

extern void tdc_raster_alloc(const TdcRasterInfo *geom, int pixtype,
							 double nodata, const char *fname,
							 TdcRasterWriter *w);
extern void tdc_raster_fill(TdcRasterWriter *w, const double *values,
							const uint8 *valid);

#endif							/* TDC_RASTER_FORMAT_H */
