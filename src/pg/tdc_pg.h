/*
 * tdc_pg.h
 *		The PostgreSQL side of tdc_delaunay: what every SQL function is
 *		built from, and what its folders share.
 *
 * src/pg is three folders, each calling only the ones below it
 * (test/layering.sh; docs/design/pg-runtime.md says why):
 *
 * runtime/, running the core in a backend:
 *	settings.c		_PG_init and the tdc_delaunay.* settings
 *	run.c			runs a job (and any work on it) while watching for
 *					interrupts: the one wait loop; core status to SQLSTATE;
 *					the parameter checks every function shares
 *	signals.c		keeps PostGIS's cancel handler from allocating inside a
 *					signal; every SQL entry point calls tdc_signal_guard()
 *	mem_cache.c		the engine's big arrays kept between runs
 *	pointbuf.c		the point buffer the vertices of the input collect in
 *	agg_state.c		the aggregates' state, its merging and serialized form
 *	seglist.c		constraint segments from linework, and their insertion
 *					(the constrained functions and the TIN's breaklines)
 *	tin_run.c		a TIN of the samples, and the operations on it, waited on
 *	tile_values.c	a tile column's values of any ordered type as dense labels
 *
 * formats/, the bytes of PostgreSQL and PostGIS values:
 *	gser_read.c		reads PostGIS geometry values straight into a point
 *					buffer (the format is in gser_format.h)
 *	toast_stream.c	reads a function's geometry argument, a big TOASTed
 *					value a slice at a time (tdc_read_geometry), and a TIN's
 *					sample (tdc_tin_read_sample)
 *	curves.c		curved input: stroked by PostGIS's ST_CurveToLine for
 *					the Delaunay functions, as ST_DelaunayTriangles does
 *	gser_write.c	writes triangulations back as geometry values
 *	gser_contour.c	contour lines written as a MULTILINESTRING Z
 *	gser_drape.c	a target geometry read as chains and written again draped
 *	raster_read.c, raster_write.c  PostGIS rasters (raster_format.h)
 *	table_write.c	rows written straight into a table just created
 *	dump_query.c	the Dump functions' query: checked, run, collected
 *
 * fn/, the SQL entry points, thin fmgr adapters named after their SQL names
 * (fn_<feature>[_agg|_dump].c): fn_delaunay (ST_TDCDelaunayTriangles,
 * ST_TDCDelaunayDump), fn_delaunay_agg (ST_TDCDelaunay), fn_constrained
 * (ST_TDCConstrainedDelaunayTriangles, its Dump and aggregate), fn_voronoi
 * (ST_TDCVoronoiPolygons/Lines; fn_voronoi.h for its aggregate and Dump),
 * fn_tiled (tdc_delaunay_tiled's per-tile step and curve helper, with
 * fn_tiled_bounded and fn_tiled_region), fn_contours_agg (ST_TDCContours),
 * fn_drape_agg (ST_TDCDrape), fn_raster and fn_raster_agg (the raster
 * interpolation), version.c (the versions a bug report needs); and
 * tin_agg.c, the TIN aggregates' shared samples and support functions.
 *
 * pg_version_compat.h, beside this header: every difference between
 * PostgreSQL majors.
 *
 * Only the backend's main thread ever calls PostgreSQL.  The core's worker
 * threads see nothing but plain malloc'd arrays.
 */
#ifndef TDC_PG_H
#define TDC_PG_H

#include "postgres.h"

#include "pg_version_compat.h"

#include "fmgr.h"
#include "portability/instr_time.h"
#include "tdc.h"

/* Output kinds, the "flags" argument of ST_DelaunayTriangles. */
#define TDC_OUT_POLYGONS	0	/* GEOMETRYCOLLECTION of POLYGON */
#define TDC_OUT_EDGES		1	/* MULTILINESTRING */
#define TDC_OUT_TIN			2	/* TIN */
/* Constrained functions only: 1 | 4, a MULTILINESTRING of the constraint edges alone. */
#define TDC_OUT_CONSTRAINTS	5

