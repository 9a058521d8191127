/*
 * test_conformance.c
 *		Runs the public test cases of PostGIS, GEOS and delaunator (the
 *		repository's copy in test/fixtures, see its README.md) through the
 *		core.
 *
 * Design.  Nothing is copied out of the fixture files into this source: they
 * are read at run time and split into CASE blocks.  From each block the test
 * takes
 *	- the input point set: a WKT geometry after "input:" (every vertex of
 *	  every part becomes a site; numbers beyond x, y -- Z or M -- are
 *	  ignored), a JSON array of [x, y] pairs inline or in "file:", or a slice
 *	  "ukraine[a:b]";
 *	- the stats: uniqueXY (unique=), exact_T and hull_incl_collinear;
 *	- the tolerance, when the input or an expected line gives one;
 *	- every expected geometry: GEOMETRYCOLLECTION / TIN of triangles,
 *	  MULTILINESTRING of edges, or a stated triangle count ("N triangles").
 * A handful of blocks need a few lines of help (the SQL-built polygon plus
 * buffer, the stroked arc, the bare coordinate list of GEOS test 9, the
 * scaled robustness fixture); blocks that only concern the SQL layer (NULL,
 * flags, SRID, error text) are listed in sql_only_cases[].  Any other block
 * without a usable input counts as a failure, so no case is skipped silently;
 * so does a file with another number of blocks than the copy holds, and a
 * case that ran no check.  The summary line counts cases passed and failed.
 *
 * Every run is checked for: status TDC_OK; consistent site ids (each input
 * maps to a kept site with its own coordinates, or one within the tolerance);
 * the number of unique sites and of triangles against the stats (tolerance
 * 0 only); the exact validator tdc_validate(); the edge iterator against the
 * triangles' edges; and, independently of the validator, that the boundary
 * of the triangles is exactly the convex hull including collinear hull
 * sites, with as many sites as the file's hull_incl_collinear says.
 *
 * Expected triangle and edge sets are compared exactly, as sets of
 * coordinates (each triangle rotated counter-clockwise from its smallest
 * (x, y) vertex), but only when the answer is unique: no site lies exactly
 * on the circumcircle of a result triangle (tested with the exact
 * tdc_incircle).  Where sites are cocircular, a fixture's set is one valid
 * answer among several, so only counts are compared.  An expected set that
 * is itself not an exact Delaunay triangulation of the sites (older GEOS
 * missing hull triangles) is reported as a note and the exact result stays
 * the reference.
 *
 * The delaunator fixtures (and, as it is cheap, every other case of 3 or more
 * points) are also run with 1, 2, 4 and 8 threads, with no, 1 and 3
 * subdivision levels, with grids of 16 and 1000, and with the input reversed:
 * the triangle set must not change.  --quick skips this for the fixtures
 * above 1000 points.  Finally bug_*() functions
 * named after the bugs the fixtures once exposed check the property each bug
 * broke.
 */
#include <ctype.h>
#include <math.h>
#include <stdbool.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "harness.h"
#include "engine/predicates.h"
#include "tdc.h"

#define MAX_EXPECTED	16
#define RUN_TIMEOUT_MS	120000	/* a run longer than this is "stuck" */

/* ------------------------------------------------------------------------
 * Small utilities
 * ------------------------------------------------------------------------
 */

static void *
xmalloc(size_t sz)
{
	void	   *p = malloc(sz ? sz : 1);

	if (p == NULL)
	{
		fprintf(stderr, "test_conformance: out of memory\n");
		abort();
	}
	return p;
}

static void *
xrealloc(void *p, size_t sz)
{
	p = realloc(p, sz ? sz : 1);
	if (p == NULL)
	{
		fprintf(stderr, "test_conformance: out of memory\n");
		abort();
	}
	return p;
}

/* growable array of doubles */
typedef struct dvec
{
	double	   *v;
	size_t		n;
	size_t		cap;
} dvec;

static void
dvec_push(dvec *a, double x)
{
	if (a->n == a->cap)
	{
		a->cap = a->cap ? 2 * a->cap : 64;
		a->v = xrealloc(a->v, a->cap * sizeof(double));
	}
	a->v[a->n++] = x;
}

/* growable array of sizes */
typedef struct svec
{
	size_t	   *v;
	size_t		n;
	size_t		cap;
} svec;

static void
svec_push(svec *a, size_t x)
{
	if (a->n == a->cap)
	{
		a->cap = a->cap ? 2 * a->cap : 16;
		a->v = xrealloc(a->v, a->cap * sizeof(size_t));
	}
	a->v[a->n++] = x;
}

static int
cmp_doubles(const double *a, const double *b, int k)
{
	for (int i = 0; i < k; i++)
	{
		if (a[i] < b[i])
			return -1;
		if (a[i] > b[i])
			return 1;
	}
	return 0;
}

static bool
xy_less(const double *a, const double *b)
{
	return cmp_doubles(a, b, 2) < 0;
}

static char *
read_whole_file(const char *dir, const char *name, size_t *len)
{
	char		path[1024];
	FILE	   *f;
	char	   *buf = NULL;
	size_t		n = 0,
				cap = 0,
				got;

	snprintf(path, sizeof path, "%s/%s", dir, name);
	f = fopen(path, "rb");
	if (f == NULL)
		return NULL;
	do
	{
		if (cap - n < 65536)
		{
			cap = cap ? 2 * cap : 65536;
			buf = xrealloc(buf, cap + 1);
		}
		got = fread(buf + n, 1, cap - n, f);
		n += got;
	} while (got > 0);
	fclose(f);
	buf[n] = '\0';
	if (len)
		*len = n;
	return buf;
}

/* ------------------------------------------------------------------------
 * WKT and JSON vertex extraction
 * ------------------------------------------------------------------------
 */

/*
 * Vertices of a geometry, and its innermost parenthesised groups ("rings"):
 * ring k holds vertices ring.v[k] .. ring.v[k + 1] - 1 (a final sentinel is
 * pushed by the parser).
 */
typedef struct wkt
{
	dvec		xy;
	svec		ring;
	bool		ok;
} wkt;

static void
wkt_free(wkt *g)
{
	free(g->xy.v);
	free(g->ring.v);
	memset(g, 0, sizeof(*g));
}

static const char *const wkt_words[] = {
	"GEOMETRYCOLLECTION", "MULTIPOINT", "MULTILINESTRING", "MULTIPOLYGON",
	"LINESTRING", "POLYGON", "POINT", "TIN", "CIRCULARSTRING", NULL
};

/*
 * Find the next WKT geometry in s: an upper-case type word on its own,
 * followed (after optional Z / M / ZM) by '(' or EMPTY.  Returns its start or
 * NULL; *word gets the type word.
 */
static const char *
find_wkt(const char *s, const char **word)
{
	for (const char *p = s; *p; p++)
	{
		if (p > s && (isalnum((unsigned char) p[-1]) || p[-1] == '_'))
			continue;
		for (int w = 0; wkt_words[w]; w++)
		{
			size_t		len = strlen(wkt_words[w]);
			const char *q = p + len;

			if (strncmp(p, wkt_words[w], len) != 0 ||
				isalnum((unsigned char) *q) || *q == '_')
				continue;
			while (*q == ' ')
				q++;
			if (strncmp(q, "ZM", 2) == 0 && !isalnum((unsigned char) q[2]))
				q += 2;
			else if ((*q == 'Z' || *q == 'M') && !isalnum((unsigned char) q[1]))
				q++;
			while (*q == ' ')
				q++;
			if (*q == '(' || (strncmp(q, "EMPTY", 5) == 0))
			{
				*word = wkt_words[w];
				return p;
			}
		}
	}
	return NULL;
}

/*
 * Parse the geometry starting at s (a type word or a bare '(').  Every
 * vertex is a run of 2 to 4 numbers ended by ',' or ')'; x and y are kept.
 * Returns the position after the geometry.
 */
