/*
 * pg_shim.h
 *		Stand-ins for the few PostgreSQL backend services that the
 *		tdc_delaunay reader and writers (src/pg/formats/gser_read.c,
 *		gser_write.c, src/pg/runtime/pointbuf.c) and the aggregate state
 *		(src/pg/runtime/agg_state.c) use, so that they run inside a
 *		libFuzzer process without a server.
 *
 * Memory: palloc and friends allocate with malloc and remember every chunk;
 * fuzz_pg_reset() frees them all, like resetting a memory context at the end
 * of a query.  Errors: ereport(ERROR) (and elog) lands in errfinish(), which
 * longjmps back to the PG_FUZZ_TRY point of the harness with the SQLSTATE
 * and message kept in fuzz_pg_sqlstate / fuzz_pg_message.
 *
 * Compiled against the real server headers (pg_config --includedir-server)
 * with USE_ASSERT_CHECKING, so the Asserts in the code under test are live
 * and fail through abort().
 */
#ifndef PG_SHIM_H
#define PG_SHIM_H

#include <setjmp.h>

extern sigjmp_buf *fuzz_pg_jmp;
extern int	fuzz_pg_sqlstate;
extern char fuzz_pg_message[1024];
extern int	fuzz_pg_verbose;

/* Settings the code under test reads (settings.c in the server). */
extern int	fuzz_pg_max_memory_mb;

/* Free every allocation made since the last reset. */
extern void fuzz_pg_reset(void);

/* Bytes currently allocated through the shim. */
extern size_t fuzz_pg_allocated(void);

/*
 * Record the stack position of the harness entry (for check_stack_depth):
 * call FUZZ_PG_STACK_BASE() at the top of LLVMFuzzerTestOneInput.  It takes
 * the frame address, not the address of a local: AddressSanitizer (by
 * default from clang 15 on, detect_stack_use_after_return) puts locals in
 * "fake" frames on the heap, so two locals' distance says nothing about the
 * depth of the real stack, and every input would look too deep.
 */
#define FUZZ_PG_STACK_BASE() fuzz_pg_stack_base(__builtin_frame_address(0))
extern void fuzz_pg_stack_base(void *base);

#endif							/* PG_SHIM_H */
