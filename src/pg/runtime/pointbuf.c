/*
 * pointbuf.c
 *		The point buffer: the vertices collected from geometry values, in
 *		the layout the core takes (x,y interleaved), plus Z.
 *
 * One buffer collects the input of a triangulation, whether from one value
 * (ST_TDCDelaunayTriangles), from the rows of an aggregate, or from the rows
 * of a query (ST_TDCDelaunayDump).  The first input fixes the SRID and the
 * dimensions and later ones must agree.  The buffer grows by doubling, with
 * every growth checked against tdc_delaunay.max_memory before it happens,
 * so an input over the limit is refused with the limit's ERROR and never
 * half-allocated.
 *
 * Some owners keep arrays that grow with the vertices: a Dump's row ids, a
 * tile's owners and source positions, the segments of a constrained
 * triangulation.  They can outweigh the coordinates (a tile's are 24 bytes
 * a vertex against 16), so they count as part of the buffer: the owner
 * grows them through tdc_pointbuf_side_grow, whose check is the same as for
 * the coordinates, and tdc_pointbuf_bytes, which every later check of the
 * triangulation starts from, includes them.
 */
#include "postgres.h"

#include <sys/mman.h>

#include "utils/memutils.h"

#include "tdc_pg.h"

/*
 * Big coordinate arrays are mapped directly, not palloc'd: a big aggregate
 * grows them to hundreds of megabytes, and once freed, malloc keeps blocks
 * below its (self-raising) mmap threshold in the backend's heap, so a
 * session's memory would depend on the sizes of the inputs it saw before.
 * Mappings grow with mremap, which moves pages instead of copying bytes,
 * and go back to the system when the buffer's context is reset or deleted.
 * The release callback is registered before any triangulation job's (whose
 * workers read the array) and so runs after it.
 *
 * Arrays below POINTMAP_MIN_BYTES are palloc'd in the buffer's context
 * instead: one call per row on a small geometry would otherwise pay a map,
 * its page faults and an unmap (with a TLB flush on every CPU the process
 * ran threads on) for a few dozen bytes of coordinates.  The map record and
 * its release callback are only created when an array first reaches that
 * size: a buffer of palloc'd arrays has nothing to release, and two pallocs
 * and a callback per row were a visible part of a call on five points.
 */
#define POINTMAP_MIN_BYTES	((Size) 256 * 1024)

static void
pointmap_release(void *arg)
{
	TdcPointMap *map = (TdcPointMap *) arg;

	/* palloc'd arrays go with the context */
	if (map->xy != NULL && map->xy_bytes >= POINTMAP_MIN_BYTES)
		munmap(map->xy, map->xy_bytes);
	if (map->z != NULL && map->z_bytes >= POINTMAP_MIN_BYTES)
		munmap(map->z, map->z_bytes);
	map->xy = map->z = NULL;
}

static double *
pointmap_grow(MemoryContext cxt, double **ptr, Size *bytes, Size want)
{
	void	   *p;

	if (want < POINTMAP_MIN_BYTES)
		p = *ptr == NULL ? MemoryContextAlloc(cxt, want) : repalloc(*ptr, want);
	else if (*ptr != NULL && *bytes >= POINTMAP_MIN_BYTES)
		p = mremap(*ptr, *bytes, want, MREMAP_MAYMOVE);
	else
	{
		p = mmap(NULL, want, PROT_READ | PROT_WRITE, MAP_PRIVATE | MAP_ANONYMOUS, -1, 0);
		if (p != MAP_FAILED && *ptr != NULL)
		{
			memcpy(p, *ptr, *bytes);
			pfree(*ptr);
		}
	}
	if (p == MAP_FAILED)
		ereport(ERROR,
				(errcode(ERRCODE_OUT_OF_MEMORY),
				 errmsg("out of memory"),
				 errdetail("Failed on request of size %zu for input vertices.", want)));
	*ptr = p;
	*bytes = want;
	return p;
}

void
tdc_pointbuf_init(TdcPointBuf *buf, MemoryContext cxt)
{
	memset(buf, 0, sizeof(*buf));
	buf->cxt = cxt;
}

static uint64
pointbuf_bytes_for(uint64 cap, bool hasz)
{
	return cap * (hasz ? 3 : 2) * sizeof(double);
}

uint64
tdc_pointbuf_bytes(const TdcPointBuf *buf)
{
	return pointbuf_bytes_for(buf->cap, buf->hasz) + buf->side_bytes;
}

/*
 * The bytes an empty buffer holds once n vertices were appended (the
 * doubling of tdc_pointbuf_reserve; where the limit cuts the doubling
 * short it holds less), for a caller deciding beforehand whether a
 * collection and its run will fit.
 */
uint64
tdc_pointbuf_bytes_after(uint64 n, bool hasz)
{
	uint64		cap = 16;

	while (cap < n)
		cap *= 2;
	return pointbuf_bytes_for(Max(Min(cap, TDC_MAX_POINTS), n), hasz);
}

/*
 * The owner's arrays beside the vertices ("what") grow from old_bytes to
 * new_bytes: refused with the limit's ERROR before they do, if the buffer
 * would then pass tdc_delaunay.max_memory.
 */
void
tdc_pointbuf_side_grow(TdcPointBuf *buf, uint64 old_bytes, uint64 new_bytes,
					   const char *what, const char *fname)
{
	uint64		limit = tdc_max_memory_bytes();
	uint64		total = tdc_pointbuf_bytes(buf) - old_bytes + new_bytes;

	Assert(old_bytes <= buf->side_bytes);
	if (limit > 0 && total > limit)
		tdc_report_memory_limit(fname,
								psprintf("the input of %llu vertices with %s",
										 (unsigned long long) buf->n, what),
								total, 0);
	buf->side_bytes = buf->side_bytes - old_bytes + new_bytes;
}