static const char *
parse_wkt(const char *s, wkt *g)
{
	const char *p = s;
	int			depth = 0;
	size_t		ring_start = 0;
	double		num[4];
	int			nnum = 0;

	memset(g, 0, sizeof(*g));
	g->ok = true;
	while (*p && *p != '(')
	{
		if (strncmp(p, "EMPTY", 5) == 0)
		{
			svec_push(&g->ring, 0);
			return p + 5;
		}
		p++;
	}
	for (; *p; p++)
	{
		char		c = *p;

		if (c == '(')
		{
			depth++;
			ring_start = g->xy.n / 2;
		}
		else if (c == ',' || c == ')')
		{
			if (nnum >= 2)
			{
				dvec_push(&g->xy, num[0]);
				dvec_push(&g->xy, num[1]);
			}
			else if (nnum == 1)
				g->ok = false;
			nnum = 0;
			if (c == ')')
			{
				if (g->xy.n / 2 > ring_start)
				{
					svec_push(&g->ring, ring_start);
					ring_start = g->xy.n / 2;
				}
				if (--depth == 0)
				{
					p++;
					break;
				}
			}
		}
		else if (isdigit((unsigned char) c) || c == '-' || c == '+' || c == '.')
		{
			char	   *end;
			double		x = strtod(p, &end);

			if (end == p || nnum == 4)
				g->ok = false;
			else
				num[nnum++] = x;
			p = end - 1;
		}
		/* letters (Z, M, type words of parts), blanks: skip */
	}
	if (depth != 0)
		g->ok = false;
	svec_push(&g->ring, g->xy.n / 2);
	return p;
}

/* All numbers of a JSON array of [x, y] pairs. */
static bool
parse_json_pairs(const char *s, dvec *xy)
{
	const char *p = s;

	while (*p && *p != '[')
		p++;
	for (; *p; p++)
	{
		if (isdigit((unsigned char) *p) || *p == '-' || *p == '+' || *p == '.')
		{
			char	   *end;
			double		x = strtod(p, &end);

			if (end == p)
				return false;
			dvec_push(xy, x);
			p = end - 1;
		}
	}
	return xy->n % 2 == 0;
}

/* ------------------------------------------------------------------------
 * Case blocks
 * ------------------------------------------------------------------------
 */

typedef struct ccase
{
	char		name[128];
	const char *source;			/* cases file */
	char	   *text;			/* whole block */
	char	   *input;			/* text after "input:" (to end of line) */
	char	   *fileref;		/* delaunator "file:" */
	char	   *expected[MAX_EXPECTED];	/* expected line + continuations */
	int			nexpected;
	long		unique;			/* -1: not given */
	long		exact_t;
	long		hull;
	double		tol;
} ccase;

static ccase *cases;
static int	ncases;
static const char *conf_dir;
static bool verbose;			/* TDC_TEST_VERBOSE set: one line per check group */

static char *
dup_range(const char *a, const char *b)
{
	char	   *s = xmalloc(b - a + 1);

	memcpy(s, a, b - a);
	s[b - a] = '\0';
	return s;
}

static long
stat_after(const char *text, const char *key)
{
	const char *p = text;

	while ((p = strstr(p, key)) != NULL)
	{
		if (p == text || !isalnum((unsigned char) p[-1]))
		{
			p += strlen(key);
			if (strncmp(p, "2n-2-h=", 7) == 0)
				p += 7;
			if (isdigit((unsigned char) *p))
				return strtol(p, NULL, 10);
		}
		else
			p++;
	}
	return -1;
}

/* Tolerance from "tolerance=X", "tolerance X" or "tol X" in s (-1: none). */
static double
tolerance_in(const char *s)
{
	static const char *const keys[] = {"tolerance=", "tolerance ", "tol ", NULL};

	for (int k = 0; keys[k]; k++)
	{
		const char *p = s;

		while ((p = strstr(p, keys[k])) != NULL)
		{
			p += strlen(keys[k]);
			if (isdigit((unsigned char) *p) || *p == '.')
				return strtod(p, NULL);
		}
	}
	return -1;
}

static const char *
skip_blanks(const char *p)
{
	while (*p == ' ' || *p == '\t')
		p++;
	return p;
}

/* Split one cases file into blocks starting at lines "CASE name". */
static void
split_cases(const char *source, char *buf)
{
	char	   *line = buf;
	ccase	   *cur = NULL;
	bool		in_expected = false;

	while (line && *line)
	{
		char	   *eol = strchr(line, '\n');
		char	   *next = eol ? eol + 1 : NULL;
		const char *t;
		char	   *l;

		if (eol)
			*eol = '\0';
		l = line;
		t = skip_blanks(l);
		if (strncmp(l, "CASE ", 5) == 0)
		{
			const char *a = l + 5,
					   *b = a;

			cases = xrealloc(cases, (ncases + 1) * sizeof(ccase));
			cur = &cases[ncases++];
			memset(cur, 0, sizeof(*cur));
			while (*b && !isspace((unsigned char) *b))
				b++;
			snprintf(cur->name, sizeof cur->name, "%.*s", (int) (b - a), a);
			cur->source = source;
			cur->text = strdup(l);
			cur->unique = cur->exact_t = cur->hull = -1;
			cur->tol = 0;
			in_expected = false;
		}
		else if (cur && (strncmp(l, "=====", 5) == 0 || strncmp(l, "-----", 5) == 0 ||
						 strncmp(l, "BEHAVIOUR", 9) == 0 || strncmp(l, "GEOS C-API", 10) == 0))
		{
			cur = NULL;
		}
		else if (cur)
		{
			size_t		tl = strlen(cur->text);

			cur->text = xrealloc(cur->text, tl + strlen(l) + 2);
			cur->text[tl] = '\n';
			strcpy(cur->text + tl + 1, l);

			if (strncmp(t, "input", 5) == 0)
			{
				const char *c = strchr(t, ':');

				if (c && cur->input == NULL)
					cur->input = strdup(skip_blanks(c + 1));
				in_expected = false;
			}
			else if (strncmp(t, "file:", 5) == 0)
			{
				const char *a = skip_blanks(t + 5),
						   *b = a;

				while (*b && !isspace((unsigned char) *b))
					b++;
				cur->fileref = dup_range(a, b);
				in_expected = false;
			}
			else if (strncmp(t, "expected", 8) == 0 && cur->nexpected < MAX_EXPECTED)
			{
				cur->expected[cur->nexpected++] = strdup(t);
				in_expected = true;
			}
			else if (in_expected && (isupper((unsigned char) *t)) &&
					 strchr(t, ':') == NULL)
			{
				/* continuation: the geometry on the line after its header */
				char	   *e = cur->expected[cur->nexpected - 1];
				size_t		el = strlen(e);

				e = xrealloc(e, el + strlen(t) + 2);
				e[el] = ' ';
				strcpy(e + el + 1, t);
				cur->expected[cur->nexpected - 1] = e;
			}
			else
				in_expected = false;
		}
		line = next;
	}

	/* stats and tolerance of the blocks of this file */
	for (int i = 0; i < ncases; i++)
	{
		ccase	   *c = &cases[i];
		double		tol = -1;

		if (c->source != source)
			continue;
		c->unique = stat_after(c->text, "uniqueXY=");
		if (c->unique < 0)
			c->unique = stat_after(c->text, "unique=");
		c->exact_t = stat_after(c->text, "exact_T=");
		c->hull = stat_after(c->text, "hull_incl_collinear=");
		if (c->input)
			tol = tolerance_in(c->input);
		for (int e = 0; e < c->nexpected && tol < 0; e++)
			tol = tolerance_in(c->expected[e]);
		c->tol = tol > 0 ? tol : 0;
	}
}

static ccase *
find_case(const char *name)
{
	for (int i = 0; i < ncases; i++)
		if (strcmp(cases[i].name, name) == 0)
			return &cases[i];
	return NULL;
}

/*
 * Input points of a case, as interleaved x, y.  Returns false when the block
 * has no input the core can take.
 */
static bool
case_points(const ccase *c, dvec *xy)
{
	memset(xy, 0, sizeof(*xy));
	if (c->fileref)
	{
		char	   *buf = read_whole_file(conf_dir, c->fileref, NULL);
		bool		ok;

		if (buf == NULL)
			return false;
		ok = parse_json_pairs(buf, xy);
		free(buf);
		return ok;
	}
	if (c->input == NULL)
		return false;
	if (c->input[0] == '[')
		return parse_json_pairs(c->input, xy);
	if (strncmp(c->input, "ukraine[", 8) == 0)
	{
		int			a,
					b;
		char	   *buf;
		dvec		all = {0};

		if (sscanf(c->input, "ukraine[%d:%d]", &a, &b) != 2)
			return false;
		buf = read_whole_file(conf_dir, "delaunator/ukraine.json", NULL);
		if (buf == NULL || !parse_json_pairs(buf, &all) || (size_t) b * 2 > all.n)
		{
			free(buf);
			free(all.v);
			return false;
		}
		for (int i = 2 * a; i < 2 * b; i++)
			dvec_push(xy, all.v[i]);
		free(buf);
		free(all.v);
		return true;
	}
	{
		const char *word;
		const char *p = find_wkt(c->input, &word);
		wkt			g;

		if (p == NULL)
			return false;
		parse_wkt(p, &g);
		if (!g.ok)
		{
			wkt_free(&g);
			return false;
		}
		*xy = g.xy;
		free(g.ring.v);
		return true;
	}
}

