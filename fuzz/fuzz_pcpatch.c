/*
 * fuzz_pcpatch.c
 *		libFuzzer target for the pgpointcloud patch and schema reader
 *		(src/pg/formats/pcpatch_read.c, pcpatch_schema.c): pure C, no
 *		PostgreSQL, linked with zlib.
 *
 * Input: byte 0 picks the mode (% 3); missing bytes read as 0.
 *
 * Mode 0, schema: the rest is a schema's XML, then (after a NUL, if any) a
 * filter text.  tdc_pc_schema_parse and tdc_pc_filter_parse either accept
 * or return an error code with a message; never a crash or a read outside
 * the text.  An accepted schema has 1..256 dimensions, each with a known
 * interpretation and its size, offsets adding up to the point size, and
 * X, Y, Z among them; an accepted filter names one of them and 1..32
 * finite values.  Parsing twice gives the same answer.
 *
 * Mode 1, round trip: the harness writes a valid patch the way pgpointcloud
 * lays one out, from the input, with a model encoder of its own:
 *	byte 1: dimensions (3..6, % 4 + 3); then per dimension an
 *	interpretation byte (% 10 + 1) and a compression byte (% 4: none,
 *	run-length, significant bits, zlib; the patch is uncompressed when
 *	byte 2 is odd); byte 2 also picks where X, Y and Z are and whether a
 *	filter on the last dimension is used; then npoints (% 65) and the raw
 *	values, eight bytes each, masked to the dimension's width and, for
 *	long runs, repeated (the high bit of a value's first byte).
 * The schema XML is written for those dimensions (with scales and
 * offsets) and read by tdc_pc_schema_parse, which must accept it; the
 * patch is decoded and every kept point must equal, bit for bit, the
 * value computed here from the raw value as pgpointcloud does (raw *
 * scale + offset), the filter keeping exactly the points it should, or the
 * decoder must say a coordinate is not finite when one kept is.
 *
 * Mode 2, raw bytes: byte 1 picks one of the round-trip schemas (the
 * first form of mode 1), the rest is a patch without its varlena header
 * (the harness adds it into an exactly sized buffer).  The decoder accepts
 * it or returns a code; never a crash or a read outside the value; and
 * tdc_pc_patch_check, which the caller runs before it reserves memory for
 * the header's count, accepts every patch the decoder reads (mode 1: every
 * patch the model writes).  Header
 * point counts above 4096 are skipped (the caller reserves memory for
 * them under tdc_delaunay.max_memory first).
 */
#include <math.h>
#include <stdbool.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <zlib.h>

#include "formats/pcpatch_format.h"

#define MAX_N		64
#define MAX_RAW_N	4096

static void
fail(const char *what)
{
	fprintf(stderr, "fuzz_pcpatch: %s\n", what);
	abort();
}

typedef struct In
{
	const uint8_t *p;
	size_t		n,
				at;
} In;

static uint8_t
next(In *in)
{
	return in->at < in->n ? in->p[in->at++] : 0;
}

static const char *const interp_name[] = {
	"", "int8_t", "uint8_t", "int16_t", "uint16_t", "int32_t", "uint32_t",
	"int64_t", "uint64_t", "double", "float"
};
static const int interp_size[] = {0, 1, 1, 2, 2, 4, 4, 8, 8, 8, 4};

/* ----- mode 0 ----- */
static void
check_schema(const TdcPcSchema *s)
{
	size_t		off = 0;

	if (s->ndims < 1 || s->ndims > TDC_PC_MAX_DIMS)
		fail("accepted a schema without dimensions");
	for (int i = 0; i < s->ndims; i++)
	{
		const TdcPcDim *d = &s->dims[i];

		if (d->interp < TDC_PC_INT8 || d->interp > TDC_PC_FLOAT || d->size != interp_size[d->interp])
			fail("accepted a dimension with a bad interpretation");
		if (d->offset_bytes != off || !isfinite(d->scale) || d->scale == 0 || !isfinite(d->offset))
			fail("accepted a dimension with a bad offset, scale or byte offset");
		if (strnlen(d->name, TDC_PC_NAME_MAX) == 0 || strnlen(d->name, TDC_PC_NAME_MAX) == TDC_PC_NAME_MAX)
			fail("accepted a dimension with a bad name");
		off += (size_t) d->size;
	}
	if (off != s->point_size)
		fail("point size is not the sum of the dimensions");
	if (s->x < 0 || s->y < 0 || s->z < 0 || s->x >= s->ndims || s->y >= s->ndims || s->z >= s->ndims)
		fail("accepted a schema without X, Y, Z");
}