/*
 * Is flags an output kind of the function?  The Delaunay functions take
 * 0..2; the constrained ones (constraints true) also 5.  The one test of
 * flags: tdc_check_flags (run.c) raises its ERROR, and the aggregate
 * states' readers (agg_state.c) use it on what they read.
 */
static inline bool
tdc_flags_valid(int flags, bool constraints)
{
	return (flags >= TDC_OUT_POLYGONS && flags <= TDC_OUT_TIN) ||
		(constraints && flags == TDC_OUT_CONSTRAINTS);
}

/* Settings (settings.c). */
extern int	tdc_guc_threads;
extern int	tdc_guc_max_threads;
extern int	tdc_guc_grid_size;
extern int	tdc_guc_levels;
extern int	tdc_guc_max_memory_mb;
extern int	tdc_guc_memory_ceiling_mb;
extern bool tdc_guc_stats;
extern int	tdc_guc_max_result_bytes;
extern int	tdc_guc_keep_memory_mb;
extern int	tdc_guc_keep_memory_time_ms;

/* mem_cache.c: the engine's big arrays kept between runs */
extern tdc_cache *tdc_backend_cache(uint64 room, bool use);
extern void tdc_backend_cache_idle(void);
extern void tdc_backend_cache_release(void);
extern unsigned long long tdc_backend_cache_kept_kb(void);

/*
 * The memory limit of one triangulation: tdc_delaunay.max_memory within
 * tdc_delaunay.memory_ceiling.  In MB with the name of the setting that
 * bounds it, or in bytes; 0 when unlimited.
 */
extern uint64 tdc_memory_limit_mb(const char **setting);
extern uint64 tdc_max_memory_bytes(void);
/* The HINT for an input over the limit: what the user can do about it. */
extern const char *tdc_memory_limit_hint(void);
/*
 * ERROR: "what" needs "need" bytes and a result value of "result" bytes more
 * (0: the caller allocates none), together more than the limit.  The two are
 * reported apart so that the same triangulation gets the same figure from
 * every function, whether or not it builds one result value.
 */
extern pg_noreturn void tdc_report_memory_limit(const char *fname, const char *what,
												uint64 need, uint64 result);

/* The mappings behind a point buffer, released with its context. */
typedef struct TdcPointMap
{
	double	   *xy;
	Size		xy_bytes;
	double	   *z;
	Size		z_bytes;
} TdcPointMap;

/*
 * What the reader does with a curve (CIRCULARSTRING and the types made of
 * them), as the PostGIS or SFCGAL counterpart of the function does: see
 * curves.c.
 */
typedef enum TdcCurves
{
	TDC_CURVES_REFUSE = 0,		/* an ERROR with a hint (the constrained functions) */
	TDC_CURVES_STROKE,			/* the value through ST_CurveToLine (Delaunay) */
	TDC_CURVES_VERTICES			/* the stored vertices, control points (Voronoi) */
} TdcCurves;

/*
 * Called by the reader for every chain of k > 1 vertices it appends (a
 * linestring, a triangle, a polygon ring), the first at index "first": the
 * constrained functions take their segments from the chains.
 */
typedef void (*TdcChainFn) (void *arg, uint64 first, uint32 k);

/*
 * Vertices collected from geometry values: interleaved x,y (what the core
 * takes) plus, for XYZ input, one Z per vertex.  The arrays are mappings
 * that belong to "cxt" (see pointbuf.c), so a buffer may exceed 1 GB.
 * "curves" and "chain" are the owner's to set after tdc_pointbuf_init
 * (which refuses curves and sets no chain function).
 */