/* ------------------------------------------------------------------------
 * Running the core and collecting its result
 * ------------------------------------------------------------------------
 */

typedef struct result
{
	size_t		n;				/* input points */
	size_t		m;				/* kept sites */
	double	   *sites;			/* m x, y, in order of first input */
	size_t	   *site_input;		/* tdc_site_input of each */
	uint32_t   *input_site;		/* compact site of each input point */
	uint32_t   *tri;			/* ntri x 3, indices into sites */
	size_t		ntri;
	double	   *edges;			/* nedge x 4, from tdc_next_edge */
	size_t		nedge;
	size_t		api_edges;		/* tdc_num_edges */
} result;

static void
result_free(result *r)
{
	free(r->sites);
	free(r->site_input);
	free(r->input_site);
	free(r->tri);
	free(r->edges);
	memset(r, 0, sizeof(*r));
}

/*
 * Triangulate xy with opt and collect the result.  Checks the status and
 * the consistency of site ids; false when there is no usable result.
 */
static bool
run_core(const char *name, const double *xy, size_t n, const tdc_options *opt,
		 result *r)
{
	tdc_job    *job = NULL;
	char		err[512] = "";
	int			rc;
	uint32_t	limit;
	uint32_t   *map;
	uint32_t	v[3];
	tdc_iter	it;
	size_t		bad_id = 0,
				bad_xy = 0,
				bad_order = 0;
	double		tol2 = opt->tolerance * opt->tolerance;

	memset(r, 0, sizeof(*r));
	rc = tdc_job_start(xy, n, opt, &job, err, sizeof err);
	if (rc == TDC_OK)
	{
		rc = tdc_job_wait(job, RUN_TIMEOUT_MS);
		if (rc == TDC_RUNNING)
		{
			tdc_job_cancel(job);
			CHECK(false, "%s: no result after %d s (n=%zu, threads=%d, levels=%d, grid=%d): stuck?",
				  name, RUN_TIMEOUT_MS / 1000, n, opt->threads, opt->levels, opt->grid_size);
			tdc_job_free(job);
			return false;
		}
		if (rc != TDC_OK)
			snprintf(err, sizeof err, "%s", tdc_job_error(job));
	}
	CHECK(rc == TDC_OK, "%s: triangulation failed with status %d: %s (n=%zu, tolerance=%g, threads=%d, levels=%d, grid=%d)",
		  name, rc, err, n, opt->tolerance, opt->threads, opt->levels, opt->grid_size);
	if (rc != TDC_OK)
	{
		tdc_job_free(job);
		return false;
	}

	r->n = n;
	CHECK(tdc_num_input(job) == n, "%s: tdc_num_input %zu != %zu", name,
		  tdc_num_input(job), n);
	limit = tdc_site_id_limit(job);
	map = xmalloc((size_t) limit * sizeof(uint32_t) + 4);
	memset(map, 0xff, (size_t) limit * sizeof(uint32_t));
	r->sites = xmalloc(2 * n * sizeof(double) + 16);
	r->site_input = xmalloc(n * sizeof(size_t) + 8);
	r->input_site = xmalloc(n * sizeof(uint32_t) + 4);

	for (size_t i = 0; i < n; i++)
	{
		uint32_t	s = tdc_input_site(job, i);
		const double *p;
		double		dx,
					dy;

		if (s >= limit)
		{
			bad_id++;
			r->input_site[i] = UINT32_MAX;
			continue;
		}
		p = tdc_site_xy(job, s);
		if (map[s] == UINT32_MAX)
		{
			map[s] = (uint32_t) r->m;
			r->sites[2 * r->m] = p[0];
			r->sites[2 * r->m + 1] = p[1];
			r->site_input[r->m] = tdc_site_input(job, s);
			r->m++;
		}
		r->input_site[i] = map[s];
		dx = p[0] - xy[2 * i];
		dy = p[1] - xy[2 * i + 1];
		if (opt->tolerance > 0 ? !(dx * dx + dy * dy < tol2 || (dx == 0 && dy == 0))
			: (dx != 0 || dy != 0))
			bad_xy++;
	}
	CHECK(bad_id == 0, "%s: %zu input points map to site ids >= tdc_site_id_limit %u",
		  name, bad_id, limit);
	CHECK(bad_xy == 0, "%s: %zu input points map to a site at other coordinates%s",
		  name, bad_xy, opt->tolerance > 0 ? " (beyond the tolerance)" : "");
	for (size_t k = 0; k < r->m; k++)
	{
		size_t		i = r->site_input[k];

		if (i >= n || r->input_site[i] != k)
			bad_id++;
	}
	CHECK(bad_id == 0, "%s: tdc_site_input does not give an input point of the site", name);
	CHECK(tdc_num_sites(job) == r->m, "%s: tdc_num_sites %zu, but the inputs map to %zu sites",
		  name, tdc_num_sites(job), r->m);

	/* triangles */
	r->tri = xmalloc(3 * sizeof(uint32_t) * (tdc_num_triangles(job) + 1));
	it.pos = 0;
	bad_id = 0;
	while (tdc_next_triangle(job, &it, v))
	{
		bool		good = true;

		for (int k = 0; k < 3; k++)
			if (v[k] >= limit || map[v[k]] == UINT32_MAX)
				good = false;
		if (!good)
		{
			bad_id++;
			continue;
		}
		if (r->ntri > tdc_num_triangles(job))
		{
			bad_id++;
			break;
		}
		if (r->ntri == tdc_num_triangles(job))
			r->tri = xrealloc(r->tri, 3 * sizeof(uint32_t) * (r->ntri + 2));
		for (int k = 0; k < 3; k++)
			r->tri[3 * r->ntri + k] = map[v[k]];
		r->ntri++;
	}
	CHECK(bad_id == 0, "%s: the triangle iterator gave %zu triangles with unknown site ids",
		  name, bad_id);
	CHECK(r->ntri == tdc_num_triangles(job), "%s: iterated %zu triangles, tdc_num_triangles says %zu",
		  name, r->ntri, tdc_num_triangles(job));

	/* edges */
	r->api_edges = tdc_num_edges(job);
	r->edges = xmalloc(4 * sizeof(double) * (r->api_edges + 1));
	it.pos = 0;
	bad_id = 0;
	while (tdc_next_edge(job, &it, v))
	{
		const double *a,
				   *b;

		if (v[0] >= limit || v[1] >= limit || map[v[0]] == UINT32_MAX ||
			map[v[1]] == UINT32_MAX)
		{
			bad_id++;
			continue;
		}
		if (r->nedge > r->api_edges)
		{
			bad_id++;
			break;
		}
		if (r->nedge == r->api_edges)
			r->edges = xrealloc(r->edges, 4 * sizeof(double) * (r->nedge + 2));
		a = &r->sites[2 * map[v[0]]];
		b = &r->sites[2 * map[v[1]]];
		if (!xy_less(a, b))
			bad_order++;
		if (xy_less(b, a))
		{
			const double *t = a;

			a = b;
			b = t;
		}
		memcpy(&r->edges[4 * r->nedge], a, 2 * sizeof(double));
		memcpy(&r->edges[4 * r->nedge + 2], b, 2 * sizeof(double));
		r->nedge++;
	}
	CHECK(bad_id == 0, "%s: the edge iterator gave %zu edges with unknown site ids", name, bad_id);
	CHECK(bad_order == 0, "%s: %zu edges not given with v[0] < v[1] in (x, y) order",
		  name, bad_order);
	CHECK(r->nedge == r->api_edges, "%s: iterated %zu edges, tdc_num_edges says %zu",
		  name, r->nedge, r->api_edges);

	free(map);
	tdc_job_free(job);
	return true;
}

/* ------------------------------------------------------------------------
 * Canonical triangle and edge sets
 * ------------------------------------------------------------------------
 */

static int
cmp_tri(const void *a, const void *b)
{
	return cmp_doubles(a, b, 6);
}

static int
cmp_edge(const void *a, const void *b)
{
	return cmp_doubles(a, b, 4);
}

/*
 * Write triangle p, q, r as 6 doubles: counter-clockwise, starting at its
 * smallest (x, y) vertex.
 */
static void
canon_tri(const double *p, const double *q, const double *r, double *out)
{
	const double *v[3] = {p, q, r};
	int			k = 0;

	if (tdc_orient2d(p, q, r) < 0)
	{
		v[1] = r;
		v[2] = q;
	}
	for (int i = 1; i < 3; i++)
		if (xy_less(v[i], v[k]))
			k = i;
	for (int i = 0; i < 3; i++)
	{
		out[2 * i] = v[(k + i) % 3][0];
		out[2 * i + 1] = v[(k + i) % 3][1];
	}
}

