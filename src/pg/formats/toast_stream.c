/*
 * toast_stream.c
 *		Reading one geometry argument into a point buffer, a big TOASTed
 *		value a slice at a time: the reader every SQL function that takes a
 *		geometry value uses (tdc_read_geometry).
 *
 * A function gets its geometry argument as a TOAST pointer when the value
 * is stored out of line (any value over about 2 kB unless it compresses
 * below that; a collection of 5 million points is 120 MB, about 90 MB with
 * pglz).  Detoasting it (PG_DETOAST_DATUM) would fetch all its chunks into
 * one buffer, decompress it into a second, and only then let the walker
 * copy the vertices into a third, all without an interrupt check: a cancel
 * arriving then would wait for the whole read.  Instead the stored bytes
 * are fetched a slice at a time (table_relation_fetch_toast_slice, 128
 * chunks, about 250 kB), and handed to the walker (gser_read.c) as they
 * come; compressed bytes, stored out of line or in line, are decompressed a
 * piece at a time into a window that keeps the last 4 kB (pglz) or 64 kB
 * (lz4) of output, which is as far back as either format refers.
 * PostgreSQL offers no incremental decompression (its slice functions
 * decompress from the start each time), so both formats are decoded here,
 * with every length and offset checked against the input left, the output
 * produced and the raw size announced: corrupt data is an ERROR, never a
 * read or write outside the buffers.  Interrupts are checked before every
 * slice and piece (a few ms of work).  Other values (in line and
 * uncompressed, or an expanded or indirect datum, or compressed with a
 * method this code does not know) are detoasted as before.  An ERROR raised
 * while reading carries a CONTEXT line saying how the value was stored.
 * The TIN functions read their samples through tdc_tin_read_sample, which
 * also wants a height at every vertex.
 */
#include "postgres.h"

#include "access/detoast.h"
#include "access/heaptoast.h"
#include "access/table.h"
#include "access/tableam.h"
#include "access/toast_compression.h"
#include "miscadmin.h"
#include "utils/rel.h"

#include "tdc_pg.h"
#include "gser_format.h"

/* Stored bytes fetched at a time: whole TOAST chunks, about 250 kB. */
#define SLICE_BYTES			(128 * TOAST_MAX_CHUNK_SIZE)
/* Decompressed bytes handed to the walker at a time. */
#define PIECE_BYTES			((Size) 256 * 1024)
/* Decompressed bytes kept for back-references: pglz's reach 4095 bytes. */
#define PGLZ_HISTORY		((Size) 4096)
/* lz4's reach 65535 bytes. */
#define LZ4_HISTORY			((Size) 65536)
/* A pglz group: a control byte and 8 items of at most 3 bytes... */
#define PGLZ_GROUP_IN		25
/* ...giving at most 8 matches of 273 bytes. */
#define PGLZ_GROUP_OUT		(8 * 273)

/* Where a lz4 decoder stopped: in which part of which sequence. */
typedef enum Lz4Step
{
	LZ4_TOKEN,					/* at a sequence's token */
	LZ4_LITLEN,					/* adding up literal length bytes */
	LZ4_LITERALS,				/* copying literals */
	LZ4_OFFSET,					/* at the match offset */
	LZ4_MATCHLEN,				/* adding up match length bytes */
	LZ4_MATCH,					/* copying the match */
	LZ4_END						/* the block ended after its last literals */
} Lz4Step;

/*
 * A TOASTed value read front to back.  The stored bytes (compressed or not)
 * come from the TOAST table a slice at a time, or, for a value compressed
 * in line, from memory; compressed bytes are decompressed a piece at a
 * time into a window that keeps the last bytes for back-references.
 */
typedef struct ToastReader
{
	TdcGserSource src;			/* first: what the walker sees */
	const char *fname;
	int			method;			/* -1: not compressed, else a ToastCompressionId */

	/* stored bytes */
	Relation	toastrel;		/* NULL: all in memory, "in" .. "in_end" */
	Oid			valueid;
	int32		stored;			/* bytes stored */
	int32		fetched;		/* bytes fetched so far */
	struct varlena *slice;		/* fetch buffer of SLICE_BYTES */
	char	   *inbuf;			/* compressed: a few bytes kept + one slice */
	const uint8 *in;			/* compressed bytes not decoded yet */
	const uint8 *in_end;

	/* decompressed bytes */
	uint8	   *out;			/* history + PIECE_BYTES */
	Size		history;		/* bytes kept for back-references */
	Size		out_pos;		/* bytes of out in use */
	uint64		produced;		/* bytes decompressed so far */
	uint64		rawsize;		/* bytes the value decompresses to */

	/* lz4: where the current sequence is */
	Lz4Step		step;
	uint64		len;			/* literal or match bytes left */
	uint32		off;			/* match offset */
	int			matchnib;		/* match length field of the token */
} ToastReader;