typedef struct TdcPointBuf
{
	MemoryContext cxt;
	TdcPointMap *map;			/* NULL while the arrays are small (palloc) */
	double	   *xy;				/* 2 * cap doubles */
	double	   *z;				/* cap doubles when hasz, else NULL */
	uint64		n;				/* vertices stored */
	uint64		cap;			/* vertices allocated */
	bool		have_first;		/* srid and hasz come from a first input */
	bool		hasz;
	int32		srid;
	uint64		side_bytes;		/* the owner's arrays beside the vertices */
	TdcCurves	curves;
	TdcChainFn	chain;			/* NULL: chains are not reported */
	void	   *chain_arg;
} TdcPointBuf;

/*
 * A geometry value that arrives in pieces, front to back: next() sets *data
 * and *len to the next piece, valid until the following call, or returns
 * false after the last.  The pieces add up to "size" bytes, the value
 * without its varlena header.  toast_stream.c reads big TOASTed values this
 * way, a slice at a time.
 */
typedef struct TdcGserSource
{
	bool		(*next) (struct TdcGserSource *src, const char **data, Size *len);
	uint64		size;
	Datum		whole;			/* the value itself, to stroke it if it has curves */
} TdcGserSource;

/* pointbuf.c */
extern void tdc_pointbuf_init(TdcPointBuf *buf, MemoryContext cxt);
extern void tdc_pointbuf_reserve(TdcPointBuf *buf, uint64 extra,
								 const char *fname);
extern uint64 tdc_pointbuf_bytes(const TdcPointBuf *buf);
extern uint64 tdc_pointbuf_bytes_after(uint64 n, bool hasz);
extern void tdc_pointbuf_side_grow(TdcPointBuf *buf, uint64 old_bytes,
								   uint64 new_bytes, const char *what,
								   const char *fname);
extern void tdc_pointbuf_check_meta(TdcPointBuf *buf, int32 srid, bool hasz,
									const char *fname);
extern void tdc_pointbuf_append_buf(TdcPointBuf *dst, const TdcPointBuf *src,
									const char *fname);

/* gser_read.c */
extern bool tdc_gser_append(TdcPointBuf *buf, const struct varlena *geom,
							const char *fname);
extern bool tdc_gser_append_source(TdcPointBuf *buf, TdcGserSource *src,
								   const char *fname);

/* toast_stream.c: any geometry argument, TOASTed or not; a TIN's sample (with Z) */
extern bool tdc_read_geometry(TdcPointBuf *buf, Datum d, const char *fname);
extern void tdc_tin_read_sample(TdcPointBuf *buf, Datum d, int64 row, const char *fname);

/* curves.c */
extern struct varlena *tdc_curve_to_line(Datum geom, const char *fname);

/* gser_write.c */
extern float tdc_float_down(double d);
extern float tdc_float_up(double d);
extern uint64 tdc_gser_result_size(const tdc_job *job, int flags, bool hasz);
extern uint64 tdc_gser_result_bound(uint64 n, int flags, bool hasz);
extern struct varlena *tdc_gser_result(const tdc_job *job, int flags,
									   const TdcPointBuf *buf,
									   const char *fname);

/* A result value being written: member k starts at members + k * member_size. */
typedef struct TdcGserWriter
{
	const tdc_job *job;
	const TdcPointBuf *buf;
	int			flags;
	bool		hasz;
	char	   *members;
	uint64		member_size;
	uint64		count;
	const char *fname;
} TdcGserWriter;

extern struct varlena *tdc_gser_result_alloc(const tdc_job *job, int flags,
											 const TdcPointBuf *buf,
											 const char *fname,
											 TdcGserWriter *w);
extern void tdc_gser_emit(void *arg, size_t first, size_t count,
						  const uint32 *v);
extern void tdc_gser_fill(const TdcGserWriter *w);
extern struct varlena *tdc_gser_empty(int flags, int32 srid);
extern struct varlena *tdc_gser_edge_list(const tdc_job *job, const TdcPointBuf *buf,
										  uint64 count,
										  bool (*next) (void *arg, uint32 v[2]),
										  void *arg, const char *fname);