/* Sorted canonical triangles of a result (6 doubles each). */
static double *
result_tri_set(const result *r)
{
	double	   *t = xmalloc(6 * sizeof(double) * (r->ntri + 1));

	for (size_t i = 0; i < r->ntri; i++)
		canon_tri(&r->sites[2 * r->tri[3 * i]], &r->sites[2 * r->tri[3 * i + 1]],
				  &r->sites[2 * r->tri[3 * i + 2]], &t[6 * i]);
	qsort(t, r->ntri, 6 * sizeof(double), cmp_tri);
	return t;
}

static bool
same_sets(const double *a, const double *b, size_t n, int width)
{
	for (size_t i = 0; i < n * width; i++)
		if (a[i] != b[i])
			return false;
	return true;
}

/* ------------------------------------------------------------------------
 * Checks of one result
 * ------------------------------------------------------------------------
 */

/* Sites sorted lexicographically: index array. */
static int
cmp_site_idx_base(const double *s, uint32_t a, uint32_t b)
{
	return cmp_doubles(&s[2 * a], &s[2 * b], 2);
}

static const double *sort_sites_base;

static int
cmp_site_idx(const void *a, const void *b)
{
	return cmp_site_idx_base(sort_sites_base, *(const uint32_t *) a, *(const uint32_t *) b);
}

static uint32_t *
sorted_site_index(const result *r)
{
	uint32_t   *idx = xmalloc(sizeof(uint32_t) * (r->m + 1));

	for (size_t i = 0; i < r->m; i++)
		idx[i] = (uint32_t) i;
	sort_sites_base = r->sites;
	qsort(idx, r->m, sizeof(uint32_t), cmp_site_idx);
	return idx;
}

/* Compact site with coordinates p, or UINT32_MAX. */
static uint32_t
lookup_site(const result *r, const uint32_t *idx, const double *p)
{
	size_t		lo = 0,
				hi = r->m;

	while (lo < hi)
	{
		size_t		mid = (lo + hi) / 2;
		int			c = cmp_doubles(&r->sites[2 * idx[mid]], p, 2);

		if (c == 0)
			return idx[mid];
		if (c < 0)
			lo = mid + 1;
		else
			hi = mid;
	}
	return UINT32_MAX;
}

/*
 * Convex hull of the sites including collinear boundary sites (Andrew's
 * monotone chain, exact orientation), as a flag per site; returns its size.
 * -1 when all sites are collinear.
 */
static long
exact_hull(const result *r, bool *on_hull)
{
	uint32_t   *idx = sorted_site_index(r);
	uint32_t   *chain = xmalloc(sizeof(uint32_t) * (2 * r->m + 2));
	size_t		k = 0;
	long		h = 0;
	bool		collinear = true;

	memset(on_hull, 0, r->m * sizeof(bool));
	for (size_t i = 2; i < r->m && collinear; i++)
		if (tdc_orient2d(&r->sites[2 * idx[0]], &r->sites[2 * idx[1]],
						 &r->sites[2 * idx[i]]) != 0)
			collinear = false;
	if (collinear)
	{
		free(idx);
		free(chain);
		return -1;
	}
	/* lower chain, then upper chain; pop only on strict right turns */
	for (size_t i = 0; i < r->m; i++)
	{
		while (k >= 2 && tdc_orient2d(&r->sites[2 * chain[k - 2]], &r->sites[2 * chain[k - 1]],
									  &r->sites[2 * idx[i]]) < 0)
			k--;
		chain[k++] = idx[i];
	}
	for (size_t i = r->m - 1, lower = k + 1; i-- > 0;)
	{
		while (k >= lower && tdc_orient2d(&r->sites[2 * chain[k - 2]], &r->sites[2 * chain[k - 1]],
										  &r->sites[2 * idx[i]]) < 0)
			k--;
		chain[k++] = idx[i];
	}
	for (size_t i = 0; i + 1 < k; i++)
		if (!on_hull[chain[i]])
		{
			on_hull[chain[i]] = true;
			h++;
		}
	free(idx);
	free(chain);
	return h;
}

static int
cmp_u64(const void *a, const void *b)
{
	uint64_t	x = *(const uint64_t *) a,
				y = *(const uint64_t *) b;

	return x < y ? -1 : x > y;
}

/*
 * Independent hull check: the directed triangle edges without a reverse
 * twin must be exactly one edge out of each exact hull site.  Returns the
 * number of boundary edges (or -1 when all sites are collinear).
 */
static long
check_hull(const char *name, const result *r, long want_h)
{
	bool	   *on_hull = xmalloc(r->m + 1);
	size_t	   *out_deg = xmalloc(sizeof(size_t) * (r->m + 1));
	uint64_t   *dir = xmalloc(sizeof(uint64_t) * (3 * r->ntri + 1));
	long		h = exact_hull(r, on_hull);
	long		nb = 0;
	size_t		missing = 0,
				extra = 0;

	if (h < 0)
	{
		CHECK(r->ntri == 0, "%s: all %zu sites collinear, yet %zu triangles", name, r->m, r->ntri);
		free(on_hull);
		free(out_deg);
		free(dir);
		return -1;
	}
	memset(out_deg, 0, sizeof(size_t) * r->m);
	for (size_t t = 0; t < r->ntri; t++)
		for (int k = 0; k < 3; k++)
			dir[3 * t + k] = ((uint64_t) r->tri[3 * t + k] << 32) | r->tri[3 * t + (k + 1) % 3];
	qsort(dir, 3 * r->ntri, sizeof(uint64_t), cmp_u64);
	for (size_t e = 0; e < 3 * r->ntri; e++)
	{
		uint64_t	twin = (dir[e] << 32) | (dir[e] >> 32);

		if (bsearch(&twin, dir, 3 * r->ntri, sizeof(uint64_t), cmp_u64) == NULL)
		{
			nb++;
			out_deg[dir[e] >> 32]++;
		}
	}
	for (size_t i = 0; i < r->m; i++)
	{
		if (on_hull[i] && out_deg[i] != 1)
			missing++;
		if (!on_hull[i] && out_deg[i] != 0)
			extra++;
	}
	CHECK(missing == 0 && extra == 0 && nb == h,
		  "%s: boundary of the triangles is not the exact convex hull: %zu hull sites not on it once, %zu interior sites on it, %ld boundary edges for %ld hull sites",
		  name, missing, extra, nb, h);
	if (want_h >= 0)
		CHECK(h == want_h, "%s: exact hull has %ld sites (collinear included), the file says %ld",
			  name, h, want_h);
	free(on_hull);
	free(out_deg);
	free(dir);
	return nb;
}

/* The validator, the edges against the triangles, and the hull. */
static void
check_result(const char *name, const result *r, long want_h)
{
	char		err[512] = "";
	int			rc = tdc_validate(r->sites, r->m, r->tri, r->ntri, err, sizeof err);

	CHECK(rc == 0, "%s: tdc_validate: %s (m=%zu, ntri=%zu)", name, err, r->m, r->ntri);

	/* the edge iterator gives exactly the edges of the triangles */
	if (r->ntri > 0)
	{
		double	   *te = xmalloc(4 * sizeof(double) * 3 * r->ntri);
		double	   *ie = xmalloc(4 * sizeof(double) * (r->nedge + 1));
		size_t		nte = 0,
					k = 0;

		for (size_t t = 0; t < r->ntri; t++)
			for (int j = 0; j < 3; j++)
			{
				const double *a = &r->sites[2 * r->tri[3 * t + j]];
				const double *b = &r->sites[2 * r->tri[3 * t + (j + 1) % 3]];

				if (xy_less(b, a))
				{
					const double *x = a;

					a = b;
					b = x;
				}
				memcpy(&te[4 * nte], a, 2 * sizeof(double));
				memcpy(&te[4 * nte + 2], b, 2 * sizeof(double));
				nte++;
			}
		qsort(te, nte, 4 * sizeof(double), cmp_edge);
		for (size_t i = 0; i < nte; i++)
			if (k == 0 || cmp_edge(&te[4 * (k - 1)], &te[4 * i]) != 0)
				memmove(&te[4 * k++], &te[4 * i], 4 * sizeof(double));
		memcpy(ie, r->edges, 4 * sizeof(double) * r->nedge);
		qsort(ie, r->nedge, 4 * sizeof(double), cmp_edge);
		CHECK(k == r->nedge && same_sets(te, ie, k, 4),
			  "%s: the edge iterator (%zu edges) disagrees with the triangles' %zu edges",
			  name, r->nedge, k);
		free(te);
		free(ie);
	}
	else if (r->m >= 2)
	{
		/* all collinear: the edges are the chain of consecutive sites */
		uint32_t   *idx = sorted_site_index(r);
		double	   *ie = xmalloc(4 * sizeof(double) * (r->nedge + 1));
		bool		chain = r->nedge == r->m - 1;

		memcpy(ie, r->edges, 4 * sizeof(double) * r->nedge);
		qsort(ie, r->nedge, 4 * sizeof(double), cmp_edge);
		for (size_t i = 0; chain && i + 1 < r->m; i++)
			chain = cmp_doubles(&ie[4 * i], &r->sites[2 * idx[i]], 2) == 0 &&
				cmp_doubles(&ie[4 * i + 2], &r->sites[2 * idx[i + 1]], 2) == 0;
		CHECK(chain, "%s: no triangles, but the %zu edges are not the chain of the %zu collinear sites",
			  name, r->nedge, r->m);
		free(idx);
		free(ie);
	}
	else
		CHECK(r->nedge == 0, "%s: %zu sites but %zu edges", name, r->m, r->nedge);

	check_hull(name, r, want_h);
}

