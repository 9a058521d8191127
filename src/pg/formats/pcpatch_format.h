/*
 * pcpatch_format.h
 *		pgpointcloud's pcpatch values and their schemas, read without
 *		PostgreSQL or pgpointcloud (pcpatch_read.c, pcpatch_schema.c).
 *
 * Pure C: the fuzz target (fuzz/fuzz_pcpatch.c) links these files alone.
 * Every function returns TDC_PC_OK or an error code, with a message in err.
 */
#ifndef TDC_PCPATCH_FORMAT_H
#define TDC_PCPATCH_FORMAT_H

#include <stddef.h>
#include <stdint.h>

/* Error codes: the SQL side gives each its own hint. */
#define TDC_PC_OK				0
#define TDC_PC_ERR_SCHEMA		1	/* a schema we do not read */
#define TDC_PC_ERR_NOXYZ		2	/* a schema without X, Y and Z */
#define TDC_PC_ERR_LAZ			3	/* a LAZ patch */
#define TDC_PC_ERR_COMPRESSION	4	/* an unknown patch or dimension compression */
#define TDC_PC_ERR_TRUNCATED	5	/* shorter than its header or contents say */
#define TDC_PC_ERR_CORRUPT		6	/* inconsistent contents */
#define TDC_PC_ERR_FILTER		7	/* a filter we do not read */
#define TDC_PC_ERR_NONFINITE	8	/* a coordinate that is not finite */

/* A patch's compression (the header's word, the schema's metadata) */
#define TDC_PC_NONE				0
#define TDC_PC_DIMENSIONAL		1
#define TDC_PC_LAZ				2

/* A dimension's compression inside a dimensional patch */
#define TDC_PC_DIM_NONE			0
#define TDC_PC_DIM_RLE			1
#define TDC_PC_DIM_SIGBITS		2
#define TDC_PC_DIM_ZLIB			3

/* Interpretations, numbered as pgpointcloud numbers them */
typedef enum TdcPcInterp
{
	TDC_PC_INT8 = 1, TDC_PC_UINT8, TDC_PC_INT16, TDC_PC_UINT16,
	TDC_PC_INT32, TDC_PC_UINT32, TDC_PC_INT64, TDC_PC_UINT64,
	TDC_PC_DOUBLE, TDC_PC_FLOAT
} TdcPcInterp;

#define TDC_PC_NAME_MAX			64
#define TDC_PC_MAX_DIMS			256

typedef struct TdcPcDim
{
	char		name[TDC_PC_NAME_MAX];
	TdcPcInterp interp;
	int			size;			/* bytes, from the interpretation */
	size_t		offset_bytes;	/* in an uncompressed point */
	double		scale;			/* 1 unless given */
	double		offset;			/* 0 unless given */
} TdcPcDim;

typedef struct TdcPcSchema
{
	int			ndims;
	TdcPcDim	dims[TDC_PC_MAX_DIMS];	/* by position */
	size_t		point_size;		/* bytes of an uncompressed point */
	int			compression;	/* TDC_PC_NONE, _DIMENSIONAL or _LAZ */
	int			x, y, z;		/* dimension indexes */
} TdcPcSchema;

/* A filter: keep the points whose dimension dim holds one of vals. */
#define TDC_PC_FILTER_MAX		32
typedef struct TdcPcFilter
{
	int			dim;			/* -1: no filter */
	int			nvals;
	double		vals[TDC_PC_FILTER_MAX];
} TdcPcFilter;

/* The header of a patch value (its varlena header included). */
typedef struct TdcPcHeader
{
	uint32_t	pcid;
	uint32_t	compression;
	uint32_t	npoints;
} TdcPcHeader;

#define TDC_PC_HEADER_BYTES		48	/* size, pcid, compression, npoints, bounds */

/* pcpatch_schema.c */
extern int	tdc_pc_fail(char *err, size_t errlen, int code, const char *fmt,...)
			__attribute__((format(printf, 4, 5)));
extern int	tdc_pc_schema_parse(const char *xml, size_t len, TdcPcSchema *s,
								char *err, size_t errlen);
extern int	tdc_pc_filter_parse(const char *text, const TdcPcSchema *s,
								TdcPcFilter *f, char *err, size_t errlen);

/* pcpatch_read.c */
extern int	tdc_pc_patch_header(const uint8_t *buf, size_t len, TdcPcHeader *h,
								char *err, size_t errlen);
extern int	tdc_pc_patch_check(const uint8_t *buf, size_t len, const TdcPcSchema *s,
							   char *err, size_t errlen);
extern size_t tdc_pc_scratch_bytes(const TdcPcSchema *s, uint32_t npoints);
extern int	tdc_pc_patch_decode(const uint8_t *buf, size_t len, const TdcPcSchema *s,
								const TdcPcFilter *f, double *xy, double *z,
								void *scratch, size_t *nkept,
								char *err, size_t errlen);

#endif							/* TDC_PCPATCH_FORMAT_H */