static void
mode_schema(const uint8_t *data, size_t size)
{
	const uint8_t *nul = memchr(data, 0, size);
	size_t		xlen = nul ? (size_t) (nul - data) : size;
	char	   *xml = malloc(xlen + 1);
	char	   *filter = NULL;
	static TdcPcSchema s1,
				s2;
	TdcPcFilter f1,
				f2;
	char		err[256];
	int			rc1,
				rc2;

	memcpy(xml, data, xlen);
	xml[xlen] = '\0';
	/* the exact length, so that ASan sees a read past it */
	rc1 = tdc_pc_schema_parse(xml, xlen, &s1, err, sizeof(err));
	rc2 = tdc_pc_schema_parse(xml, xlen, &s2, err, sizeof(err));
	if (rc1 != rc2 || (rc1 == TDC_PC_OK && memcmp(&s1, &s2, sizeof(s1)) != 0))
		fail("two parses of one schema differ");
	if (rc1 != TDC_PC_OK)
	{
		if (rc1 != TDC_PC_ERR_SCHEMA && rc1 != TDC_PC_ERR_NOXYZ && rc1 != TDC_PC_ERR_COMPRESSION)
			fail("unexpected schema error code");
		free(xml);
		return;
	}
	check_schema(&s1);
	if (nul != NULL)
	{
		size_t		flen = size - xlen - 1;

		filter = malloc(flen + 1);
		memcpy(filter, nul + 1, flen);
		filter[flen] = '\0';
		rc1 = tdc_pc_filter_parse(filter, &s1, &f1, err, sizeof(err));
		rc2 = tdc_pc_filter_parse(filter, &s1, &f2, err, sizeof(err));
		if (rc1 != rc2)
			fail("two parses of one filter differ");
		if (rc1 == TDC_PC_OK && filter[0] != '\0')
		{
			if (f1.dim < 0 || f1.dim >= s1.ndims || f1.nvals < 1 || f1.nvals > TDC_PC_FILTER_MAX)
				fail("accepted a bad filter");
			for (int i = 0; i < f1.nvals; i++)
				if (!isfinite(f1.vals[i]))
					fail("accepted a non-finite filter value");
		}
		else if (rc1 != TDC_PC_OK && rc1 != TDC_PC_ERR_FILTER)
			fail("unexpected filter error code");
		free(filter);
	}
	free(xml);
}

/* ----- mode 1: the model encoder ----- */
typedef struct Model
{
	int			ndims;
	int			interp[6],
				comp[6];
	double		scale[6],
				offset[6];
	int			x,
				y,
				z;
	bool		uncompressed,
				filtering;
} Model;

static void
model_from(In *in, Model *m)
{
	uint8_t		b2;

	m->ndims = next(in) % 4 + 3;
	b2 = next(in);
	m->uncompressed = (b2 & 1) != 0;
	m->filtering = (b2 & 2) != 0;
	m->x = (b2 >> 2) % 3;
	m->y = (m->x + 1 + ((b2 >> 4) & 1)) % 3;
	m->z = 3 - m->x - m->y;
	for (int i = 0; i < m->ndims; i++)
	{
		static const double scales[] = {1, 0.01, 0.001, 0.5, 1e-7, 100};
		static const double offsets[] = {0, 1000, -2.5, 6e6, 0.1, 0};
		uint8_t		s = next(in);

		m->interp[i] = next(in) % 10 + 1;
		m->comp[i] = next(in) % 4;
		m->scale[i] = scales[s % 6];
		m->offset[i] = offsets[(s / 6) % 6];
	}
}

