/*
 * pg_shim.c
 *		Minimal backend services for the PostgreSQL-side fuzz targets; see
 *		pg_shim.h.  This is harness code: it runs only inside the fuzzers.
 */
#include "postgres.h"

#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>

#include "access/detoast.h"
#include "fmgr.h"
#include "miscadmin.h"
#include "utils/memutils.h"

#include "pg_version_compat.h"
#include "pg_shim.h"
/* the shim's tdc_* stand-ins checked against the real declarations */
#include "tdc_pg.h"

sigjmp_buf *fuzz_pg_jmp = NULL;
int			fuzz_pg_sqlstate = 0;
char		fuzz_pg_message[1024];
int			fuzz_pg_verbose = 0;
int			fuzz_pg_max_memory_mb = 0;

/* ----------------------------------------------------------------
 *		printf: port.h maps the libc names to libpgport's pg_* versions;
 *		the formats used here are all libc-compatible (no %m).
 * ----------------------------------------------------------------
 */
#undef vsnprintf
#undef snprintf
#undef fprintf
#undef vfprintf
#undef printf
#undef vprintf

int
pg_vsnprintf(char *str, size_t count, const char *fmt, va_list args)
{
	return vsnprintf(str, count, fmt, args);
}

int
pg_snprintf(char *str, size_t count, const char *fmt,...)
{
	va_list		ap;
	int			r;

	va_start(ap, fmt);
	r = vsnprintf(str, count, fmt, ap);
	va_end(ap);
	return r;
}

int
pg_fprintf(FILE *stream, const char *fmt,...)
{
	va_list		ap;
	int			r;

	va_start(ap, fmt);
	r = vfprintf(stream, fmt, ap);
	va_end(ap);
	return r;
}

int
pg_printf(const char *fmt,...)
{
	va_list		ap;
	int			r;

	va_start(ap, fmt);
	r = vprintf(fmt, ap);
	va_end(ap);
	return r;
}

/* ----------------------------------------------------------------
 *		memory
 * ----------------------------------------------------------------
 */

typedef union ShimChunk
{
	struct
	{
		union ShimChunk *prev;
		union ShimChunk *next;
		Size		size;
	}			h;
	max_align_t align;
	char		pad[32];
} ShimChunk;

static ShimChunk *chunks = NULL;
static size_t allocated = 0;

/* One dummy context; the code under test only passes it around. */
static MemoryContextData dummy_context;
MemoryContext CurrentMemoryContext = &dummy_context;
MemoryContext TopMemoryContext = &dummy_context;

static void *
shim_alloc(Size size, bool zero, bool huge)
{
	ShimChunk  *c;

	if (!huge && !AllocSizeIsValid(size))
		elog(ERROR, "invalid memory alloc request size %zu", size);
	if (huge && !AllocHugeSizeIsValid(size))
		elog(ERROR, "invalid memory alloc request size %zu", size);
	/* stay far below the fuzzer's RSS limit: a real server would say ENOMEM */
	if (size > ((Size) 256 << 20))
		ereport(ERROR,
				(errcode(ERRCODE_OUT_OF_MEMORY),
				 errmsg("out of memory (fuzz shim refuses %zu bytes)", size)));
	c = malloc(sizeof(ShimChunk) + size);
	if (c == NULL)
		ereport(ERROR, (errcode(ERRCODE_OUT_OF_MEMORY), errmsg("out of memory")));
	if (zero)
		memset(c + 1, 0, size);
	c->h.size = size;
	c->h.prev = NULL;
	c->h.next = chunks;
	if (chunks)
		chunks->h.prev = c;
	chunks = c;
	allocated += size;
	return c + 1;
}

static void
shim_unlink(ShimChunk *c)
{
	if (c->h.prev)
		c->h.prev->h.next = c->h.next;
	else
		chunks = c->h.next;
	if (c->h.next)
		c->h.next->h.prev = c->h.prev;
	allocated -= c->h.size;
}

static void *
shim_realloc(void *p, Size size, bool huge)
{
	ShimChunk  *c = (ShimChunk *) p - 1;
	void	   *n = shim_alloc(size, false, huge);

	memcpy(n, p, Min(size, c->h.size));
	shim_unlink(c);
	free(c);
	return n;
}