static void
toast_corrupt(const ToastReader *r)
{
	ereport(ERROR,
			(errcode(ERRCODE_DATA_CORRUPTED),
			 errmsg("%s: compressed %s data is corrupt", r->fname,
					r->method == TOAST_LZ4_COMPRESSION_ID ? "lz4" : "pglz")));
}

/* Fetch the next slice of stored bytes into r->slice; returns its length. */
static Size
fetch_slice(ToastReader *r)
{
	int32		n = Min(r->stored - r->fetched, (int32) SLICE_BYTES);

	CHECK_FOR_INTERRUPTS();
	table_relation_fetch_toast_slice(r->toastrel, r->valueid, r->stored,
									 r->fetched, n, r->slice);
	r->fetched += n;
	return (Size) n;
}

/*
 * Make at least "want" compressed bytes available at r->in, fetching a
 * slice when fewer remain; returns false when fewer than that are left in
 * the whole value.  The bytes not decoded yet (fewer than "want") move to
 * the front of the input buffer, and the slice goes after them.
 */
static bool
toast_input(ToastReader *r, Size want)
{
	Size		keep = r->in_end - r->in;
	Size		n;

	if (keep >= want)
		return true;
	if (r->toastrel == NULL || r->fetched == r->stored)
		return false;
	memmove(r->inbuf, r->in, keep);
	n = fetch_slice(r);
	memcpy(r->inbuf + keep, VARDATA(r->slice), n);
	r->in = (const uint8 *) r->inbuf;
	r->in_end = r->in + keep + n;
	return keep + n >= want;
}

/*
 * Copy a match of len bytes from off bytes back.  They may overlap: the
 * match then repeats the last off bytes, and each copy doubles what can be
 * copied in one go (the distance from the source grows, the source stays).
 */
static inline void
copy_match(uint8 *dst, Size off, Size len)
{
	const uint8 *src = dst - off;

	while (len > 0)
	{
		Size		k = Min(len, (Size) (dst - src));

		memcpy(dst, src, k);
		dst += k;
		len -= k;
	}
}

/*
 * Decompress pglz groups into out from r->out_pos up to "limit".  The format
 * (common/pg_lzcompress.c): a control byte, then 8 items, each a literal
 * byte (bit clear, low bit first) or a match (bit set): 2 bytes, length - 3
 * in the low nibble of the first, a 12-bit offset in its high nibble and the
 * second, and when the length field is 15 a third byte adds to the length.
 * The value's stream ends with its input: then exactly rawsize bytes must
 * have been produced.
 */
static void
pglz_piece(ToastReader *r, Size limit)
{
	uint8	   *out = r->out;
	Size		pos = r->out_pos;
	uint64		base = r->produced - pos;	/* produced = base + pos */

	while (limit - pos >= PGLZ_GROUP_OUT)
	{
		const uint8 *in;
		const uint8 *end;
		uint8		ctrl;

		if (!toast_input(r, PGLZ_GROUP_IN) && r->in == r->in_end)
			break;				/* all input decoded */
		in = r->in;
		end = r->in_end;
		ctrl = *in++;
		for (int bit = 0; bit < 8 && in < end; bit++, ctrl >>= 1)
		{
			if (ctrl & 1)
			{
				Size		len;
				Size		off;

				if (end - in < 2)
					toast_corrupt(r);
				len = (in[0] & 0x0f) + 3;
				off = ((Size) (in[0] & 0xf0) << 4) | in[1];
				in += 2;
				if (len == 18)
				{
					if (in == end)
						toast_corrupt(r);
					len += *in++;
				}
				if (off == 0 || off > base + pos ||
					len > r->rawsize - (base + pos))
					toast_corrupt(r);
				copy_match(out + pos, off, len);
				pos += len;
			}
			else
			{
				if (base + pos >= r->rawsize)
					toast_corrupt(r);
				out[pos++] = *in++;
			}
		}
		r->in = in;
	}
	r->produced = base + pos;
	r->out_pos = pos;
}