/* Does no site other than its corners lie exactly on the circle of a, b, c? */
static bool
circle_has_3_sites(const result *r, const uint32_t *v)
{
	for (size_t s = 0; s < r->m; s++)
	{
		if (s == v[0] || s == v[1] || s == v[2])
			continue;
		if (tdc_incircle(&r->sites[2 * v[0]], &r->sites[2 * v[1]],
						 &r->sites[2 * v[2]], &r->sites[2 * s]) == 0)
			return false;
	}
	return true;
}

/*
 * Is the Delaunay triangulation of the sites unique?  It is when no site
 * lies exactly on the circumcircle of a triangle of a (valid) result.
 */
static bool
delaunay_unique(const result *r)
{
	for (size_t t = 0; t < r->ntri; t++)
		if (!circle_has_3_sites(r, &r->tri[3 * t]))
			return false;
	return true;
}

/* ------------------------------------------------------------------------
 * Expected geometries
 * ------------------------------------------------------------------------
 */

/* Compare one expected triangle set (GEOMETRYCOLLECTION / TIN) with r. */
static void
compare_triangles(const char *name, const result *r, const wkt *g, bool unique,
				  const char *what)
{
	size_t		ne = g->ring.n - 1;
	double	   *et = xmalloc(6 * sizeof(double) * (ne + 1));
	uint32_t   *eidx = xmalloc(3 * sizeof(uint32_t) * (ne + 1));
	uint32_t   *idx = sorted_site_index(r);
	double	   *rt;
	bool		shape_ok = true,
				found = true;
	char		err[512] = "";

	for (size_t k = 0; k < ne; k++)
	{
		size_t		a = g->ring.v[k],
					len = g->ring.v[k + 1] - a;
		const double *p = &g->xy.v[2 * a];

		if (len == 4 && cmp_doubles(p, p + 6, 2) == 0)
			len = 3;
		if (len != 3)
		{
			shape_ok = false;
			continue;
		}
		canon_tri(p, p + 2, p + 4, &et[6 * k]);
		for (int j = 0; j < 3; j++)
		{
			eidx[3 * k + j] = lookup_site(r, idx, p + 2 * j);
			if (eidx[3 * k + j] == UINT32_MAX)
				found = false;
		}
		/* validator wants counter-clockwise triangles */
		if (found && tdc_orient2d(p, p + 2, p + 4) < 0)
		{
			uint32_t	x = eidx[3 * k + 1];

			eidx[3 * k + 1] = eidx[3 * k + 2];
			eidx[3 * k + 2] = x;
		}
	}
	CHECK(shape_ok && found, "%s: fixture: expected %s has a ring that is not a triangle of the input sites",
		  name, what);
	if (!(shape_ok && found))
		goto done;
	qsort(et, ne, 6 * sizeof(double), cmp_tri);
	if (tdc_validate(r->sites, r->m, eidx, ne, err, sizeof err) != 0)
	{
		/* older GEOS may miss hull triangles: then the exact count rules */
		CHECK(ne != r->ntri,
			  "%s: expected %s has the exact triangle count %zu but is not a Delaunay triangulation of the sites: %s",
			  name, what, ne, err);
		if (ne != r->ntri)
			printf("note: %s: expected %s (%zu triangles) is not an exact Delaunay triangulation of the %zu sites (%s); the exact result (%zu triangles) is the reference\n",
				   name, what, ne, r->m, err, r->ntri);
		goto done;
	}
	rt = result_tri_set(r);
	if (verbose)
		printf("  %s: %s: %zu triangles, compared as %s\n", name, what, ne,
			   unique ? "a set (unique)" : "a count and the triangles without cocircular sites");
	if (unique)
		CHECK(ne == r->ntri && same_sets(et, rt, ne, 6),
			  "%s: triangle set differs from the expected %s (unique Delaunay triangulation; %zu vs %zu triangles)",
			  name, what, r->ntri, ne);
	else
	{
		/*
		 * Cocircular sites: the expected set is one valid answer.  Still,
		 * a triangle whose circle holds no 4th site is in every Delaunay
		 * triangulation, so those must agree both ways.
		 */
		size_t		differ = 0;
		double		key[6];

		CHECK(ne == r->ntri, "%s: %zu triangles, the expected %s (cocircular sites, one valid answer) has %zu",
			  name, r->ntri, what, ne);
		for (size_t t = 0; t < r->ntri; t++)
			if (circle_has_3_sites(r, &r->tri[3 * t]))
			{
				canon_tri(&r->sites[2 * r->tri[3 * t]], &r->sites[2 * r->tri[3 * t + 1]],
						  &r->sites[2 * r->tri[3 * t + 2]], key);
				if (!bsearch(key, et, ne, 6 * sizeof(double), cmp_tri))
					differ++;
			}
		for (size_t t = 0; t < ne; t++)
			if (circle_has_3_sites(r, &eidx[3 * t]))
			{
				canon_tri(&r->sites[2 * eidx[3 * t]], &r->sites[2 * eidx[3 * t + 1]],
						  &r->sites[2 * eidx[3 * t + 2]], key);
				if (!bsearch(key, rt, r->ntri, 6 * sizeof(double), cmp_tri))
					differ++;
			}
		CHECK(differ == 0, "%s: %zu triangles whose circle holds no 4th site are not in both the result and the expected %s",
			  name, differ, what);
	}
	free(rt);
done:
	free(et);
	free(eidx);
	free(idx);
}

/* Compare one expected edge set (MULTILINESTRING) with r. */
static void
compare_edges(const char *name, const result *r, const wkt *g, bool unique,
			  const char *what)
{
	size_t		ne = g->ring.n - 1;
	double	   *ee = xmalloc(4 * sizeof(double) * (ne + 1));
	double	   *re = xmalloc(4 * sizeof(double) * (r->nedge + 1));
	uint32_t   *idx = sorted_site_index(r);
	bool		shape_ok = true;

	for (size_t k = 0; k < ne; k++)
	{
		size_t		a = g->ring.v[k];
		const double *p = &g->xy.v[2 * a],
				   *q = p + 2;

		if (g->ring.v[k + 1] - a != 2 ||
			lookup_site(r, idx, p) == UINT32_MAX || lookup_site(r, idx, q) == UINT32_MAX)
		{
			shape_ok = false;
			continue;
		}
		if (xy_less(q, p))
		{
			const double *x = p;

			p = q;
			q = x;
		}
		memcpy(&ee[4 * k], p, 2 * sizeof(double));
		memcpy(&ee[4 * k + 2], q, 2 * sizeof(double));
	}
	CHECK(shape_ok, "%s: fixture: expected %s has a part that is not a segment between input sites",
		  name, what);
	if (shape_ok)
	{
		qsort(ee, ne, 4 * sizeof(double), cmp_edge);
		memcpy(re, r->edges, 4 * sizeof(double) * r->nedge);
		qsort(re, r->nedge, 4 * sizeof(double), cmp_edge);
		if (verbose)
			printf("  %s: %s: %zu edges, compared as %s\n", name, what, ne,
				   unique ? "a set (unique)" : "a count (cocircular)");
		if (ne != r->nedge)
			printf("note: %s: expected %s has %zu edges, the exact result %zu; the exact result is the reference\n",
				   name, what, ne, r->nedge);
		else if (unique)
			CHECK(same_sets(ee, re, ne, 4),
				  "%s: edge set differs from the expected %s (unique Delaunay triangulation)",
				  name, what);
	}
	free(ee);
	free(re);
	free(idx);
}