extern Size tdc_gser_triangle_size(bool hasz);
extern void tdc_gser_write_triangle(struct varlena *out, const tdc_job *job,
									const uint32 v[3], const TdcPointBuf *buf);
extern void tdc_gser_write_triangle_coords(struct varlena *out, const double *v,
										   int dim, int32 srid);
extern void tdc_gser_check_result_size(uint64 size, const char *fname);
extern void tdc_advise_result(void *out, Size size);

/* agg_state.c: the state of the ST_TDCDelaunay aggregates */
#define TDC_AGG_NAME		"ST_TDCDelaunay"

typedef struct TdcAggState
{
	TdcPointBuf pts;
	bool		params_set;
	double		tolerance;
	int32		flags;
	struct TdcPcSource *pc;		/* pcpatch rows: their format (pcpatch_source.c) */
} TdcAggState;

extern TdcAggState *tdc_agg_state_new(MemoryContext cxt);
extern void tdc_agg_state_set_params(TdcAggState *st, double tolerance,
									 int32 flags);
extern void tdc_agg_state_merge(TdcAggState *dst, const TdcAggState *src);
extern bytea *tdc_agg_state_serialize(const TdcAggState *st);
extern TdcAggState *tdc_agg_state_deserialize(const bytea *in,
											  MemoryContext cxt);

/* formats/pcpatch_source.c: pgpointcloud patches into a point buffer (its X, Y, Z) */
extern void tdc_pc_read_patch(TdcAggState *st, FmgrInfo *flinfo, Datum patch, text *filter,
							  const char *fname);
extern void tdc_pc_append_patch(TdcPointBuf *buf, struct TdcPcSource **srcp, MemoryContext cxt,
								FmgrInfo *flinfo, Datum patch, const char *ftext, const char *what,
								const char *fname);
extern text *tdc_pc_filter_arg(FunctionCallInfo fcinfo, int geometry_nargs);

/*
 * The serialized form of an aggregate whose state holds a TdcAggState plus
 * a part of its own, which follows the vertices (see agg_state.c).
 */
typedef struct TdcStateFormat
{
	uint32		magic;
	uint32		version;
	const char *fname;			/* the aggregate, in errors */
	const char *hint;			/* for a state too large to pass on */
	int32		more_flags;		/* TDC_OUT_CONSTRAINTS: takes the constrained
								 * functions' flags (tdc_flags_valid); -1: not */
} TdcStateFormat;

extern bytea *tdc_agg_state_serialize_with(const TdcAggState *st,
										   const TdcStateFormat *fmt,
										   const void *extra, Size extra_len,
										   const char *contents);
extern TdcAggState *tdc_agg_state_deserialize_with(const bytea *in,
												   const TdcStateFormat *fmt,
												   MemoryContext cxt,
												   const char **extra,
												   Size *extra_len);
/* ERROR: "fname: corrupt serialized aggregate state: what" */
extern pg_noreturn void tdc_agg_state_corrupt(const char *fname, const char *what);
/* states with parameters and a row count (the TIN aggregates') */
extern void tdc_agg_state_check_unset(const TdcAggState *st, bool params_set, int64 rows,
									  const char *fname);
extern void tdc_agg_rows_add(int64 *rows, int64 more, const char *fname);

/* fn_delaunay_agg.c, for the support functions of every aggregate */
extern MemoryContext tdc_agg_context(FunctionCallInfo fcinfo, const char *fn);
extern bool tdc_agg_arg_is_constant(FunctionCallInfo fcinfo, int argno);

/* run.c */
typedef struct TdcRun
{
	tdc_job    *job;			/* NULL once freed */
	bool		kept;			/* its arrays come from the backend's cache */
	uint64		engine_bytes;	/* the engine's estimate, for tdc_run_free */
} TdcRun;

