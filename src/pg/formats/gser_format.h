/*
 * gser_format.h
 *		The PostGIS serialized geometry format, as far as tdc_delaunay reads
 *		(gser_read.c) and writes (gser_write.c) it.  Not installed.
 *
 * PostGIS 3 stores a geometry as
 *
 *	varlena header (4 bytes after detoasting)
 *	srid[3]			21-bit signed SRID, big-endian-ish: high 5 bits first
 *	gflags			Z 0x01, M 0x02, BBOX 0x04, GEODETIC 0x08,
 *					EXTENDED 0x10 (v2), VERSION 0x40 (set = v2)
 *	[uint64]		extended flags, v2 only, when EXTENDED is set
 *	[float box]		when BBOX is set: 2 floats per dimension (6 if geodetic)
 *	geometry		uint32 type, uint32 count, then
 *					  point/line/triangle/circularstring: count vertices
 *					  polygon: count ring sizes, padded to 8 bytes, then the
 *						rings' vertices
 *					  multi and collection types: count nested geometries
 *
 * Vertices are doubles, 2 to 4 per vertex (XY, XYZ, XYM, XYZM).  Version 1
 * (PostGIS 2, possibly still on disk after pg_upgrade) differs only in the
 * flags byte: no EXTENDED flag, 0x10 is a read-only bit we ignore.
 */
#ifndef TDC_GSER_FORMAT_H
#define TDC_GSER_FORMAT_H

/* Geometry type numbers of the serialized format. */
#define G_POINT				1
#define G_LINE				2
#define G_POLYGON			3
#define G_MULTIPOINT		4
#define G_MULTILINE			5
#define G_MULTIPOLYGON		6
#define G_COLLECTION		7
#define G_CIRCSTRING		8
#define G_COMPOUND			9
#define G_CURVEPOLY			10
#define G_MULTICURVE		11
#define G_MULTISURFACE		12
#define G_POLYHEDRAL		13
#define G_TRIANGLE			14
#define G_TIN				15

/* Flag bits. */
#define GF_Z				0x01
#define GF_M				0x02
#define GF_BBOX				0x04
#define GF_GEODETIC			0x08
#define GF_EXTENDED			0x10
#define GF_VERSION			0x40

/* srid[3] + gflags */
#define G_HEADER			4

#endif							/* TDC_GSER_FORMAT_H */