/* Every geometry and stated triangle count of the expected lines. */
static void
compare_expected(const ccase *c, const result *r)
{
	int			unique = -1;	/* computed when first needed */

	for (int e = 0; e < c->nexpected; e++)
	{
		const char *s = c->expected[e];
		const char *word;
		const char *p;
		int			ngeom = 0;

		while ((p = find_wkt(s, &word)) != NULL)
		{
			wkt			g;
			char		what[64];

			s = parse_wkt(p, &g);
			snprintf(what, sizeof what, "%s #%d of expected line %d", word, ++ngeom, e + 1);
			CHECK(g.ok, "%s: fixture: cannot parse expected %s", c->name, what);
			if (unique < 0)
				unique = delaunay_unique(r);
			if (g.ok && (strcmp(word, "GEOMETRYCOLLECTION") == 0 || strcmp(word, "TIN") == 0))
				compare_triangles(c->name, r, &g, unique, what);
			else if (g.ok && strcmp(word, "MULTILINESTRING") == 0)
				compare_edges(c->name, r, &g, unique, what);
			wkt_free(&g);
		}
		/* a stated count: "[9 triangles]", "(55 triangles", "-> 1 triangle" */
		s = c->expected[e];
		while ((p = strstr(s, " triangle")) != NULL)
		{
			const char *q = p;

			while (q > s && isdigit((unsigned char) q[-1]))
				q--;
			if (q < p)
			{
				long		t = strtol(q, NULL, 10);

				CHECK((long) r->ntri == t, "%s: %zu triangles, the file states %ld",
					  c->name, r->ntri, t);
				break;
			}
			s = p + 1;
		}
	}
}

/* ------------------------------------------------------------------------
 * One case
 * ------------------------------------------------------------------------
 */

static const char *const sql_only_cases[] = {
	"pg_behaviour_NULL_input",	/* STRICT function */
	"pg_behaviour_flags_out_of_range",	/* argument check */
	"pg_behaviour_SRID",		/* SRID of the result */
	"pg_behaviour_GEOS_failure",	/* error text; no concrete input */
	NULL
};

static void
run_points_case(const ccase *c, const char *label, const double *xy, size_t n,
				double tol, bool compare)
{
	tdc_options opt;
	result		r;

	tdc_options_init(&opt);
	opt.tolerance = tol;
	if (!run_core(label, xy, n, &opt, &r))
		return;
	if (verbose)
		printf("case %s: n=%zu tolerance=%g sites=%zu triangles=%zu edges=%zu (file: unique=%ld exact_T=%ld hull=%ld)\n",
			   label, n, tol, r.m, r.ntri, r.nedge, c->unique, c->exact_t, c->hull);
	if (tol == 0)
	{
		if (c->unique >= 0)
			CHECK((long) r.m == c->unique, "%s: %zu unique sites, the file says uniqueXY=%ld",
				  label, r.m, c->unique);
		if (c->exact_t >= 0)
			CHECK((long) r.ntri == c->exact_t, "%s: %zu triangles, the file says exact_T=%ld",
				  label, r.ntri, c->exact_t);
	}
	check_result(label, &r, tol == 0 ? c->hull : -1);
	if (compare)
		compare_expected(c, &r);
	result_free(&r);
}

/* PostGIS docs example: ST_Union(polygon, ST_Buffer(POINT(110 170), 20)). */
static void
case_polygon_plus_buffer(const ccase *c)
{
	static const double poly[] = {175, 150, 20, 40, 50, 60, 125, 100};
	double		xy[2 * 36];
	size_t		n = 0;
	double		inc = 2.0 * M_PI / 32;
	tdc_options opt;
	result		r;
	const char *word;
	const char *p = NULL;
	wkt			g;

	for (int i = 0; i < 4; i++)
	{
		xy[2 * n] = poly[2 * i];
		xy[2 * n + 1] = poly[2 * i + 1];
		n++;
	}
	/* GEOS builds the 32-gon clockwise from angle 0 */
	for (int i = 0; i < 32; i++)
	{
		double		a = (double) (-i) * inc;

		xy[2 * n] = 110 + 20 * cos(a);
		xy[2 * n + 1] = 170 + 20 * sin(a);
		n++;
	}

	/* the reconstruction must round to the vertices the docs show */
	for (int e = 0; e < c->nexpected && p == NULL; e++)
		p = find_wkt(c->expected[e], &word);
	CHECK(p != NULL, "%s: fixture: no expected geometry", c->name);
	if (p != NULL)
	{
		size_t		matched = 0;

		parse_wkt(p, &g);
		for (size_t i = 0; i < n; i++)
		{
			double		rx = nearbyint(xy[2 * i]),
						ry = nearbyint(xy[2 * i + 1]);

			for (size_t k = 0; k < g.xy.n / 2; k++)
				if (g.xy.v[2 * k] == rx && g.xy.v[2 * k + 1] == ry)
				{
					matched++;
					break;
				}
		}
		CHECK(matched == n, "%s: fixture: only %zu of the 36 rebuilt sites round to vertices of the documented result",
			  c->name, matched);
		wkt_free(&g);
	}

	tdc_options_init(&opt);
	if (run_core(c->name, xy, n, &opt, &r))
	{
		CHECK(r.m == 36 && r.ntri == 57 && r.nedge == 92,
			  "%s: %zu sites, %zu triangles, %zu edges; the docs show 36, 57, 92",
			  c->name, r.m, r.ntri, r.nedge);
		check_result(c->name, &r, 13);
		result_free(&r);
	}
	opt.tolerance = 0.001;
	if (run_core(c->name, xy, n, &opt, &r))
	{
		CHECK(r.m == 36 && r.nedge == 92, "%s (tolerance 0.001): %zu sites, %zu edges; the docs show 36, 92",
			  c->name, r.m, r.nedge);
		check_result(c->name, &r, -1);
		result_free(&r);
	}
}

/*
 * CIRCULARSTRING(0 0,1 1,2 0) as PostGIS strokes it (32 segments per
 * quadrant): 65 nearly cocircular sites on a half circle.
 */
static void
case_stroked_arc(const ccase *c)
{
	double		xy[2 * 65];
	tdc_options opt;
	result		r;

	for (int i = 0; i <= 64; i++)
	{
		double		a = M_PI - i * (M_PI / 64);

		xy[2 * i] = 1 + cos(a);
		xy[2 * i + 1] = sin(a);
	}
	xy[0] = 0;
	xy[1] = 0;
	xy[2 * 32] = 1;
	xy[2 * 32 + 1] = 1;
	xy[2 * 64] = 2;
	xy[2 * 64 + 1] = 0;
	tdc_options_init(&opt);
	if (run_core(c->name, xy, 65, &opt, &r))
	{
		CHECK(r.m == 65, "%s: %zu sites of 65 stroked vertices", c->name, r.m);
		check_result(c->name, &r, -1);
		result_free(&r);
	}
	/* the control points alone, as GEOS would take them */
	{
		static const double ctl[] = {0, 0, 1, 1, 2, 0};

		if (run_core(c->name, ctl, 3, &opt, &r))
		{
			CHECK(r.ntri == 1, "%s (control points): %zu triangles, want 1", c->name, r.ntri);
			check_result(c->name, &r, 3);
			result_free(&r);
		}
	}
}

/* Triangle sets under different options and input orders must not change. */
static void
check_determinism(const ccase *c, const double *xy, size_t n)
{
	static const struct
	{
		int			threads,
					levels,
					grid;
		bool		reverse;
	}			variants[] = {
		{1, 0, 0, false}, {2, 0, 0, false}, {4, 0, 0, false}, {8, 0, 0, false},
		{0, -1, 0, false}, {0, 1, 0, false}, {0, 3, 0, false},
		{0, 0, 16, false}, {0, 0, 1000, false}, {0, 0, 0, true},
		{8, 3, 16, true},
	};
	tdc_options opt;
	result		r;
	double	   *base,
			   *rev = xmalloc(2 * sizeof(double) * (n + 1));
	size_t		nbase;

	for (size_t i = 0; i < n; i++)
	{
		rev[2 * i] = xy[2 * (n - 1 - i)];
		rev[2 * i + 1] = xy[2 * (n - 1 - i) + 1];
	}
	tdc_options_init(&opt);
	if (!run_core(c->name, xy, n, &opt, &r))
	{
		free(rev);
		return;
	}
	base = result_tri_set(&r);
	nbase = r.ntri;
	result_free(&r);

	for (size_t v = 0; v < sizeof(variants) / sizeof(variants[0]); v++)
	{
		char		label[256];
		double	   *t;

		tdc_options_init(&opt);
		opt.threads = variants[v].threads;
		opt.levels = variants[v].levels;
		opt.grid_size = variants[v].grid;
		snprintf(label, sizeof label, "%s [threads=%d levels=%d grid=%d%s]", c->name,
				 opt.threads, opt.levels, opt.grid_size,
				 variants[v].reverse ? " reversed input" : "");
		if (!run_core(label, variants[v].reverse ? rev : xy, n, &opt, &r))
			continue;
		t = result_tri_set(&r);
		CHECK(r.ntri == nbase && same_sets(t, base, nbase, 6),
			  "%s: triangle set differs from the default run (%zu vs %zu triangles)",
			  label, r.ntri, nbase);
		free(t);
		result_free(&r);
	}
	free(base);
	free(rev);
}