/* Reset callbacks of the one context, newest first, as PostgreSQL runs them. */
static MemoryContextCallback *callbacks = NULL;

void
MemoryContextRegisterResetCallback(MemoryContext context, MemoryContextCallback *cb)
{
	cb->next = callbacks;
	callbacks = cb;
}

void
fuzz_pg_reset(void)
{
	while (callbacks)
	{
		MemoryContextCallback *cb = callbacks;

		callbacks = cb->next;
		cb->func(cb->arg);
	}
	while (chunks)
	{
		ShimChunk  *c = chunks;

		chunks = c->h.next;
		free(c);
	}
	allocated = 0;
}

size_t
fuzz_pg_allocated(void)
{
	return allocated;
}

void *
palloc(Size size)
{
	return shim_alloc(size, false, false);
}

void *
palloc0(Size size)
{
	return shim_alloc(size, true, false);
}

void *
MemoryContextAlloc(MemoryContext context, Size size)
{
	return shim_alloc(size, false, false);
}

void *
MemoryContextAllocZero(MemoryContext context, Size size)
{
	return shim_alloc(size, true, false);
}

void *
MemoryContextAllocHuge(MemoryContext context, Size size)
{
	return shim_alloc(size, false, true);
}

void *
repalloc(void *pointer, Size size)
{
	return shim_realloc(pointer, size, false);
}

void *
repalloc_huge(void *pointer, Size size)
{
	return shim_realloc(pointer, size, true);
}

void
pfree(void *pointer)
{
	ShimChunk  *c = (ShimChunk *) pointer - 1;

	shim_unlink(c);
	free(c);
}

char *
psprintf(const char *fmt,...)
{
	va_list		ap;
	char		tmp[1024];

	va_start(ap, fmt);
	vsnprintf(tmp, sizeof(tmp), fmt, ap);
	va_end(ap);
	return strcpy(palloc(strlen(tmp) + 1), tmp);
}

/* ----------------------------------------------------------------
 *		errors
 * ----------------------------------------------------------------
 */

static int	cur_elevel;
static int	cur_sqlstate;
static char cur_message[1024];

bool
errstart(int elevel, const char *domain)
{
	cur_elevel = elevel;
	cur_sqlstate = ERRCODE_INTERNAL_ERROR;
	cur_message[0] = '\0';
	return true;
}

bool
errstart_cold(int elevel, const char *domain)
{
	return errstart(elevel, domain);
}

int
errcode(int sqlerrcode)
{
	cur_sqlstate = sqlerrcode;
	return 0;
}

static void
set_message(const char *fmt, va_list ap)
{
	vsnprintf(cur_message, sizeof(cur_message), fmt, ap);
}

int
errmsg(const char *fmt,...)
{
	va_list		ap;

	va_start(ap, fmt);
	set_message(fmt, ap);
	va_end(ap);
	return 0;
}

int
errmsg_internal(const char *fmt,...)
{
	va_list		ap;

	va_start(ap, fmt);
	set_message(fmt, ap);
	va_end(ap);
	return 0;
}

int
errhint(const char *fmt,...)
{
	return 0;
}

int
errdetail(const char *fmt,...)
{
	return 0;
}

void
errfinish(const char *filename, int lineno, const char *funcname)
{
	if (fuzz_pg_verbose)
		fprintf(stderr, "[shim] level %d %s:%d %s: %s\n", cur_elevel, filename,
				lineno, funcname, cur_message);
	if (cur_elevel < ERROR)
		return;
	fuzz_pg_sqlstate = cur_sqlstate;
	memcpy(fuzz_pg_message, cur_message, sizeof(fuzz_pg_message));
	if (fuzz_pg_jmp == NULL)
	{
		fprintf(stderr, "ERROR outside of a PG_FUZZ_TRY block: %s\n", cur_message);
		abort();
	}
	siglongjmp(*fuzz_pg_jmp, 1);
}

/* A failed Assert: abort(), which the fuzzer reports as a crash. */
pg_noreturn static void
assert_failed(const char *conditionName, const char *errorType,
			  const char *fileName, int lineNumber)
{
	fprintf(stderr, "TRAP: %s(\"%s\", File: \"%s\", Line: %d)\n",
			errorType, conditionName, fileName, lineNumber);
	abort();
}