/*
 * Decompress lz4 into out from r->out_pos up to "limit", resuming wherever
 * the previous call stopped.  The format (one lz4 block): sequences of a
 * token (literal length in the high nibble, match length - 4 in the low
 * one, 15 meaning that bytes follow, each added, until one is not 255), the
 * literals, a 2-byte little-endian offset and the match; the last sequence
 * stops after its literals, at the end of the input.
 */
static void
lz4_piece(ToastReader *r, Size limit)
{
	uint8	   *out = r->out;
	Size		pos = r->out_pos;
	uint64		base = r->produced - pos;
	Size		k;
	uint8		b;

	while (pos < limit)
	{
		switch (r->step)
		{
			case LZ4_TOKEN:
				if (!toast_input(r, 1))
					toast_corrupt(r);
				b = *r->in++;
				r->len = b >> 4;
				r->matchnib = b & 0x0f;
				r->step = r->len == 15 ? LZ4_LITLEN : LZ4_LITERALS;
				break;

			case LZ4_LITLEN:
			case LZ4_MATCHLEN:
				if (!toast_input(r, 1))
					toast_corrupt(r);
				b = *r->in++;
				r->len += b;
				if (r->len > r->rawsize)
					toast_corrupt(r);
				if (b != 255)
					r->step = r->step == LZ4_LITLEN ? LZ4_LITERALS : LZ4_MATCH;
				break;

			case LZ4_LITERALS:
				if (r->len > r->rawsize - (base + pos))
					toast_corrupt(r);
				if (r->len > 0 && !toast_input(r, 1))
					toast_corrupt(r);
				k = Min(Min(r->len, (uint64) (limit - pos)),
						(uint64) (r->in_end - r->in));
				memcpy(out + pos, r->in, k);
				pos += k;
				r->in += k;
				r->len -= k;
				if (r->len == 0)
				{
					/* the last sequence: no offset follows */
					if (!toast_input(r, 1))
					{
						r->step = LZ4_END;
						goto done;
					}
					r->step = LZ4_OFFSET;
				}
				break;

			case LZ4_OFFSET:
				if (!toast_input(r, 2))
					toast_corrupt(r);
				r->off = r->in[0] | ((uint32) r->in[1] << 8);
				r->in += 2;
				if (r->off == 0 || r->off > base + pos)
					toast_corrupt(r);
				r->len = r->matchnib + 4;
				r->step = r->matchnib == 15 ? LZ4_MATCHLEN : LZ4_MATCH;
				break;

			case LZ4_MATCH:
				if (r->len > r->rawsize - (base + pos))
					toast_corrupt(r);
				k = Min(r->len, (uint64) (limit - pos));
				copy_match(out + pos, r->off, k);
				pos += k;
				r->len -= k;
				if (r->len == 0)
					r->step = LZ4_TOKEN;
				break;

			case LZ4_END:
				goto done;
		}
	}
done:
	r->produced = base + pos;
	r->out_pos = pos;
}

/* TdcGserSource.next of an uncompressed value: its next slice. */
static bool
plain_next(TdcGserSource *src, const char **data, Size *len)
{
	ToastReader *r = (ToastReader *) src;

	if (r->fetched == r->stored)
		return false;
	*len = fetch_slice(r);
	*data = VARDATA(r->slice);
	return true;
}

/* TdcGserSource.next of a compressed value: the next piece decompressed. */
static bool
compressed_next(TdcGserSource *src, const char **data, Size *len)
{
	ToastReader *r = (ToastReader *) src;
	Size		start;

	if (r->produced == r->rawsize)
		return false;
	CHECK_FOR_INTERRUPTS();
	/* keep the history, drop what is older: the walker is done with it */
	if (r->out_pos > r->history)
	{
		memmove(r->out, r->out + r->out_pos - r->history, r->history);
		r->out_pos = r->history;
	}
	start = r->out_pos;
	if (r->method == TOAST_PGLZ_COMPRESSION_ID)
		pglz_piece(r, start + PIECE_BYTES);
	else
		lz4_piece(r, start + PIECE_BYTES);
	if (r->out_pos == start)
		toast_corrupt(r);		/* the input ended early */
	*data = (const char *) r->out + start;
	*len = r->out_pos - start;
	return true;
}