static void bug_robustness_scaled(void);

static void
run_case(const ccase *c)
{
	dvec		xy;

	for (int i = 0; sql_only_cases[i]; i++)
		if (strcmp(c->name, sql_only_cases[i]) == 0)
			return;
	if (strcmp(c->name, "pg_doc_polygon_plus_buffer") == 0)
	{
		case_polygon_plus_buffer(c);
		return;
	}
	if (strcmp(c->name, "pg_behaviour_curves") == 0)
	{
		case_stroked_arc(c);
		return;
	}
	if (strcmp(c->name, "delaunator_scaled_robustness1") == 0)
	{
		bug_robustness_scaled();
		return;
	}
	if (strcmp(c->name, "geos_delaunay_test_9") == 0 && c->input)
	{
		/* "(150 200),(180 270),(275 163) -> envelope ...": a bare list */
		char	   *end = strstr(c->input, "->");
		char		buf[256];
		wkt			g;

		snprintf(buf, sizeof buf, "MULTIPOINT(%.*s)",
				 (int) (end ? end - c->input : (long) strlen(c->input)), c->input);
		parse_wkt(buf, &g);
		CHECK(g.ok && g.xy.n == 6, "%s: fixture: cannot read the 3 points", c->name);
		if (g.ok)
			run_points_case(c, c->name, g.xy.v, g.xy.n / 2, 0, false);
		wkt_free(&g);
		return;
	}

	if (!case_points(c, &xy))
	{
		CHECK(false, "%s (%s): no input point set this test understands", c->name, c->source);
		free(xy.v);
		return;
	}

	run_points_case(c, c->name, xy.v, xy.n / 2, c->tol, true);

	/* tolerance cases: also the plain triangulation */
	if (c->tol > 0)
	{
		char		label[160];

		snprintf(label, sizeof label, "%s (tolerance 0)", c->name);
		run_points_case(c, label, xy.v, xy.n / 2, 0, false);
	}

	if (strcmp(c->name, "pg_behaviour_XY_duplicate_with_different_Z") == 0)
	{
		tdc_options opt;
		result		r;

		/* (0 0 1) and (0 0 9): the first in input order survives (Z=1) */
		tdc_options_init(&opt);
		if (run_core(c->name, xy.v, xy.n / 2, &opt, &r))
		{
			CHECK(r.input_site[0] == r.input_site[1] && r.site_input[r.input_site[1]] == 0,
				  "%s: the duplicate site does not keep its first input point", c->name);
			result_free(&r);
		}
	}

	/* required of the delaunator fixtures; cheap for the small ones too */
	if (xy.n / 2 >= 3 && !(tdc_test_quick && xy.n / 2 > 1000))
		check_determinism(c, xy.v, xy.n / 2);
	free(xy.v);
}

/* ------------------------------------------------------------------------
 * Tests named after the bugs the fixtures once exposed
 * ------------------------------------------------------------------------
 */

static bool
load_case_points(const char *name, dvec *xy)
{
	const ccase *c = find_case(name);

	if (c == NULL || !case_points(c, xy))
	{
		CHECK(false, "%s: fixture not found", name);
		return false;
	}
	return true;
}

/*
 * Run a fixture (optionally the first n points, scaled) and check site
 * count, triangle count and exact hull size when given (>= 0).
 */
static void
bug_check(const char *label, const char *casename, size_t first, double scale,
		  long want_m, long want_t, long want_h)
{
	dvec		xy;
	tdc_options opt;
	result		r;
	size_t		n;

	if (!load_case_points(casename, &xy))
		return;
	n = xy.n / 2;
	if (first && first < n)
		n = first;
	if (scale != 1)
		for (size_t i = 0; i < 2 * n; i++)
			xy.v[i] *= scale;
	tdc_options_init(&opt);
	if (run_core(label, xy.v, n, &opt, &r))
	{
		if (want_m >= 0)
			CHECK((long) r.m == want_m, "%s: %zu sites, want %ld", label, r.m, want_m);
		if (want_t >= 0)
			CHECK((long) r.ntri == want_t, "%s: %zu triangles, want %ld", label, r.ntri, want_t);
		check_result(label, &r, want_h);
		result_free(&r);
	}
	free(xy.v);
}

/* Input order must not matter: all cyclic rotations of the input. */
static void
bug_rotations(const char *label, const char *casename)
{
	dvec		xy;
	size_t		n;
	double	   *rot,
			   *base = NULL;
	size_t		nbase = 0;

	if (!load_case_points(casename, &xy))
		return;
	n = xy.n / 2;
	rot = xmalloc(2 * sizeof(double) * (n + 1));
	for (size_t s = 0; s < n; s++)
	{
		tdc_options opt;
		result		r;
		char		l2[256];

		for (size_t i = 0; i < n; i++)
		{
			rot[2 * i] = xy.v[2 * ((i + s) % n)];
			rot[2 * i + 1] = xy.v[2 * ((i + s) % n) + 1];
		}
		snprintf(l2, sizeof l2, "%s (input rotated by %zu)", label, s);
		tdc_options_init(&opt);
		opt.threads = 1 + (int) (s % 4);
		if (!run_core(l2, rot, n, &opt, &r))
			continue;
		if (base == NULL)
		{
			base = result_tri_set(&r);
			nbase = r.ntri;
			check_result(l2, &r, -1);
		}
		else
		{
			double	   *t = result_tri_set(&r);

			CHECK(r.ntri == nbase && same_sets(t, base, nbase, 6),
				  "%s: triangle set depends on the input order", l2);
			free(t);
		}
		result_free(&r);
	}
	free(base);
	free(rot);
	free(xy.v);
}

/* delaunator #11: a flipped quad whose opposite edge is a hull edge. */
static void
bug_issue11_halfedges_flip_at_hull(void)
{
	bug_check("issue11: halfedges race on a hull flip", "delaunator_inline_issue11",
			  0, 1, 7, 7, 5);
	bug_rotations("issue11: halfedges race on a hull flip", "delaunator_inline_issue11");
}

/* delaunator #13: 17 cocircular points; flips must not reach the hull. */
static void
bug_issue13_cocircular_artifacts(void)
{
	bug_check("issue13: artifacts on cocircular input", "delaunator_fixture_issue13",
			  0, 1, 17, 15, 17);
	bug_rotations("issue13: artifacts on cocircular input", "delaunator_fixture_issue13");
}

/* delaunator #24: two collinear columns broke _legalize. */
static void
bug_issue24_collinear_columns(void)
{
	bug_check("issue24: collinear columns", "delaunator_inline_issue24", 0, 1, 9, 11, 5);
	bug_rotations("issue24: collinear columns", "delaunator_inline_issue24");
}

/*
 * delaunator #43: four nearly collinear points plus one; a non-robust
 * orientation made a wrong hull.  Exactly, the hull has 3 sites.
 */
static void
bug_issue43_wrong_hull_near_collinear(void)
{
	bug_check("issue43: wrong hull with nearly collinear points", "delaunator_fixture_issue43",
			  0, 1, 5, 5, 3);
	bug_rotations("issue43: wrong hull with nearly collinear points", "delaunator_fixture_issue43");
}

/* delaunator #44: the hull walk looped forever (run_core has a time limit). */
static void
bug_issue44_stuck_hull_walk(void)
{
	bug_check("issue44: stuck in the hull walk", "delaunator_fixture_issue44",
			  0, 1, 2828, 5599, 55);
}

/*
 * Robustness fixtures: nearly collinear hull rows must keep every exact hull
 * site (collinear ones included) and nothing else on the boundary.
 */
static void
bug_robustness_hull_points_kept(void)
{
	bug_check("robustness1: JTS #298 overlapping triangles, hull kept",
			  "delaunator_fixture_robustness1", 0, 1, 79, 141, 15);
	bug_check("robustness2: last-ulp near-duplicates stay distinct, hull kept",
			  "delaunator_fixture_robustness2", 0, 1, 968, 1924, 10);
	bug_check("robustness2: first 100 points", "delaunator_fixture_robustness2",
			  100, 1, -1, -1, -1);
	bug_check("robustness3: duplicates and collinear rows, collinear hull sites kept",
			  "delaunator_fixture_robustness3", 0, 1, 54, 94, 12);
	bug_check("robustness4: tilted grid, exactly 7 hull sites",
			  "delaunator_fixture_robustness4", 0, 1, 36, 63, 7);
}

