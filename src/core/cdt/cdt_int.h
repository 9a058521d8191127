/*
 * cdt_int.h
 *		The state of a constraint insertion, shared by cdt.c (sharing the
 *		segments out, the lifecycle) and cdt_insert.c (one segment).  Not
 *		installed.
 */
#ifndef TDC_CDT_INT_H
#define TDC_CDT_INT_H

#include "engine/mesh_view.h"

/* cons[] holds segment number + 1, so that the zeroed array means "none" */
#define NO_SEG		0					/* edge is no constraint */
#define CAV			UINT32_MAX			/* new edge of the current cavity */
#define CAVQ		(UINT32_MAX - 1)	/* ... and on the Lawson stack */
#define MAX_SEG		((size_t) UINT32_MAX - 3)
#define POLL_STEPS	4096

/*
 * The parallel pass: NPART vertical stripes of equal width over the sites'
 * x range, a number fixed so that the work, the mesh and the error reported
 * are the same for every thread count.  Below PART_MIN_SEG segments the
 * pass would cost more than it saves.
 */
#define NPART		16
#define PART_MIN_SEG 8192
#define PART_CAP	4096			/* crossed edges a stripe's walk may list */
#define LIST_MIN	4096			/* the serial lists' first size */
#define SEG_SERIAL	0xfe			/* seg_part[]: ends in two stripes */
#define SEG_NONE	0xff			/* ... both ends on one site */
#define TDC_DEFER	1				/* insert_segment: leave it to the serial pass */

/*
 * One inserter: the serial one (part < 0, any site), or the one of stripe
 * "part" in the parallel pass, which may only touch triangles whose three
 * corners lie in its stripe.  Each has its own lists, poll counter and
 * error, so inserters of different stripes share nothing they write.
 */
typedef struct cdt_ctx
{
	struct tdc_cdt *c;
	int			part;			/* stripe, or -1: serial */
	uint32_t   *list;			/* crossed edges, used as a circular queue */
	uint32_t   *fresh;			/* new edges, then the Lawson stack */
	size_t		cap;
	size_t		nconstraint;	/* constraint edges this inserter made */
	size_t		ndone;			/* a stripe's: segments it inserted */
	size_t		ndeferred;		/* ... and left to the serial pass */
	size_t		cross[2];		/* the two segments of a TDC_ECROSS */
	long		steps;
	int			rc;
	char		err[512];
} cdt_ctx;

struct tdc_cdt
{
	tdc_job    *job;			/* opaque (tdc.h): its accessors, the input map,
								 * the writable mesh (mesh_view.h) */
	tdc_mesh_view mesh;			/* what the insertion reads of it */
	tdc_cache  *cache;			/* the job's, kept: the job may be freed first */
	const uint32_t *seg;		/* caller's pairs of input indices */
	size_t		nseg;
	tdc_mesh	m;				/* the same mesh, writable: the flips
								 * (tdc_job_edit_mesh, mesh_view.h) */
	uint32_t   *cons;			/* per edge slot: segment number + 1, or NO_SEG/CAV/CAVQ */
	uint32_t   *vedge;			/* per site: a half-edge leaving it */
	uint32_t   *list;			/* the serial inserter's lists (grow_lists) */
	uint32_t   *fresh;
	size_t		nslots;			/* edge slots: the most any list needs */
	uint32_t   *part_lists;		/* the stripes' lists, PART_CAP each, 2 per stripe */
	size_t		nconstraint;	/* constraint edges */
	size_t		cross[2];		/* the two segments of a TDC_ECROSS */
	size_t		npar_done;		/* segments the stripes inserted */
	size_t		npar_deferred;	/* ... and left to the serial pass */
	size_t		npar_serial;	/* segments with ends in two stripes */

	/* the parallel pass (only for at least PART_MIN_SEG segments) */
	uint8_t    *spart;			/* per site: its stripe (x_part) */
	uint8_t    *seg_part;		/* per segment: its stripe, SEG_SERIAL or SEG_NONE */
	uint8_t    *seg_done;		/* per segment: inserted by its stripe's inserter */
	uint32_t   *order;			/* the segments of stripe 0, then of 1, ..., each in input order */
	size_t		part_off[NPART + 2];	/* stripe k's: order[part_off[k] .. part_off[k + 1]);
										 * k = NPART: those with ends in two stripes */
	double		part_x0;		/* stripe of x: (x - part_x0) * part_scale */
	double		part_scale;
	cdt_ctx    *parts;			/* NPART inserters */
	cdt_ctx		serial;

	atomic_int	cancel;
	bool		inline_run;
	tdc_runner	run;			/* the job's lifecycle (runner.c) */
	char		err[512];
};

/* The stripe of site v: a function of its x alone, never of the threads. */
static inline int
site_part(const tdc_cdt *c, uint32_t v)
{
	return c->spart[v];
}

/* The stripe of an x coordinate. */
static inline uint8_t
x_part(const tdc_cdt *c, double x)
{
	double		t = (x - c->part_x0) * c->part_scale;

	if (!(t > 0))
		return 0;
	if (t >= NPART)
		return NPART - 1;
	return (uint8_t) t;
}

/* cdt_insert.c: x's error: its message from fmt, returns code. */
extern int	tdc_cdt_ctx_fail(cdt_ctx *x, int code, const char *fmt,...)
			__attribute__((format(printf, 3, 4)));

/* cdt_insert.c: TDC_EINVAL for an internal inconsistency at segment s. */
extern int	tdc_cdt_internal_error(cdt_ctx *x, size_t s, const char *what);

/* cdt_insert.c: the end sites of segment s, checked. */
extern int	tdc_cdt_seg_sites(cdt_ctx *x, size_t s, uint32_t *a, uint32_t *b);

/*
 * cdt_insert.c: insert segment s from site a to site b with inserter x
 * (TDC_OK, TDC_DEFER for a stripe's inserter that must leave it to the
 * serial pass, or an error with its message in x->err).
 */
extern int	tdc_cdt_insert_segment(cdt_ctx *x, size_t s, uint32_t a, uint32_t b);

/* cdt_insert.c: the status of inserter x, its message and crossing moved to c. */
extern int	tdc_cdt_take_error(tdc_cdt *c, const cdt_ctx *x, int rc);

#endif							/* TDC_CDT_INT_H */
