/*
 * tile_values.c
 *		The values of tdc_delaunay_tiled's tile column, of any type with an
 *		ordering, as dense labels: each distinct value numbered as it is
 *		first seen while the source is read, then ranked 1.. in the type's
 *		order.
 *
 * The tiled run labels each triangle by the tile that owns its smallest
 * vertex, a vertex being owned by the least tile among its copies (as the
 * rounds of SQL statements on Citus decide it, tile_final.c's stars).  The
 * core compares labels, not values: it carries an int64 per vertex through
 * its files and hands each vertex the least of its copies' labels
 * (tdc_least_labels).  So the labels must be in the values' order, and
 * that order is only known once every value has been seen.  While the
 * source is read, a value gets the number of its first sighting (a hash of
 * its bytes; the last value is kept, so a run of rows in one tile costs
 * one comparison of bytes each); afterwards the distinct values are sorted
 * with the type's default btree ordering in the type's collation (what a
 * column of that type, the target's, sorts by) and ranked, equal values
 * sharing a rank.  Two byte patterns that the ordering calls equal (0 and
 * -0 of a float, say) are two numbers but one rank, and the target gets
 * the first of them seen.
 *
 * Memory: the values, the hash table and the rank arrays live in the
 * caller's context and are counted in tv->bytes as they grow (an estimate
 * per value: its bytes plus TV_VALUE_BYTES), which the caller adds to what
 * it checks against tdc_delaunay.max_memory.
 */
#include "postgres.h"

#include "common/hashfn.h"
#include "utils/builtins.h"
#include "utils/datum.h"
#include "utils/lsyscache.h"
#include "utils/sortsupport.h"
#include "utils/typcache.h"

#include "tdc_pg.h"

/*
 * What a distinct value costs beside its bytes: its hash entry (twice, for
 * the table's slack), its slot in the values array (twice, for doubling),
 * the allocation's header, the rank arrays (order, rank, by rank) and its
 * count of rows written.
 */
#define TV_VALUE_BYTES	(2 * 24 + 2 * sizeof(Datum) + 16 + 4 + 4 + sizeof(Datum) + sizeof(int64))

typedef struct TvEntry
{
	Datum		key;			/* the value, in the values' context */
	uint32		index;			/* its number, in order of first sighting */
	uint32		hash;
	char		status;
} TvEntry;

/* The bytes of a value (varlena detoasted by the caller) and their length. */
static inline const void *
tv_bytes(const TdcTileValues *tv, Datum d, Size *len)
{
	if (tv->typbyval)
	{
		*len = sizeof(Datum);
		return NULL;
	}
	if (tv->typlen > 0)
	{
		*len = tv->typlen;
		return DatumGetPointer(d);
	}
	if (tv->typlen == -1)
	{
		*len = VARSIZE_ANY_EXHDR(DatumGetPointer(d));
		return VARDATA_ANY(DatumGetPointer(d));
	}
	*len = strlen(DatumGetCString(d));
	return DatumGetPointer(d);
}

static inline uint32
tv_hash(const TdcTileValues *tv, Datum d)
{
	Size		len;
	const void *p = tv_bytes(tv, d, &len);

	if (p == NULL)
		return hash_bytes((const unsigned char *) &d, (int) sizeof(d));
	return hash_bytes((const unsigned char *) p, (int) len);
}

static inline bool
tv_same(const TdcTileValues *tv, Datum a, Datum b)
{
	Size		la,
				lb;
	const void *pa = tv_bytes(tv, a, &la),
			   *pb = tv_bytes(tv, b, &lb);

	if (pa == NULL)
		return a == b;
	return la == lb && memcmp(pa, pb, la) == 0;
}

#define SH_PREFIX		tvhash
#define SH_ELEMENT_TYPE	TvEntry
#define SH_KEY_TYPE		Datum
#define SH_KEY			key
#define SH_HASH_KEY(tb, k)	tv_hash((const TdcTileValues *) (tb)->private_data, k)
#define SH_EQUAL(tb, a, b)	tv_same((const TdcTileValues *) (tb)->private_data, a, b)
#define SH_STORE_HASH
#define SH_GET_HASH(tb, a)	((a)->hash)
#define SH_SCOPE		static inline
#define SH_DECLARE
#define SH_DEFINE
#include "lib/simplehash.h"

/*
 * Ready tv for values of type typid (the tile column's, typmod only
 * kept), in cxt.  A type without a default btree ordering is refused,
 * naming the column.
 */
void
tdc_tile_values_init(TdcTileValues *tv, MemoryContext cxt, Oid typid, int32 typmod,
					 const char *column, const char *fname)
{
	TypeCacheEntry *tc = lookup_type_cache(typid, TYPECACHE_LT_OPR);

	if (!OidIsValid(tc->lt_opr))
		ereport(ERROR,
				(errcode(ERRCODE_UNDEFINED_FUNCTION),
				 errmsg("%s: tile column \"%s\" is of type %s, which has no ordering", fname, column,
						format_type_be(typid)),
				 errhint("A tile column needs a type with a default btree operator class.")));
	memset(tv, 0, sizeof(*tv));
	tv->cxt = cxt;
	tv->typid = typid;
	tv->typmod = typmod;
	tv->lt_opr = tc->lt_opr;
	tv->collation = get_typcollation(typid);
	get_typlenbyval(typid, &tv->typlen, &tv->typbyval);
	tv->hash = tvhash_create(cxt, 16, tv);
	tv->cap = 16;
	tv->values = MemoryContextAlloc(cxt, tv->cap * sizeof(Datum));
	tv->bytes = tv->cap * sizeof(Datum) + 16 * 2 * sizeof(TvEntry);
}