/*
 * test.js validates robustness1 scaled by 1e-9, 1e-2, 1e2 and 1e9.  Run as
 * the case delaunator_scaled_robustness1, which has no input of its own.
 */
static void
bug_robustness_scaled(void)
{
	static const double scales[] = {1e-9, 1e-2, 1e2, 1e9};

	for (int i = 0; i < 4; i++)
	{
		char		label[128];

		snprintf(label, sizeof label, "delaunator_scaled_robustness1 x %g", scales[i]);
		bug_check(label, "delaunator_fixture_robustness1", 0, scales[i], -1, -1, -1);
	}
}

/* ukraine: after moving point 0 to [80, 220], delaunator expects 1713. */
static void
bug_ukraine_update(void)
{
	dvec		xy;
	tdc_options opt;
	result		r;

	if (!load_case_points("delaunator_fixture_ukraine", &xy))
		return;
	xy.v[0] = 80;
	xy.v[1] = 220;
	tdc_options_init(&opt);
	if (run_core("ukraine: point 0 moved to [80, 220]", xy.v, xy.n / 2, &opt, &r))
	{
		CHECK(r.ntri == 1713, "ukraine: point 0 moved to [80, 220]: %zu triangles, want 1713",
			  r.ntri);
		check_result("ukraine: point 0 moved to [80, 220]", &r, -1);
		result_free(&r);
	}
	free(xy.v);
}

/* GEOS #719 / JTS #931: flat hull triangles of nearly collinear chains. */
static void
bug_geos719_flat_hull_triangles(void)
{
	bug_check("geos719: nearly collinear chain keeps flat hull triangles",
			  "geos_delaunay_test_13", 0, 1, 5, 4, 4);
	bug_check("geos719: nearly collinear chain at 1e6/8e6",
			  "geos_delaunay_test_14", 0, 1, 5, 4, 4);
	bug_check("shapely1873: nearly collinear UTM points", "geos_delaunay_test_19",
			  0, 1, 8, 8, 6);
	bug_rotations("shapely1873: nearly collinear UTM points", "geos_delaunay_test_19");
}

/* JTS #477 / shapely #764: a very flat triangle was lost. */
static void
bug_jts477_flat_triangle_lost(void)
{
	bug_check("jts477: flat triangle with a duplicate", "geos_delaunay_test_16", 0, 1, 3, 1, 3);
	bug_check("jts477: tall thin set", "geos_delaunay_test_17", 0, 1, 6, 5, 5);
	bug_check("geos20: union of triangles is the convex hull", "geos_delaunay_test_20",
			  0, 1, 9, 11, 5);
}

/* GEOS #946 and JTS #298: sites 1e-10 and 6e-14 apart stay distinct. */
static void
bug_near_duplicates_kept(void)
{
	bug_check("geos946: near-duplicate sites 2e-10 apart", "geos_delaunay_test_18",
			  0, 1, 5, 3, 5);
	bug_check("jts298: sites 5.7e-14 apart", "geos_delaunay_test_10", 0, 1, 5, 4, 4);
}

/* ------------------------------------------------------------------------
 * Entry point
 * ------------------------------------------------------------------------
 */

/*
 * Where the fixtures are.  The repository carries them in test/fixtures; the
 * Makefile compiles in its own directory as TDC_SOURCE_DIR, so the suite
 * finds them whatever the current directory.  If the tree moved since the
 * build, test/fixtures under the current directory is tried as well.
 * TDC_FIXTURES_DIR, when set, is used alone (say, a newer copy of the
 * cases): a wrong setting fails rather than quietly testing another copy.
 */
static const char *
find_fixtures(const char *probe_name, char *buf, size_t bufsz)
{
	const char *env = getenv("TDC_FIXTURES_DIR");
	const char *cands[3];
	int			ncand = 0;

	if (env != NULL && env[0] != '\0')
		cands[ncand++] = env;
	else
	{
#ifdef TDC_SOURCE_DIR
		cands[ncand++] = TDC_SOURCE_DIR "/test/fixtures";
#endif
		cands[ncand++] = "test/fixtures";
	}
	for (int i = 0; i < ncand; i++)
	{
		char	   *probe = read_whole_file(cands[i], probe_name, NULL);

		if (probe != NULL)
		{
			free(probe);
			snprintf(buf, bufsz, "%s", cands[i]);
			return buf;
		}
	}
	fprintf(stderr, "test_conformance: %s not found in", probe_name);
	for (int i = 0; i < ncand; i++)
		fprintf(stderr, " %s%s", cands[i], i + 1 < ncand ? "," : "\n");
	return NULL;
}

/* CASE blocks each file of the repository's copy holds (test/fixtures/README.md). */
#define POSTGIS_CASES		25
#define GEOS_CASES			28
#define DELAUNATOR_CASES	16

void
test_conformance(void)
{
	static const char *const files[] = {"postgis-cases.txt", "geos-cases.txt",
	"delaunator-cases.txt", NULL};
	static const int file_cases[] = {POSTGIS_CASES, GEOS_CASES, DELAUNATOR_CASES};
	char	   *bufs[3] = {NULL, NULL, NULL};
	char		dirbuf[1024];
	long		failed_before = tdc_test_failed,
				passed_before = tdc_test_passed;
	int			cases_ok = 0,
				cases_failed = 0,
				cases_sql = 0;

	verbose = getenv("TDC_TEST_VERBOSE") != NULL;

	conf_dir = find_fixtures(files[0], dirbuf, sizeof dirbuf);
	if (conf_dir == NULL)
	{
		CHECK(false, "conformance fixtures missing: %d cases not run",
			  POSTGIS_CASES + GEOS_CASES + DELAUNATOR_CASES);
		return;
	}

	for (int f = 0; files[f]; f++)
	{
		int			before = ncases;

		bufs[f] = read_whole_file(conf_dir, files[f], NULL);
		CHECK(bufs[f] != NULL, "cannot read %s/%s", conf_dir, files[f]);
		if (bufs[f])
			split_cases(files[f], bufs[f]);
		/* a block the splitter lost would otherwise go unnoticed */
		CHECK(getenv("TDC_FIXTURES_DIR") != NULL || ncases - before == file_cases[f],
			  "%s/%s: %d CASE blocks, want %d", conf_dir, files[f], ncases - before,
			  file_cases[f]);
	}

	for (int i = 0; i < ncases; i++)
	{
		long		f0 = tdc_test_failed,
					p0 = tdc_test_passed;
		bool		sql_only = false;

		for (int k = 0; sql_only_cases[k]; k++)
			if (strcmp(cases[i].name, sql_only_cases[k]) == 0)
				sql_only = true;
		run_case(&cases[i]);
		if (sql_only)
			cases_sql++;
		else if (tdc_test_failed > f0)
			cases_failed++;
		else
		{
			/* every case the core runs must check something */
			CHECK(tdc_test_passed > p0, "%s: no check ran", cases[i].name);
			if (tdc_test_passed > p0)
				cases_ok++;
			else
				cases_failed++;
		}
	}

	bug_issue11_halfedges_flip_at_hull();
	bug_issue13_cocircular_artifacts();
	bug_issue24_collinear_columns();
	bug_issue43_wrong_hull_near_collinear();
	bug_issue44_stuck_hull_walk();
	bug_robustness_hull_points_kept();
	bug_ukraine_update();
	bug_geos719_flat_hull_triangles();
	bug_jts477_flat_triangle_lost();
	bug_near_duplicates_kept();

	/* (not "N passed, N failed": scripts/test.sh reads the last such line) */
	printf("conformance: %d cases from %s: %d pass, %d fail, %d SQL-only "
		   "(sql/tdc_postgis_cases.sql); checks: %ld pass, %ld fail\n",
		   ncases, conf_dir, cases_ok, cases_failed, cases_sql,
		   tdc_test_passed - passed_before, tdc_test_failed - failed_before);

	for (int i = 0; i < ncases; i++)
	{
		free(cases[i].text);
		free(cases[i].input);
		free(cases[i].fileref);
		for (int e = 0; e < cases[i].nexpected; e++)
			free(cases[i].expected[e]);
	}
	free(cases);
	cases = NULL;
	ncases = 0;
	conf_dir = NULL;
	for (int f = 0; f < 3; f++)
		free(bufs[f]);
}
