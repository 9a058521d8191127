/*
 * pg_shim_agg.c
 *		The rest of the backend, and of tdc_delaunay's own runtime, that the
 *		TIN aggregates' SQL entry points (fn_contours_agg.c, fn_drape_agg.c,
 *		fn_raster_agg.c) reference, for fuzz_state.  Harness code: it runs
 *		only inside the fuzzer.
 *
 * fuzz_state calls the serial, deserial and combine functions of those
 * aggregates through their fmgr entry points, and never their transition
 * or final functions: those read geometries and run the engine on threads
 * through run.c's wait loop (latches, signals), which has no stand-in here.
 * So the pieces only the transition and final functions use (tin_run.c,
 * the geometry and sample readers of toast_stream.c, the pcpatch reader
 * of pcpatch_source.c, and run.c's wait loop for the breaklines' insertion)
 * raise an ERROR that the harness counts as a finding, and the helpers of
 * fn_delaunay_agg.c and signals.c that every entry point calls do what the
 * server's do in a backend that is not being signalled.
 */
#include "postgres.h"

#include <strings.h>

#include "fmgr.h"
#include "utils/builtins.h"
#include "utils/memutils.h"

#include "pg_shim.h"
/* the stand-ins checked against the real declarations */
#include "tdc_pg.h"

/* signals.c: nothing to settle, no signal comes */
bool		tdc_signal_settled = true;

void
tdc_signal_settle(void)
{
	tdc_signal_settled = true;
}

/* fn_delaunay_agg.c: the same test as the server's */
MemoryContext
tdc_agg_context(FunctionCallInfo fcinfo, const char *fn)
{
	MemoryContext aggcxt;

	if (!AggCheckCallContext(fcinfo, &aggcxt))
		elog(ERROR, "%s called in non-aggregate context", fn);
	return aggcxt;
}

/* Only the transition functions ask; the harness has no Aggref. */
bool
tdc_agg_arg_is_constant(FunctionCallInfo fcinfo, int argno)
{
	return false;
}

/* ----------------------------------------------------------------
 *		tin_run.c and toast_stream.c: transition and final functions only
 * ----------------------------------------------------------------
 */
pg_noreturn static void
not_here(const char *what)
{
	ereport(ERROR,
			(errcode(ERRCODE_FEATURE_NOT_SUPPORTED),
			 errmsg("%s is not in the fuzzer (transition and final functions only)", what)));
	pg_unreachable();
}

/* toast_stream.c, for ST_TDCInterpolateRaster (fn_raster.c) */
bool
tdc_read_geometry(TdcPointBuf *buf, Datum d, const char *fname)
{
	not_here("tdc_read_geometry");
}

void
tdc_tin_read_sample(TdcPointBuf *buf, Datum d, int64 row, const char *fname)
{
	not_here("tdc_tin_read_sample");
}

/* pcpatch_source.c: the pcpatch transition functions' reader */
void
tdc_pc_read_patch(TdcAggState *st, FmgrInfo *flinfo, Datum patch, text *filter, const char *fname)
{
	not_here("tdc_pc_read_patch");
}

text *
tdc_pc_filter_arg(FunctionCallInfo fcinfo, int geometry_nargs)
{
	not_here("tdc_pc_filter_arg");
}

TdcTinRun *
tdc_tin_run_start(const TdcPointBuf *buf, const TdcSegList *breaklines, uint64 extra,
				  const char *fname)
{
	not_here("tdc_tin_run_start");
}

void
tdc_tin_run_wait(TdcTinRun *tr, int rc, const char *err, const char *fname)
{
	not_here("tdc_tin_run_wait");
}

void
tdc_tin_run_free(TdcTinRun *tr)
{
	not_here("tdc_tin_run_free");
}

/*
 * run.c and settings.c, for the insertion of breaklines (seglist.c's
 * tdc_constrain, final functions only): its segment list's reading,
 * appending and growth, which the harness does reach, need none of them.
 */
bool		tdc_guc_stats = false;

int
tdc_wait_work(void *work, const TdcWorkOps *ops, const char *fname)
{
	not_here("tdc_wait_work");
}

void
tdc_report_status(int rc, const char *msg, const char *fname)
{
	not_here("tdc_report_status");
}

/* ----------------------------------------------------------------
 *		libpgcommon, libpgport and mcxt.c pieces
 * ----------------------------------------------------------------
 */
char *
pnstrdup(const char *in, Size len)
{
	char	   *out;

	len = strnlen(in, len);
	out = palloc(len + 1);
	memcpy(out, in, len);
	out[len] = '\0';
	return out;
}

char *
MemoryContextStrdup(MemoryContext context, const char *string)
{
	Size		len = strlen(string) + 1;

	return memcpy(MemoryContextAlloc(context, len), string, len);
}

char *
text_to_cstring(const text *t)
{
	/* the harness passes plain values: nothing to detoast */
	return pnstrdup(VARDATA_ANY(t), VARSIZE_ANY_EXHDR(t));
}

void *
palloc_extended(Size size, int flags)
{
	void	   *p = (flags & MCXT_ALLOC_HUGE) ?
		MemoryContextAllocHuge(CurrentMemoryContext, size) : palloc(size);

	if (flags & MCXT_ALLOC_ZERO)
		memset(p, 0, size);
	return p;
}

int
pg_strncasecmp(const char *s1, const char *s2, size_t n)
{
	return strncasecmp(s1, s2, n);
}