/* Make room for "extra" more vertices, honouring tdc_delaunay.max_memory. */
void
tdc_pointbuf_reserve(TdcPointBuf *buf, uint64 extra, const char *fname)
{
	uint64		need = buf->n + extra;
	uint64		newcap;
	uint64		limit;

	if (need <= buf->cap)
		return;
	limit = tdc_max_memory_bytes();
	if (need > TDC_MAX_POINTS)
		ereport(ERROR,
				(errcode(ERRCODE_PROGRAM_LIMIT_EXCEEDED),
				 errmsg("%s: too many input vertices (more than %zu)",
						fname, (size_t) TDC_MAX_POINTS)));

	newcap = Max(buf->cap, 16);
	while (newcap < need)
		newcap *= 2;
	if (newcap > TDC_MAX_POINTS)
		newcap = TDC_MAX_POINTS;
	/* don't let doubling alone trip the memory limit */
	if (limit > 0 && pointbuf_bytes_for(newcap, buf->hasz) + buf->side_bytes > limit)
		newcap = Max(need, (limit - Min(limit, buf->side_bytes)) /
					 ((buf->hasz ? 3 : 2) * sizeof(double)));
	if (limit > 0 && pointbuf_bytes_for(newcap, buf->hasz) + buf->side_bytes > limit)
		tdc_report_memory_limit(fname,
								psprintf("the input of %llu vertices",
										 (unsigned long long) need),
								pointbuf_bytes_for(need, buf->hasz) + buf->side_bytes, 0);

	if (buf->map == NULL)
	{
		Size		xy_bytes = (Size) buf->cap * 2 * sizeof(double);
		MemoryContextCallback *cb;

		/* z is half the size of xy: if xy stays small, so does z */
		if ((Size) newcap * 2 * sizeof(double) < POINTMAP_MIN_BYTES)
		{
			buf->xy = buf->xy == NULL ?
				MemoryContextAlloc(buf->cxt, (Size) newcap * 2 * sizeof(double)) :
				repalloc(buf->xy, (Size) newcap * 2 * sizeof(double));
			if (buf->hasz)
				buf->z = buf->z == NULL ?
					MemoryContextAlloc(buf->cxt, (Size) newcap * sizeof(double)) :
					repalloc(buf->z, (Size) newcap * sizeof(double));
			buf->cap = newcap;
			return;
		}
		/* the arrays palloc'd so far move to mappings from here on */
		buf->map = MemoryContextAllocZero(buf->cxt, sizeof(TdcPointMap));
		buf->map->xy = buf->xy;
		buf->map->xy_bytes = buf->xy != NULL ? xy_bytes : 0;
		buf->map->z = buf->z;
		buf->map->z_bytes = buf->z != NULL ? xy_bytes / 2 : 0;
		cb = MemoryContextAllocZero(buf->cxt, sizeof(MemoryContextCallback));
		cb->func = pointmap_release;
		cb->arg = buf->map;
		MemoryContextRegisterResetCallback(buf->cxt, cb);
	}
	buf->xy = pointmap_grow(buf->cxt, &buf->map->xy, &buf->map->xy_bytes,
							(Size) newcap * 2 * sizeof(double));
	if (buf->hasz)
		buf->z = pointmap_grow(buf->cxt, &buf->map->z, &buf->map->z_bytes,
							   (Size) newcap * sizeof(double));
	buf->cap = newcap;
}

/* The first input fixes SRID and dimensions; later ones must agree. */
void
tdc_pointbuf_check_meta(TdcPointBuf *buf, int32 srid, bool hasz,
						const char *fname)
{
	if (!buf->have_first)
	{
		Assert(buf->n == 0 && buf->xy == NULL);
		buf->have_first = true;
		buf->srid = srid;
		buf->hasz = hasz;
		return;
	}
	if (buf->srid != srid)
		ereport(ERROR,
				(errcode(ERRCODE_INVALID_PARAMETER_VALUE),
				 errmsg("%s: geometries have mixed SRIDs %d and %d",
						fname, Min(buf->srid, srid), Max(buf->srid, srid)),
				 errhint("Transform them to one SRID with ST_Transform or set it with ST_SetSRID.")));
	if (buf->hasz != hasz)
		ereport(ERROR,
				(errcode(ERRCODE_INVALID_PARAMETER_VALUE),
				 errmsg("%s: geometries have mixed dimensions (XY and XYZ)",
						fname),
				 errhint("Use ST_Force2D or ST_Force3DZ to give all inputs the same dimensions.")));
}

/* Append all vertices of src (another aggregate state) to dst. */
void
tdc_pointbuf_append_buf(TdcPointBuf *dst, const TdcPointBuf *src,
						const char *fname)
{
	if (!src->have_first)
		return;
	tdc_pointbuf_check_meta(dst, src->srid, src->hasz, fname);
	if (src->n == 0)
		return;
	tdc_pointbuf_reserve(dst, src->n, fname);
	memcpy(dst->xy + 2 * dst->n, src->xy, (Size) src->n * 2 * sizeof(double));
	if (dst->hasz)
		memcpy(dst->z + dst->n, src->z, (Size) src->n * sizeof(double));
	dst->n += src->n;
}