/* CONTEXT of an ERROR (a cancel included) raised while reading a value. */
static void
toast_read_context(void *arg)
{
	const ToastReader *r = arg;
	const char *method = r->method == TOAST_LZ4_COMPRESSION_ID ? "lz4" : "pglz";

	if (r->toastrel != NULL && r->method == -1)
		errcontext("reading a geometry value of %llu bytes stored out of line",
				   (unsigned long long) r->rawsize);
	else if (r->toastrel != NULL)
		errcontext("reading a geometry value of %llu bytes stored out of line, compressed with %s",
				   (unsigned long long) r->rawsize, method);
	else
		errcontext("reading a geometry value of %llu bytes compressed with %s",
				   (unsigned long long) r->rawsize, method);
}

/*
 * Read a value stored out of line or compressed into buf, a slice at a time
 * (see the top of this file); returns false, having read nothing, for any
 * other value, which tdc_read_geometry detoasts as usual.
 */
static bool
read_toasted_value(TdcPointBuf *buf, struct varlena *attr, const char *fname,
				   bool *stroked)
{
	ToastReader r;
	ErrorContextCallback errcb;

	/* the common case, a small value in line: nothing to do here */
	if (!VARATT_IS_EXTERNAL_ONDISK(attr) && !VARATT_IS_COMPRESSED(attr))
		return false;
	memset(&r, 0, sizeof(r));
	r.fname = fname;
	if (VARATT_IS_EXTERNAL_ONDISK(attr))
	{
		struct varatt_external ptr;

		VARATT_EXTERNAL_GET_POINTER(ptr, attr);
		r.stored = VARATT_EXTERNAL_GET_EXTSIZE(ptr);
		r.rawsize = ptr.va_rawsize - VARHDRSZ;
		r.method = VARATT_EXTERNAL_IS_COMPRESSED(ptr) ?
			(int) VARATT_EXTERNAL_GET_COMPRESS_METHOD(ptr) : -1;
		r.valueid = ptr.va_valueid;
		if (r.method != -1 && r.method != TOAST_PGLZ_COMPRESSION_ID &&
			r.method != TOAST_LZ4_COMPRESSION_ID)
			return false;
		r.toastrel = table_open(ptr.va_toastrelid, AccessShareLock);
		r.slice = palloc(VARHDRSZ + Min(r.stored, (int32) SLICE_BYTES));
	}
	else if (VARATT_IS_COMPRESSED(attr))
	{
		r.stored = VARSIZE(attr) - VARHDRSZ;
		r.rawsize = VARDATA_COMPRESSED_GET_EXTSIZE(attr);
		r.method = (int) VARDATA_COMPRESSED_GET_COMPRESS_METHOD(attr);
		if (r.method != TOAST_PGLZ_COMPRESSION_ID &&
			r.method != TOAST_LZ4_COMPRESSION_ID)
			return false;
		r.fetched = r.stored;
		r.in = (const uint8 *) VARDATA(attr);
		r.in_end = r.in + r.stored;
	}
	else
		return false;

	/* from here on an ERROR, a cancel included, says what was being read */
	errcb.callback = toast_read_context;
	errcb.arg = &r;
	errcb.previous = error_context_stack;
	error_context_stack = &errcb;

	r.src.size = r.rawsize;
	r.src.whole = PointerGetDatum(attr);
	if (r.method == -1)
		r.src.next = plain_next;
	else
	{
		/*
		 * The stored bytes start with the 4-byte header of the compressed
		 * value: its raw size (checked against the pointer's) and method.
		 */
		uint32		tcinfo;

		r.src.next = compressed_next;
		if (r.toastrel != NULL)
		{
			r.inbuf = palloc(PGLZ_GROUP_IN + Min(r.stored, (int32) SLICE_BYTES));
			r.in = r.in_end = (const uint8 *) r.inbuf;
		}
		if (!toast_input(&r, sizeof(tcinfo)))
			toast_corrupt(&r);
		memcpy(&tcinfo, r.in, sizeof(tcinfo));
		r.in += sizeof(tcinfo);
		if ((tcinfo & VARLENA_EXTSIZE_MASK) != r.rawsize)
			toast_corrupt(&r);
		r.history = r.method == TOAST_LZ4_COMPRESSION_ID ? LZ4_HISTORY : PGLZ_HISTORY;
		r.out = palloc(Min(r.history + PIECE_BYTES, r.rawsize));
		r.step = LZ4_TOKEN;
	}

	/*
	 * A value with arcs, for a buffer that strokes them, is read whole here
	 * first (so checked) and read again stroked from r.src.whole.
	 */
	*stroked = tdc_gser_append_source(buf, &r.src, fname);

	/* every stored byte must have been used, and no more */
	if (r.method != -1 &&
		(r.produced != r.rawsize || r.in != r.in_end || r.fetched != r.stored ||
		 (r.method == TOAST_LZ4_COMPRESSION_ID && r.step != LZ4_END)))
	{
		/* a lz4 block may end in an empty last sequence: decode it */
		if (r.method == TOAST_LZ4_COMPRESSION_ID && r.produced == r.rawsize &&
			r.step != LZ4_END)
			lz4_piece(&r, r.out_pos + 1);
		if (r.step != LZ4_END || r.in != r.in_end || r.fetched != r.stored)
			toast_corrupt(&r);
	}
	error_context_stack = errcb.previous;

	if (r.toastrel != NULL)
		table_close(r.toastrel, AccessShareLock);
	if (r.slice)
		pfree(r.slice);
	if (r.inbuf)
		pfree(r.inbuf);
	if (r.out)
		pfree(r.out);
	return true;
}