/*
 * The number of value d (not NULL), given in order of first sighting from
 * 0: a new value is copied into tv's context.
 */
uint32
tdc_tile_values_number(TdcTileValues *tv, Datum d)
{
	TvEntry    *e;
	bool		found;
	Datum		copy;
	Size		len;
	Pointer		given = DatumGetPointer(d);

	/* (a compressed or out-of-line value is expanded here, and freed below) */
	if (tv->typlen == -1)
		d = PointerGetDatum(PG_DETOAST_DATUM_PACKED(d));
	if (tv->have_last && tv_same(tv, d, tv->last))
	{
		if (tv->typlen == -1 && DatumGetPointer(d) != given)
			pfree(DatumGetPointer(d));
		return tv->last_number;
	}
	e = tvhash_insert(tv->hash, d, &found);
	if (!found)
	{
		MemoryContext old;

		if (tv->n == PG_UINT32_MAX)
			ereport(ERROR,
					(errcode(ERRCODE_PROGRAM_LIMIT_EXCEEDED),
					 errmsg("tdc_delaunay_tiled: more than %u distinct tile values", PG_UINT32_MAX)));
		old = MemoryContextSwitchTo(tv->cxt);
		copy = datumCopy(d, tv->typbyval, tv->typlen);
		if (tv->n == tv->cap)
		{
			tv->cap *= 2;
			tv->values = repalloc_huge(tv->values, tv->cap * sizeof(Datum));
		}
		MemoryContextSwitchTo(old);
		/* the entry's key must outlive the row: it becomes the copy */
		e->key = copy;
		e->index = tv->n;
		tv->values[tv->n++] = copy;
		(void) tv_bytes(tv, copy, &len);
		tv->bytes += TV_VALUE_BYTES + (tv->typbyval ? 0 : len + VARHDRSZ);
	}
	if (tv->typlen == -1 && DatumGetPointer(d) != given)
		pfree(DatumGetPointer(d));
	tv->last = e->key;
	tv->last_number = e->index;
	tv->have_last = true;
	return e->index;
}

/* qsort_arg's comparison of two value numbers: by the type's order, then first sighting. */
static int
tv_order_cmp(const void *a, const void *b, void *arg)
{
	const TdcTileValues *tv = (const TdcTileValues *) arg;
	uint32		i = *(const uint32 *) a,
				j = *(const uint32 *) b;
	int			c = ApplySortComparator(tv->values[i], false, tv->values[j], false, tv->sort);

	if (c != 0)
		return c;
	return i < j ? -1 : i > j;
}

/*
 * Rank the values seen: tv->rank[number] is each one's rank from 1 in the
 * type's order (equal values share one), tv->by_rank[rank] the first value
 * of that rank seen, tv->nranks the ranks, tv->count[rank] zero (the
 * caller's count of rows).  More ranks than an id has room
 * for (2^31 - 1: ids are rank * 2^32 + k) is an ERROR.
 */
void
tdc_tile_values_rank(TdcTileValues *tv, const char *fname)
{
	MemoryContext old = MemoryContextSwitchTo(tv->cxt);
	uint32	   *order = MemoryContextAllocHuge(tv->cxt, Max(tv->n, 1) * sizeof(uint32));

	tv->sort = palloc0(sizeof(SortSupportData));
	tv->sort->ssup_cxt = tv->cxt;
	tv->sort->ssup_collation = tv->collation;
	PrepareSortSupportFromOrderingOp(tv->lt_opr, tv->sort);
	for (uint32 i = 0; i < tv->n; i++)
		order[i] = i;
	qsort_arg(order, tv->n, sizeof(uint32), tv_order_cmp, tv);
	tv->rank = MemoryContextAllocHuge(tv->cxt, Max(tv->n, 1) * sizeof(uint32));
	tv->by_rank = MemoryContextAllocHuge(tv->cxt, (tv->n + 1) * sizeof(Datum));
	tv->count = MemoryContextAllocHuge(tv->cxt, (tv->n + 1) * sizeof(int64));
	memset(tv->count, 0, (tv->n + 1) * sizeof(int64));
	tv->nranks = 0;
	for (uint32 k = 0; k < tv->n; k++)
	{
		uint32		i = order[k];

		if (k == 0 || ApplySortComparator(tv->values[order[k - 1]], false, tv->values[i], false,
										  tv->sort) != 0)
		{
			tv->nranks++;
			tv->by_rank[tv->nranks] = tv->values[i];
		}
		tv->rank[i] = tv->nranks;
	}
	pfree(order);
	MemoryContextSwitchTo(old);
	if (tv->nranks > (uint32) PG_INT32_MAX)
		ereport(ERROR,
				(errcode(ERRCODE_PROGRAM_LIMIT_EXCEEDED),
				 errmsg("%s: %u distinct tile values, more than the ids have room for (%d)", fname,
						tv->nranks, PG_INT32_MAX)));
}