/*
 * Work on the core's threads that the backend waits for (a job phase, a
 * Voronoi diagram, a constrained insertion), as the core offers each:
 * wait() as tdc_job_wait, cancel() as tdc_job_cancel, error() as
 * tdc_job_error, free() as tdc_job_free; "what" names it in the cancel
 * message.
 */
typedef struct TdcWorkOps
{
	int			(*wait) (void *work, int timeout_ms);
	void		(*cancel) (void *work);
	const char *(*error) (const void *work);
	void		(*free) (void *work);
	const char *what;
} TdcWorkOps;

/*
 * "static const TdcWorkOps name" for a core type whose functions are
 * prefix_wait, prefix_cancel, prefix_error and prefix_free (tdc_job,
 * tdc_voronoi, tdc_cdt), through adapters that take void *.
 */
#define TDC_WORK_OPS(name, type, prefix, what) \
static int name##_wait(void *w, int ms) { return prefix##_wait((type *) w, ms); } \
static void name##_cancel(void *w) { prefix##_cancel((type *) w); } \
static const char *name##_error(const void *w) { return prefix##_error((const type *) w); } \
static void name##_free(void *w) { prefix##_free((type *) w); } \
static const TdcWorkOps name = {name##_wait, name##_cancel, name##_error, name##_free, what}

extern int	tdc_wait_work(void *work, const TdcWorkOps *ops, const char *fname);
extern void tdc_finish_work(void **workp, const TdcWorkOps *ops, const char *fname);
extern pg_noreturn void tdc_report_status(int rc, const char *msg, const char *fname);

extern void tdc_check_flags(int flags, bool constraints, const char *fname);
extern void tdc_check_tolerance(bool isnull, double tolerance, const char *fname);
extern void tdc_check_params(double tolerance, int flags, const char *fname);
/* the threads a triangulation starts now: the settings within the CPUs */
extern int	tdc_effective_threads(void);
extern void tdc_session_options(tdc_options *opt);
extern void tdc_check_run_memory(const TdcPointBuf *buf, double tolerance,
								 uint64 result_bytes, const char *fname);
extern TdcRun *tdc_run(const TdcPointBuf *buf, double tolerance,
					   uint64 result_bytes, const char *fname);
extern bool tdc_run_emit(TdcRun *run, tdc_emit_fn emit, void *arg,
						 const char *fname);
extern void tdc_run_free(TdcRun *run);

/* What the stats NOTICE reports of a finished job, kept past its free. */
typedef struct TdcRunStats
{
	size_t		input;
	size_t		sites;
	size_t		triangles;
	size_t		edges;
	int			threads;
	int			levels;
	int			grid;
	tdc_times	t;
} TdcRunStats;

extern void tdc_stats_take(const tdc_job *job, TdcRunStats *st);
extern void tdc_stats_report(const TdcRunStats *st, const char *fname,
							 const char *phases);
extern double tdc_ms_since(instr_time start);

/* fn_delaunay.c */
struct ReturnSetInfo;
extern void tdc_dump_triangles(struct ReturnSetInfo *rsinfo, TdcRun *run,
							   const TdcPointBuf *buf);
extern Datum tdc_triangulate_to_datum(const TdcPointBuf *buf, double tolerance,
									  int flags, const char *fname);

/* dump_query.c */

/* The row id of every collected vertex: id[k] for vertex k. */
typedef struct TdcIdBuf
{
	int64	   *id;
	Size		n;
	Size		cap;
} TdcIdBuf;

/*
 * Called for each non-NULL geometry of the query after its vertices were
 * appended to buf, the first of them at index "first" (the constrained
 * Dump makes the row's chains segments this way).
 */
typedef void (*TdcDumpRowFn) (void *arg, uint64 first);

extern void tdc_dump_collect(TdcPointBuf *buf, TdcIdBuf *ids, const char *query,
							 Oid geomoid, const char *fname,
							 TdcDumpRowFn row_fn, void *row_arg);

/* A row's tag, the query's second column, and what the column is. */
typedef struct TdcDumpTag
{
	Datum		value;
	bool		isnull;
	Oid			typid;
	int32		typmod;
	const char *name;
} TdcDumpTag;

/* What a tagged collection calls: once with the tag column (or NULL), then per row. */
typedef struct TdcDumpTagOps
{
	void		(*columns) (void *arg, const TdcDumpTag *tag);
	void		(*row) (void *arg, uint64 first, const TdcDumpTag *tag);
} TdcDumpTagOps;

extern void tdc_dump_collect_tagged(TdcPointBuf *buf, const char *query, Oid geomoid,
									const char *fname, const TdcDumpTagOps *ops, void *arg);

/*
 * A query's column of pgpointcloud patches (a tiled procedure's pcpatch
 * source): the filter ('dimension=value[,...]', NULL: none), and the
 * format the first patch fixes, allocated in cxt.
 */
typedef struct TdcPcColumn
{
	const char *filter;
	MemoryContext cxt;
	struct TdcPcSource *src;
} TdcPcColumn;

extern void tdc_dump_collect_pc(TdcPointBuf *buf, const char *query, Oid coltype, TdcPcColumn *pc,
								const char *fname, TdcDumpRowFn row_fn, void *row_arg);
extern void tdc_dump_collect_tagged_pc(TdcPointBuf *buf, const char *query, Oid coltype, TdcPcColumn *pc,
									   const char *fname, const TdcDumpTagOps *ops, void *arg);

/*
 * seglist.c: segments as pairs of vertex indices into buf, taken from the
 * chains the reader reports (every linestring and polygon ring) once
 * tdc_seg_init has made buf report them to the list.
 */
typedef struct TdcSegList
{
	MemoryContext cxt;
	TdcPointBuf *buf;
	const char *fname;
	uint32	   *seg;
	uint64		nseg;
	uint64		cap;
	uint64	   *chain;			/* (first, k) pairs noted, not yet segments */
	Size		nchain;
	Size		chaincap;
} TdcSegList;

/* An insertion of segments into a job, freed before the job on an error. */
typedef struct TdcCdtHold
{
	tdc_cdt    *cdt;
} TdcCdtHold;

extern void tdc_seg_init(TdcSegList *l, MemoryContext cxt, TdcPointBuf *buf,
						 const char *fname);
extern void tdc_seg_reserve(TdcSegList *l, uint64 more);
extern void tdc_seg_flush(TdcSegList *l);
extern void tdc_seg_append(TdcSegList *dst, const TdcSegList *src, uint64 base);
extern void tdc_seg_read(TdcSegList *l, const char *data, Size len, uint64 n);
extern TdcCdtHold *tdc_constrain(TdcRun *run, const TdcPointBuf *buf,
								 const TdcSegList *w, const char *fname);
extern void tdc_constrain_release(TdcCdtHold *hold);

/* tin_run.c: a TIN of the samples, and the operations on it */
typedef struct TdcTinRun
{
	TdcRun	   *run;			/* the triangulation */
	tdc_tin    *tin;			/* NULL once freed */
	size_t		max_memory;		/* the TIN's and its operations' share (0: no limit) */
} TdcTinRun;

extern TdcTinRun *tdc_tin_run_start(const TdcPointBuf *buf, const TdcSegList *breaklines,
									uint64 extra, const char *fname);
extern void tdc_tin_run_wait(TdcTinRun *tr, int rc, const char *err, const char *fname);
extern void tdc_tin_run_free(TdcTinRun *tr);

/* tin_agg.c: the samples every TIN aggregate's state begins with */
typedef struct TdcTinAgg
{
	TdcAggState *base;			/* the vertices, with heights */
	int64		rows;			/* non-NULL rows read */
	bool		params_set;		/* the first row's parameters are kept */
	bool		breaklines;		/* segs holds the samples' linework */
	TdcSegList	segs;
} TdcTinAgg;

/* copies src's parameters into dst, or checks that they are dst's */
typedef void (*TdcTinAggParams) (TdcTinAgg *dst, const TdcTinAgg *src, MemoryContext cxt);

/*
 * What one TIN aggregate's serial, deserial and combine functions need to
 * know of it (tin_agg.c explains the shared form).  Its parameters come
 * after the vertices: a fixed part (the set flag, a uint32 at 0, and the
 * int64 rows at rows_at are tin_agg.c's; the rest the kind's), then
 * var_len bytes more.
 */
typedef struct TdcTinAggKind
{
	const TdcStateFormat *fmt;	/* magic, version, the aggregate's name */
	Size		size;			/* its state, which begins with a TdcTinAgg */
	TdcCurves	curves;			/* how it reads a curved sample */
	Size		fixed;			/* the parameters' fixed part, in bytes */
	Size		rows_at;		/* where the rows lie in it */
	TdcTinAggParams params;		/* the combine function's reconciliation */
	/* the length of the variable part (0 when the parameters are unset) */
	Size		(*var_len) (const TdcTinAgg *a);
	/* the parameters into their zeroed part, but for the flag and the rows */
	void		(*write) (const TdcTinAgg *a, char *extra);

	/*
	 * The parameters from the len bytes of extra, whose flag and rows are
	 * read: checks them (tdc_agg_state_corrupt), sets the breaklines, and
	 * returns their length; the segments follow.
	 */
	Size		(*read) (TdcTinAgg *a, const char *extra, Size len);
} TdcTinAggKind;

extern TdcTinAgg *tdc_tin_agg_new(MemoryContext cxt, Size size, TdcCurves curves);
extern void tdc_tin_agg_breaklines(TdcTinAgg *a, bool breaklines, MemoryContext cxt,
								   const char *fname);
extern void tdc_tin_agg_add(TdcTinAgg *a, Datum geom, const char *fname);
extern void tdc_tin_agg_add_patch(TdcTinAgg *a, FmgrInfo *flinfo, Datum patch, text *filter,
								  const char *fname);
extern Datum tdc_tin_agg_serialfn(FunctionCallInfo fcinfo, const TdcTinAggKind *k,
								  const char *fn);
extern Datum tdc_tin_agg_deserialfn(FunctionCallInfo fcinfo, const TdcTinAggKind *k,
									const char *fn);
extern Datum tdc_tin_agg_combinefn(FunctionCallInfo fcinfo, const TdcTinAggKind *k,
								   const char *fn);

/*
 * The SQL entry points prefix_combinefn, prefix_serialfn and
 * prefix_deserialfn of a TIN aggregate (st_tdccontours_combinefn, ...: the
 * names its SQL scripts give), over tin_agg.c's functions for kind.  Used
 * as a declaration, with a semicolon (as PG_FUNCTION_INFO_V1 is).
 */
#define TDC_TIN_AGG_SUPPORT(prefix, kind) \
PG_FUNCTION_INFO_V1(prefix##_combinefn); \
Datum prefix##_combinefn(PG_FUNCTION_ARGS) \
{ return tdc_tin_agg_combinefn(fcinfo, &(kind), #prefix "_combinefn"); } \
PG_FUNCTION_INFO_V1(prefix##_serialfn); \
Datum prefix##_serialfn(PG_FUNCTION_ARGS) \
{ return tdc_tin_agg_serialfn(fcinfo, &(kind), #prefix "_serialfn"); } \
PG_FUNCTION_INFO_V1(prefix##_deserialfn); \
Datum prefix##_deserialfn(PG_FUNCTION_ARGS) \
{ return tdc_tin_agg_deserialfn(fcinfo, &(kind), #prefix "_deserialfn"); } \
extern int	no_such_variable

/* gser_contour.c: the contour lines of a TIN as a MULTILINESTRING Z */
extern struct varlena *tdc_gser_contours(const tdc_tin *tin, int32 srid, uint64 room,
										 const char *fname);

/* gser_drape.c: a target geometry's vertices, and the target draped */
typedef struct TdcDrapeTarget
{
	const struct varlena *value;	/* detoasted */
	int32		srid;
	bool		hasm;
	double	   *xy;				/* its vertices */
	double	   *m;				/* their M, when hasm */
	size_t	   *chain_end;		/* chains as tdc_tin_drape_start takes them */
	size_t		nchains;
	size_t		nvert;
} TdcDrapeTarget;

extern void tdc_drape_target_read(TdcDrapeTarget *t, const struct varlena *value,
								  const char *fname);
extern uint64 tdc_drape_target_bytes(const TdcDrapeTarget *t);
extern struct varlena *tdc_drape_target_write(const TdcDrapeTarget *t,
											  const tdc_drape_vertex *v,
											  const size_t *chain_off, uint64 room,
											  const char *fname);

/* table_write.c: triangles inserted straight into a table just created */
typedef struct TdcTableWriter
{
	struct RelationData *rel;
	struct TupleTableSlot **slots;	/* a batch of rows, each with its own value */
	struct varlena **geoms;
	int			nbatch;
	MemoryContext batch_cxt;	/* what an insert allocates, reset after each batch */
	struct BulkInsertStateData *bistate;
	CommandId	cid;
	Oid			geomoid;		/* the geom column's type */
	Oid			tiletype;		/* the tile column's type and typmod */
	int32		tiletypmod;
	int			dim;
	int32		srid;
	uint64		rows;
} TdcTableWriter;

extern void tdc_table_writer_open(TdcTableWriter *tw, Oid relid, const char *fname);
extern void tdc_table_writer_shape(TdcTableWriter *tw, int dim, int32 srid, const char *fname);
extern void tdc_table_writer_put(TdcTableWriter *tw, int64 id, Datum tile, const double *v);
extern void tdc_table_writer_close(TdcTableWriter *tw);

/*
 * tile_values.c: the values of a tile column as dense labels, numbered as
 * first seen, then ranked 1.. in the type's order (equal values one rank).
 */
struct tvhash_hash;
struct SortSupportData;
typedef struct TdcTileValues
{
	MemoryContext cxt;
	Oid			typid;
	int32		typmod;
	int16		typlen;
	bool		typbyval;
	Oid			lt_opr;			/* the type's default btree "<" */
	Oid			collation;		/* the type's */
	struct tvhash_hash *hash;	/* value -> number */
	Datum	   *values;			/* number -> value (a copy in cxt) */
	uint32		n,
				cap;
	bool		have_last;		/* the last value looked up, for runs of rows in one tile */
	Datum		last;
	uint32		last_number;
	uint64		bytes;			/* what all of it holds, for the memory checks */
	/* after tdc_tile_values_rank */
	struct SortSupportData *sort;
	uint32	   *rank;			/* number -> rank from 1 */
	Datum	   *by_rank;		/* rank -> value */
	int64	   *count;			/* rank -> rows written so far (the caller's) */
	uint32		nranks;
} TdcTileValues;

extern void tdc_tile_values_init(TdcTileValues *tv, MemoryContext cxt, Oid typid, int32 typmod,
								 const char *column, const char *fname);
extern uint32 tdc_tile_values_number(TdcTileValues *tv, Datum d);
extern void tdc_tile_values_rank(TdcTileValues *tv, const char *fname);

/* The tiled procedure's name in messages (fn_tiled*.c). */
#define TILED_FNAME		"tdc_delaunay_tiled"

/* fn_tiled_region.c: a square's label, an ERROR when it has none */
extern int64 tdc_tiled_square_label(double x, double y, const double origin[2], double size);

/* signals.c */
extern bool tdc_signal_settled;
extern void tdc_signal_settle(void);

/* First thing in every SQL entry point: see signals.c. */
static inline void
tdc_signal_guard(void)
{
	if (unlikely(!tdc_signal_settled))
		tdc_signal_settle();
}

#endif							/* TDC_PG_H */