static char *
model_xml(const Model *m)
{
	static char buf[8192];
	size_t		k = 0;
	static const char *const names[] = {"X", "Y", "Z"};

	k += (size_t) snprintf(buf + k, sizeof(buf) - k,
						   "<?xml version=\"1.0\"?>\n<pc:PointCloudSchema xmlns:pc=\"http://pointcloud.org/schemas/PC/1.1\">\n");
	for (int i = 0; i < m->ndims; i++)
	{
		const char *name = i == m->x ? names[0] : i == m->y ? names[1] : i == m->z ? names[2] : NULL;
		char		other[16];

		if (name == NULL)
		{
			snprintf(other, sizeof(other), "D%d", i);
			name = other;
		}
		k += (size_t) snprintf(buf + k, sizeof(buf) - k,
							   "<pc:dimension><pc:position>%d</pc:position><pc:size>%d</pc:size>"
							   "<pc:description>d &lt;%d&gt;</pc:description><pc:name>%s</pc:name>"
							   "<pc:interpretation>%s</pc:interpretation><pc:scale>%.17g</pc:scale>"
							   "<pc:offset>%.17g</pc:offset><!-- c --></pc:dimension>\n",
							   i + 1, interp_size[m->interp[i]], i, name, interp_name[m->interp[i]],
							   m->scale[i], m->offset[i]);
	}
	snprintf(buf + k, sizeof(buf) - k,
			 "<pc:metadata><Metadata name=\"compression\">%s</Metadata></pc:metadata></pc:PointCloudSchema>\n",
			 m->uncompressed ? "none" : "dimensional");
	return buf;
}

/* The raw value as a double, the way pgpointcloud reads it. */
static double
raw_double(uint64_t w, int interp)
{
	switch (interp)
	{
		case 1: return (double) (int8_t) w;
		case 2: return (double) (uint8_t) w;
		case 3: return (double) (int16_t) w;
		case 4: return (double) (uint16_t) w;
		case 5: return (double) (int32_t) w;
		case 6: return (double) (uint32_t) w;
		case 7: return (double) (int64_t) w;
		case 8: return (double) w;
		case 9:
			{
				double		d;

				memcpy(&d, &w, 8);
				return d;
			}
		default:
			{
				float		f;
				uint32_t	u = (uint32_t) w;

				memcpy(&f, &u, 4);
				return (double) f;
			}
	}
}

static double
model_value(const Model *m, int d, uint64_t w)
{
	volatile double v = raw_double(w, m->interp[d]);

	if (m->scale[d] != 1)
		v = v * m->scale[d];
	if (m->offset[d] != 0)
		v = v + m->offset[d];
	return v;
}

static size_t
put_word(uint8_t *out, uint64_t w, int size)
{
	memcpy(out, &w, (size_t) size);	/* little-endian: the low bytes */
	return (size_t) size;
}

/* One dimension's block: compression byte, uint32 size, bytes. */
static size_t
encode_block(uint8_t *out, int comp, const uint64_t *v, int n, int size)
{
	uint8_t    *b = out + 5;
	size_t		len = 0;
	unsigned	bits = (unsigned) size * 8;
	uint32_t	len32;

	if (comp == TDC_PC_DIM_RLE)
	{
		for (int i = 0; i < n;)
		{
			int			run = 1;

			while (i + run < n && run < 255 && v[i + run] == v[i])
				run++;
			b[len++] = (uint8_t) run;
			len += put_word(b + len, v[i], size);
			i += run;
		}
	}
	else if (comp == TDC_PC_DIM_SIGBITS)
	{
		uint64_t	diff = 0,
					common,
					mask;
		unsigned	nbits = 0;
		uint64_t	bitpos = 0;
		size_t		words;

		for (int i = 1; i < n; i++)
			diff |= v[i] ^ v[0];
		while (nbits < bits && (diff >> nbits) != 0)
			nbits++;
		mask = nbits == 64 ? ~(uint64_t) 0 : (((uint64_t) 1 << nbits) - 1);
		common = n > 0 ? v[0] & ~mask : 0;
		len += put_word(b + len, nbits, size);
		len += put_word(b + len, common, size);
		words = ((size_t) nbits * (size_t) n + bits - 1) / bits;
		memset(b + len, 0, words * (size_t) size);
		for (int i = 0; i < n; i++)
			for (unsigned k = 0; k < nbits; k++, bitpos++)
			{
				/* bit k of the value's unique part, most significant first */
				uint64_t	bit = (v[i] >> (nbits - 1 - k)) & 1;
				size_t		word = (size_t) (bitpos / bits);
				unsigned	inword = bits - 1 - (unsigned) (bitpos % bits);
				uint64_t	w = 0;

				memcpy(&w, b + len + word * (size_t) size, (size_t) size);
				w |= bit << inword;
				memcpy(b + len + word * (size_t) size, &w, (size_t) size);
			}
		len += words * (size_t) size;
	}
	else if (comp == TDC_PC_DIM_ZLIB)
	{
		uint8_t		raw[MAX_N * 8];
		uLongf		zlen = compressBound(MAX_N * 8);

		for (int i = 0; i < n; i++)
			put_word(raw + (size_t) i * (size_t) size, v[i], size);
		if (compress2(b, &zlen, raw, (uLong) n * (uLong) size, 6) != Z_OK)
			fail("zlib compress failed");
		len = zlen;
	}
	else
		for (int i = 0; i < n; i++)
			len += put_word(b + len, v[i], size);
	out[0] = (uint8_t) comp;
	len32 = (uint32_t) len;
	memcpy(out + 1, &len32, 4);
	return 5 + len;
}

