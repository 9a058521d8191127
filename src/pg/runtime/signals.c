/*
 * signals.c
 *		Keep PostGIS's cancel handler from allocating memory inside a signal.
 *
 * PostGIS installs its own SIGINT handler when its library is loaded.  The
 * handler records the cancel for liblwgeom in a thread-local variable and
 * then calls PostgreSQL's.  glibc gives a dlopen'ed library's thread-local
 * block to a thread lazily, on the thread's first access, and allocates it
 * with malloc.  So in a backend where no PostGIS code has touched that
 * variable yet, the first cancel runs malloc inside the signal handler; if
 * the backend was itself inside malloc at that moment, the heap is corrupt
 * and glibc aborts ("malloc assertion failure in sysmalloc"): the postmaster
 * then restarts every session.
 *
 * Ordinary PostGIS functions touch the variable early, so a plain PostGIS
 * backend is rarely exposed.  Ours never do: we read and write geometry
 * values ourselves and run for seconds, allocating all the time, in
 * backends that may not have run a single PostGIS function.  A cancel storm
 * against fresh sessions hit the window about once in a hundred sessions.
 *
 * tdc_signal_settle() closes it once per backend.  With SIGINT blocked, so
 * that no handler can run halfway, it has glibc allocate, for the calling
 * thread, the thread-local block of every loaded library that has one
 * (through the same __tls_get_addr that the libraries' own code calls),
 * loads the PostGIS library if the backend has not yet (through one of its
 * functions' catalog entries, which is what the first call of any PostGIS
 * function would do), and does it again for what that brought in.  After
 * that, no handler's first thread-local access allocates.  Only the
 * backend's main thread takes signals: the core's threads start with every
 * signal blocked.
 *
 * _PG_init settles when our library is loaded inside a transaction, which is
 * how a query or a parallel worker loads it; tdc_signal_guard(), at the top
 * of every SQL entry point, settles when _PG_init could not (a library
 * preloaded by the postmaster).  So when our library comes first, PostGIS's
 * handler is only ever installed with its block ready.  When PostGIS comes
 * first in the same query, the window is the few microseconds of executor
 * start-up between the two loads.  On platforms other than glibc on x86-64
 * or AArch64, settling only loads PostGIS.
 */
#include "postgres.h"

#include <signal.h>

#if defined(__GLIBC__) && (defined(__x86_64__) || defined(__aarch64__))
#define TDC_SETTLE_TLS 1
#include <link.h>
#endif

#include "access/htup_details.h"
#include "catalog/pg_language.h"
#include "catalog/pg_proc.h"
#include "fmgr.h"
#include "utils/builtins.h"
#include "utils/catcache.h"
#include "utils/syscache.h"

#include "tdc_pg.h"

bool		tdc_signal_settled = false;

#ifdef TDC_SETTLE_TLS
/* The argument of __tls_get_addr on these platforms (the ELF TLS ABI). */
typedef struct TdcTlsIndex
{
	unsigned long int module;
	unsigned long int offset;
} TdcTlsIndex;

extern void *__tls_get_addr(TdcTlsIndex *ti);

/* dl_iterate_phdr callback: count, or allocate, unallocated blocks. */
static int
settle_one(struct dl_phdr_info *info, size_t size, void *arg)
{
	int		   *missing = (int *) arg;

	if (info->dlpi_tls_modid != 0 && info->dlpi_tls_data == NULL)
	{
		if (missing)
			(*missing)++;
		else
		{
			TdcTlsIndex ti = {info->dlpi_tls_modid, 0};

			(void) __tls_get_addr(&ti);
		}
	}
	return 0;
}
#endif

/*
 * Load the PostGIS library, found through its function postgis_lib_version
 * in whatever schema PostGIS lives in; nothing when there is none.
 */
static void
load_postgis(void)
{
	CatCList   *list;
	Oid			fn = InvalidOid;

	list = SearchSysCacheList1(PROCNAMEARGSNSP,
							   CStringGetDatum("postgis_lib_version"));
	for (int i = 0; i < list->n_members && !OidIsValid(fn); i++)
	{
		Form_pg_proc p = (Form_pg_proc) GETSTRUCT(&list->members[i]->tuple);

		if (p->prolang == ClanguageId)
			fn = p->oid;
	}
	ReleaseSysCacheList(list);

	if (OidIsValid(fn))
	{
		FmgrInfo	finfo;

		fmgr_info(fn, &finfo);	/* loads the library; does not call it */
	}
}

/* Allocate the calling thread's block of every loaded library with one. */
static void
settle_tls(void)
{
#ifdef TDC_SETTLE_TLS
	dl_iterate_phdr(settle_one, NULL);
#endif
}

void
tdc_signal_settle(void)
{
	sigset_t	sigint,
				old;

	sigemptyset(&sigint);
	sigaddset(&sigint, SIGINT);
	sigprocmask(SIG_BLOCK, &sigint, &old);
	PG_TRY();
	{
		settle_tls();
		load_postgis();
		settle_tls();
		tdc_signal_settled = true;
	}
	PG_FINALLY();
	{
		sigprocmask(SIG_SETMASK, &old, NULL);
	}
	PG_END_TRY();
}

/*
 * _tdc_signal_tls_ready(): true when every loaded library's thread-local
 * block is allocated for the backend's main thread (the tests' view of the
 * guard).  Does not settle anything itself.
 */
PG_FUNCTION_INFO_V1(_tdc_signal_tls_ready);

Datum
_tdc_signal_tls_ready(PG_FUNCTION_ARGS)
{
	int			missing = 0;

#ifdef TDC_SETTLE_TLS
	dl_iterate_phdr(settle_one, &missing);
#endif
	PG_RETURN_BOOL(missing == 0);
}