/* Its signature differs between majors: pg_version_compat.h. */
#if TDC_ASSERT_HAS_ERRORTYPE
void
ExceptionalCondition(const char *conditionName, const char *errorType,
					 const char *fileName, int lineNumber)
{
	assert_failed(conditionName, errorType, fileName, lineNumber);
}
#else
void
ExceptionalCondition(const char *conditionName, const char *fileName,
					 int lineNumber)
{
	assert_failed(conditionName, "FailedAssertion", fileName, lineNumber);
}
#endif

/* ----------------------------------------------------------------
 *		interrupts, stack
 * ----------------------------------------------------------------
 */

volatile sig_atomic_t InterruptPending = false;

void
ProcessInterrupts(void)
{
	InterruptPending = false;
}

static char *stack_base;

void
fuzz_pg_stack_base(void *base)
{
	stack_base = base;
}

/*
 * Like the server with max_stack_depth = 2MB less its safety margin.  Frame
 * addresses on both ends, for the reason in pg_shim.h.
 */
void
check_stack_depth(void)
{
	char	   *here = __builtin_frame_address(0);
	long		depth = stack_base ? labs((long) (stack_base - here)) : 0;

	if (depth > 1536L * 1024)
		ereport(ERROR,
				(errcode(ERRCODE_STATEMENT_TOO_COMPLEX),
				 errmsg("stack depth limit exceeded")));
}

/* ----------------------------------------------------------------
 *		fmgr bits and the tdc_delaunay settings
 * ----------------------------------------------------------------
 */

int
AggCheckCallContext(FunctionCallInfo fcinfo, MemoryContext *aggcontext)
{
	if (aggcontext)
		*aggcontext = CurrentMemoryContext;
	return 1;
}

struct varlena *
pg_detoast_datum(struct varlena *datum)
{
	return datum;
}

struct varlena *
pg_detoast_datum_packed(struct varlena *datum)
{
	return datum;
}

/*
 * The harness's values are plain in-memory varlenas with a 4-byte header:
 * a slice is a copy of their bytes [first, first + count), as the server
 * returns for a value stored uncompressed.
 */
struct varlena *
pg_detoast_datum_slice(struct varlena *datum, int32 first, int32 count)
{
	Size		size = VARSIZE(datum) - VARHDRSZ;
	Size		from = Min((Size) first, size);
	Size		n = count < 0 ? size - from : Min((Size) count, size - from);
	struct varlena *out = palloc(VARHDRSZ + n);

	SET_VARSIZE(out, VARHDRSZ + n);
	memcpy(VARDATA(out), VARDATA(datum) + from, n);
	return out;
}

Size
toast_raw_datum_size(Datum value)
{
	return VARSIZE(DatumGetPointer(value));
}

/*
 * PostGIS's ST_CurveToLine is not here: a reader that strokes curves
 * (TDC_CURVES_STROKE) gets an ERROR once it has stopped at the first one.
 */
struct varlena *
tdc_curve_to_line(Datum geom, const char *fname)
{
	ereport(ERROR,
			(errcode(ERRCODE_FEATURE_NOT_SUPPORTED),
			 errmsg("%s: the fuzzer has no ST_CurveToLine", fname)));
	return NULL;
}

int			tdc_guc_max_result_bytes = MaxAllocSize;

int			tdc_guc_max_memory_mb;

uint64
tdc_max_memory_bytes(void)
{
	tdc_guc_max_memory_mb = fuzz_pg_max_memory_mb;
	return (uint64) fuzz_pg_max_memory_mb << 20;
}

/* Same error as settings.c, with the limit the fuzzer picked. */
void
tdc_report_memory_limit(const char *fname, const char *what, uint64 need,
						uint64 result)
{
	ereport(ERROR,
			(errcode(ERRCODE_PROGRAM_LIMIT_EXCEEDED),
			 errmsg("%s: %s needs about %llu MB, more than tdc_delaunay.max_memory (%d MB)",
					fname, what, (unsigned long long) ((need + result + (1 << 20) - 1) >> 20),
					fuzz_pg_max_memory_mb)));
	pg_unreachable();
}