static void
mode_roundtrip(In *in)
{
	Model		m;
	static TdcPcSchema s;
	TdcPcFilter f;
	const char *xml;
	char		err[256];
	int			n,
				rc;
	uint64_t	raw[6][MAX_N];
	uint8_t    *patch;
	size_t		len,
				cap;
	uint32_t	u;
	double		xy[2 * MAX_N],
				z[2 * MAX_N],
				scratch[2 * MAX_N];
	size_t		kept,
				want = 0;
	bool		want_nonfinite = false;

	model_from(in, &m);
	xml = model_xml(&m);
	if (tdc_pc_schema_parse(xml, strlen(xml), &s, err, sizeof(err)) != TDC_PC_OK)
	{
		fprintf(stderr, "%s\n%s\n", err, xml);
		fail("refused a valid schema");
	}
	check_schema(&s);
	if (s.x != m.x || s.y != m.y || s.z != m.z || s.ndims != m.ndims ||
		s.compression != (m.uncompressed ? TDC_PC_NONE : TDC_PC_DIMENSIONAL))
		fail("the schema read is not the one written");
	for (int d = 0; d < m.ndims; d++)
		if (s.dims[d].scale != m.scale[d] || s.dims[d].offset != m.offset[d] ||
			(int) s.dims[d].interp != m.interp[d])
			fail("a dimension read is not the one written");

	n = next(in) % (MAX_N + 1);
	for (int i = 0; i < n; i++)
		for (int d = 0; d < m.ndims; d++)
		{
			uint64_t	w = 0;
			int			size = interp_size[m.interp[d]];
			uint8_t		first = next(in);

			if (i > 0 && (first & 0x80))
			{
				raw[d][i] = raw[d][i - 1];	/* runs */
				continue;
			}
			w = first;
			for (int k = 1; k < 8; k++)
				w |= (uint64_t) next(in) << (8 * k);
			if (size < 8)
				w &= ((uint64_t) 1 << (8 * size)) - 1;
			raw[d][i] = w;
		}

	memset(&f, 0, sizeof(f));
	f.dim = -1;
	if (m.filtering && n > 0)
	{
		f.dim = m.ndims - 1;
		f.nvals = 1;
		f.vals[0] = model_value(&m, f.dim, raw[f.dim][0]);
	}

	cap = 48 + 3 * s.point_size + (size_t) m.ndims * (5 + 2 * 8 + compressBound(MAX_N * 8)) +
		(size_t) n * s.point_size;
	patch = calloc(1, cap);
	len = 48 + 3 * s.point_size;	/* statistics: zeros, unread */
	if (m.uncompressed)
		for (int i = 0; i < n; i++)
			for (int d = 0; d < m.ndims; d++)
				len += put_word(patch + len, raw[d][i], interp_size[m.interp[d]]);
	else
		for (int d = 0; d < m.ndims; d++)
		{
			int			comp = m.comp[d];

			/* pgpointcloud never uses sigbits on doubles, but may: fine */
			len += encode_block(patch + len, comp, raw[d], n, interp_size[m.interp[d]]);
		}
	u = (uint32_t) len;
	memcpy(patch, &u, 4);
	u = 1;
	memcpy(patch + 4, &u, 4);
	u = m.uncompressed ? TDC_PC_NONE : TDC_PC_DIMENSIONAL;
	memcpy(patch + 8, &u, 4);
	u = (uint32_t) n;
	memcpy(patch + 12, &u, 4);

	if (tdc_pc_patch_check(patch, len, &s, err, sizeof(err)) != TDC_PC_OK)
	{
		fprintf(stderr, "%s\n", err);
		fail("the layout check refused a valid patch");
	}
	rc = tdc_pc_patch_decode(patch, len, &s, &f, xy, z, scratch, &kept, err, sizeof(err));
	for (int i = 0; i < n; i++)
	{
		double		ex = model_value(&m, m.x, raw[m.x][i]),
					ey = model_value(&m, m.y, raw[m.y][i]),
					ez = model_value(&m, m.z, raw[m.z][i]);

		if (f.dim >= 0 && model_value(&m, f.dim, raw[f.dim][i]) != f.vals[0])
			continue;
		if (!isfinite(ex) || !isfinite(ey) || !isfinite(ez))
		{
			want_nonfinite = true;
			break;
		}
		if (rc == TDC_PC_OK &&
			(want >= kept || memcmp(&xy[2 * want], &ex, 8) != 0 ||
			 memcmp(&xy[2 * want + 1], &ey, 8) != 0 || memcmp(&z[want], &ez, 8) != 0))
		{
			fprintf(stderr, "point %d: want %.17g %.17g %.17g", i, ex, ey, ez);
			if (want < kept)
				fprintf(stderr, ", got %.17g %.17g %.17g", xy[2 * want], xy[2 * want + 1], z[want]);
			fprintf(stderr, " (kept %zu)\n", kept);
			fail("a decoded point differs from the model");
		}
		want++;
	}
	if (want_nonfinite ? rc != TDC_PC_ERR_NONFINITE : rc != TDC_PC_OK)
	{
		fprintf(stderr, "rc %d: %s\n", rc, err);
		fail("the decoder's answer is not the model's");
	}
	if (rc == TDC_PC_OK && kept != want)
		fail("the filter kept another number of points");
	free(patch);
}

