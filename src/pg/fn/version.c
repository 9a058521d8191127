/*
 * version.c
 *		tdc_delaunay_lib_version() and tdc_delaunay_full_version(): what a
 *		bug report needs, as postgis_lib_version() and postgis_full_version()
 *		give it for PostGIS.
 *
 * The library's version and the PostGIS seen at build time come from the
 * Makefile (TDC_LIB_VERSION, TDC_BUILD_POSTGIS).  The library does not
 * compile against PostGIS, so the PostGIS "built against" is the
 * default_version of the postgis control file the build found, or
 * "unknown".  What the server runs is read at call time: its version, and
 * the versions of the postgis and tdc_delaunay extensions installed in this
 * database.  The SQL objects of tdc_delaunay may be of another version than
 * the library between a package upgrade and ALTER EXTENSION UPDATE (the
 * library keeps every C function an older script names, so they go on
 * working); the report says so, with a WARNING.
 */
#include "postgres.h"

#include "access/genam.h"
#include "access/htup_details.h"
#include "access/table.h"
#include "catalog/indexing.h"
#include "catalog/pg_extension.h"
#include "lib/stringinfo.h"
#include "utils/builtins.h"
#include "utils/fmgroids.h"
#include "utils/guc.h"
#include "utils/rel.h"

#include "tdc_pg.h"

#ifndef TDC_LIB_VERSION
#error "the Makefile defines TDC_LIB_VERSION (its EXTVERSION)"
#endif
#ifndef TDC_BUILD_POSTGIS
#define TDC_BUILD_POSTGIS "unknown"
#endif

PG_FUNCTION_INFO_V1(tdc_delaunay_lib_version);
PG_FUNCTION_INFO_V1(tdc_delaunay_full_version);

Datum
tdc_delaunay_lib_version(PG_FUNCTION_ARGS)
{
	tdc_signal_guard();
	PG_RETURN_TEXT_P(cstring_to_text(TDC_LIB_VERSION));
}

/*
 * The version of extension "name" installed in this database, or NULL.
 * Read from pg_extension directly (as the server's own extension code
 * does), so that the report works in any search_path and in parallel
 * workers.
 */
static char *
installed_version(const char *name)
{
	Relation	rel;
	ScanKeyData key;
	SysScanDesc scan;
	HeapTuple	tup;
	char	   *version = NULL;

	rel = table_open(ExtensionRelationId, AccessShareLock);
	ScanKeyInit(&key, Anum_pg_extension_extname, BTEqualStrategyNumber,
				F_NAMEEQ, CStringGetDatum(name));
	scan = systable_beginscan(rel, ExtensionNameIndexId, true, NULL, 1, &key);
	tup = systable_getnext(scan);
	if (HeapTupleIsValid(tup))
	{
		bool		isnull;
		Datum		d = heap_getattr(tup, Anum_pg_extension_extversion,
									 RelationGetDescr(rel), &isnull);

		if (!isnull)
			version = text_to_cstring(DatumGetTextPP(d));
	}
	systable_endscan(scan);
	table_close(rel, AccessShareLock);
	return version;
}

/*
 * One line of NAME="value" pairs, in the manner of postgis_full_version():
 *	TDC_DELAUNAY	the library
 *	EXTENSION		the SQL objects in this database, with a note when they
 *					are not the library's version
 *	PGSQL			the server, BUILT_PGSQL the headers the library was built with
 *	POSTGIS			the postgis extension in this database, BUILT_POSTGIS at build
 *	THREADS			the threads a triangulation would start now
 */
Datum
tdc_delaunay_full_version(PG_FUNCTION_ARGS)
{
	StringInfoData out;
	char	   *sql_version;
	char	   *postgis;

	tdc_signal_guard();
	sql_version = installed_version("tdc_delaunay");
	postgis = installed_version("postgis");

	initStringInfo(&out);
	appendStringInfo(&out, "TDC_DELAUNAY=\"%s\"", TDC_LIB_VERSION);
	appendStringInfo(&out, " EXTENSION=\"%s\"",
					 sql_version ? sql_version : "not installed");
	if (sql_version && strcmp(sql_version, TDC_LIB_VERSION) != 0)
	{
		appendStringInfoString(&out,
							   " [needs ALTER EXTENSION tdc_delaunay UPDATE]");
		ereport(WARNING,
				(errmsg("tdc_delaunay: the library is version %s, its SQL objects in this database are version %s",
						TDC_LIB_VERSION, sql_version),
				 errhint("Run ALTER EXTENSION tdc_delaunay UPDATE.")));
	}
	appendStringInfo(&out, " PGSQL=\"%s\" BUILT_PGSQL=\"%s\"",
					 GetConfigOption("server_version", false, false),
					 PG_VERSION);
	appendStringInfo(&out, " POSTGIS=\"%s\" BUILT_POSTGIS=\"%s\"",
					 postgis ? postgis : "not installed", TDC_BUILD_POSTGIS);
	appendStringInfo(&out, " THREADS=\"%d\"", tdc_effective_threads());
	PG_RETURN_TEXT_P(cstring_to_text(out.data));
}
