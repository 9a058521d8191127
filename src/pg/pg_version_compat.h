/*
 * pg_version_compat.h
 *		Every difference between the PostgreSQL majors this extension builds
 *		against (15, 17, 18), in one place.
 *
 * The rest of src/pg is written against the newest API; this header maps
 * it onto the older servers, so no other file tests PG_VERSION_NUM.  Each
 * shim says in which release the API changed.  Included by tdc_pg.h, right
 * after postgres.h.
 */
#ifndef PG_VERSION_COMPAT_H
#define PG_VERSION_COMPAT_H

#include "postgres.h"

/* 16 moved VARSIZE and the other varlena macros out of postgres.h. */
#if PG_VERSION_NUM >= 160000
#include "varatt.h"
#endif

/* 17 moved PG_TEMP_FILE_PREFIX from storage/fd.h to common/file_utils.h. */
#if PG_VERSION_NUM >= 170000
#include "common/file_utils.h"
#endif

/*
 * 18 replaced the trailing pg_attribute_noreturn() by a leading pg_noreturn.
 * GCC and clang take the attribute in the leading position too.
 */
#if PG_VERSION_NUM < 180000 && !defined(pg_noreturn)
#define pg_noreturn pg_attribute_noreturn()
#endif

/*
 * 15.1 renamed SetSingleFuncCall (15.0) to InitMaterializedSRF; the
 * arguments are the same.  funcapi.h declares either.
 */
#if PG_VERSION_NUM < 150001
#define InitMaterializedSRF(fcinfo, flags) SetSingleFuncCall(fcinfo, flags)
#endif

/*
 * 16 dropped the errorType argument of ExceptionalCondition, the function a
 * failed Assert calls (it was always "FailedAssertion" by then).  Nothing
 * in src/pg calls it by name; only the fuzz harness's stand-in for the
 * server (fuzz/pg_shim.c) defines it, and picks its signature by this.
 */
#if PG_VERSION_NUM >= 160000
#define TDC_ASSERT_HAS_ERRORTYPE 0
#else
#define TDC_ASSERT_HAS_ERRORTYPE 1
#endif

#endif							/* PG_VERSION_COMPAT_H */