/* ----- mode 2 ----- */
static void
mode_raw(In *in)
{
	Model		m;
	static TdcPcSchema s;
	TdcPcFilter f;
	const char *xml;
	char		err[256];
	size_t		len,
				kept;
	uint8_t    *patch;
	uint32_t	u;
	TdcPcHeader h;
	double	   *xy,
			   *z;
	void	   *scratch;
	int			rc;

	model_from(in, &m);
	xml = model_xml(&m);
	if (tdc_pc_schema_parse(xml, strlen(xml), &s, err, sizeof(err)) != TDC_PC_OK)
		fail("refused a valid schema");
	memset(&f, 0, sizeof(f));
	f.dim = m.filtering ? m.ndims - 1 : -1;
	f.nvals = 1;
	len = 4 + (in->n - in->at);
	patch = malloc(len);
	u = (uint32_t) len;
	memcpy(patch, &u, 4);
	memcpy(patch + 4, in->p + in->at, in->n - in->at);
	if (tdc_pc_patch_header(patch, len, &h, err, sizeof(err)) != TDC_PC_OK || h.npoints > MAX_RAW_N)
	{
		free(patch);
		return;
	}
	xy = malloc(sizeof(double) * 2 * (h.npoints + 1));
	z = malloc(sizeof(double) * (h.npoints + 1));
	scratch = malloc(tdc_pc_scratch_bytes(&s, h.npoints) + 1);
	rc = tdc_pc_patch_decode(patch, len, &s, &f, xy, z, scratch, &kept, err, sizeof(err));
	if (kept > h.npoints)
		fail("kept more points than the patch has");
	/* the check the caller makes first is never stricter than the decoder */
	if (rc == TDC_PC_OK && tdc_pc_patch_check(patch, len, &s, err, sizeof(err)) != TDC_PC_OK)
	{
		fprintf(stderr, "%s\n", err);
		fail("the layout check refused a patch the decoder reads");
	}
	free(scratch);
	free(z);
	free(xy);
	free(patch);
}

int			LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

int
LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
	In			in = {data, size, 1};

	if (size == 0)
		return 0;
	switch (data[0] % 3)
	{
		case 0:
			mode_schema(data + 1, size - 1);
			break;
		case 1:
			mode_roundtrip(&in);
			break;
		default:
			mode_raw(&in);
	}
	return 0;
}