/*
 * Append the vertices of the geometry value "d" (a function's argument,
 * possibly a TOAST pointer) to buf: a value stored out of line or
 * compressed a slice at a time, any other as it is.  Returns what
 * tdc_gser_append returns: true when the value had arcs and was read
 * stroked.
 */
bool
tdc_read_geometry(TdcPointBuf *buf, Datum d, const char *fname)
{
	struct varlena *attr = (struct varlena *) DatumGetPointer(d);
	struct varlena *geom;
	bool		stroked;

	if (read_toasted_value(buf, attr, fname, &stroked))
		return stroked;
	geom = PG_DETOAST_DATUM_PACKED(d);
	stroked = tdc_gser_append(buf, geom, fname);
	if (geom != attr)
		pfree(geom);
	return stroked;
}

/*
 * A sample of the TIN functions: a geometry whose vertices need a height,
 * so a value without Z is an error naming it, by its row (the aggregate's
 * count of the non-NULL rows it read, per parallel worker) and its first
 * vertex.  Its flags are read from the first bytes of the value (a slice
 * of a TOASTed one), so no value is read twice; an EMPTY sample has no
 * vertex to lack a height and is skipped, whatever its dimensions.  M is
 * dropped.
 */
void
tdc_tin_read_sample(TdcPointBuf *buf, Datum d, int64 row, const char *fname)
{
	struct varlena *head = PG_DETOAST_DATUM_SLICE(d, 0, G_HEADER);
	bool		hasz = VARSIZE_ANY_EXHDR(head) < G_HEADER ||
		(((const unsigned char *) VARDATA_ANY(head))[3] & GF_Z) != 0;

	if ((Pointer) head != DatumGetPointer(d))
		pfree(head);
	if (!hasz)
	{
		TdcPointBuf tmp;

		/* its vertices, to tell EMPTY apart and to name the first */
		tdc_pointbuf_init(&tmp, CurrentMemoryContext);
		tmp.curves = TDC_CURVES_VERTICES;
		(void) tdc_read_geometry(&tmp, d, fname);
		if (tmp.n == 0)
			return;
		ereport(ERROR,
				(errcode(ERRCODE_INVALID_PARAMETER_VALUE),
				 errmsg("%s: sample row %lld has no Z coordinate", fname, (long long) row),
				 errdetail("The row's first vertex is (%.17g %.17g); rows are counted from 1 among the "
						   "non-NULL rows each aggregate (each parallel worker) reads.",
						   tmp.xy[0], tmp.xy[1]),
				 errhint("Every sample needs a height: make the samples XYZ, with ST_MakePoint(x, y, z) or "
						 "ST_Force3DZ(geom, z).")));
	}
	(void) tdc_read_geometry(buf, d, fname);
}
