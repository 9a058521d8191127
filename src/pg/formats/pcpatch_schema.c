/*
 * pcpatch_schema.c
 *		The XML schema of a pgpointcloud format (pointcloud_formats.schema)
 *		and the filter on one of its dimensions, read in pure C.
 *
 * pgpointcloud parses the schema with libxml2 and keeps, per
 * <dimension> under the root <PointCloudSchema>: position (1-based),
 * name, interpretation (int8_t ... uint64_t, double, float), scale
 * (default 1) and offset (default 0); size follows from the
 * interpretation, and the points are laid out in position order without
 * padding.  The patch compression is the text of <Metadata
 * name="compression"> under <metadata>: none (also when absent),
 * dimensional or laz.  X, Y and Z are the dimensions named X, Y and Z
 * (pgpointcloud also takes Longitude/Lon, Latitude/Lat, H/Height; so do
 * we), ignoring case.
 *
 * We need nothing else, so this reader is a small XML scanner, not an
 * XML library: elements, attributes, text with the five predefined
 * entities and numeric character references, comments and the XML
 * declaration.  What it does not understand it refuses, naming it: a
 * DOCTYPE, CDATA, a processing instruction elsewhere, unbalanced tags, an
 * unknown interpretation or compression, a number that does not parse,
 * positions that are missing or repeated.  Unknown child elements of a
 * dimension (description, uuid, active, ...) are skipped, as
 * pgpointcloud skips them: they say nothing about the bytes.
 *
 * No allocation: the scan works on the caller's text, and the schema is a
 * fixed-size struct.  The fuzz target feeds arbitrary bytes to both
 * functions here.
 */
#include <ctype.h>
#include <math.h>
#include <stdarg.h>
#include <stdbool.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>

#include "formats/pcpatch_format.h"

#define XML_MAX_DEPTH	16
#define TEXT_MAX		256

typedef struct Scan
{
	const char *p;
	const char *end;
	char	   *err;
	size_t		errlen;
} Scan;

/* The error code, with its message in err (both files' errors go through here). */
int
tdc_pc_fail(char *err, size_t errlen, int code, const char *fmt,...)
{
	va_list		ap;

	if (errlen > 0)
	{
		va_start(ap, fmt);
		vsnprintf(err, errlen, fmt, ap);
		va_end(ap);
	}
	return code;
}

static bool
starts(const Scan *s, const char *lit)
{
	size_t		n = strlen(lit);

	return (size_t) (s->end - s->p) >= n && memcmp(s->p, lit, n) == 0;
}

/* Skip to just after lit; false if it does not occur. */
static bool
skip_past(Scan *s, const char *lit)
{
	size_t		n = strlen(lit);

	while ((size_t) (s->end - s->p) >= n)
	{
		if (memcmp(s->p, lit, n) == 0)
		{
			s->p += n;
			return true;
		}
		s->p++;
	}
	return false;
}

static bool
is_name_char(char c)
{
	return isalnum((unsigned char) c) || c == '_' || c == '-' || c == '.' || c == ':';
}

/* A qualified name; its local part (after any prefix) into out. */
static bool
scan_name(Scan *s, char *out, size_t outlen)
{
	const char *b = s->p,
			   *local;
	size_t		n;

	while (s->p < s->end && is_name_char(*s->p))
		s->p++;
	if (s->p == b)
		return false;
	local = b;
	for (const char *q = b; q < s->p; q++)
		if (*q == ':')
			local = q + 1;
	n = (size_t) (s->p - local);
	if (n == 0 || n >= outlen)
		return false;
	memcpy(out, local, n);
	out[n] = '\0';
	return true;
}

/*
 * Text from b to e with entities decoded, trimmed, into out.  false on an
 * entity we do not know or text too long to be one of ours.
 */
static bool
decode_text(const char *b, const char *e, char *out, size_t outlen)
{
	size_t		n = 0;

	while (b < e && isspace((unsigned char) *b))
		b++;
	while (e > b && isspace((unsigned char) e[-1]))
		e--;
	while (b < e)
	{
		char		c = *b++;

		if (c == '&')
		{
			static const char *const ent[] = {"amp;", "lt;", "gt;", "quot;", "apos;"};
			static const char val[] = "&<>\"'";
			int			k;

			for (k = 0; k < 5; k++)
				if ((size_t) (e - b) >= strlen(ent[k]) && memcmp(b, ent[k], strlen(ent[k])) == 0)
					break;
			if (k == 5)
				return false;
			b += strlen(ent[k]);
			c = val[k];
		}
		else if (c == '<')
			return false;
		if (n + 1 >= outlen)
			return false;
		out[n++] = c;
	}
	out[n] = '\0';
	return true;
}

static bool
parse_double(const char *t, double *v)
{
	char	   *end;

	if (*t == '\0')
		return false;
	*v = strtod(t, &end);
	return *end == '\0' && isfinite(*v);
}

static TdcPcInterp
interp_of(const char *t, int *size)
{
	static const struct
	{
		const char *name;
		TdcPcInterp interp;
		int			size;
	}			known[] = {
		{"int8_t", TDC_PC_INT8, 1}, {"uint8_t", TDC_PC_UINT8, 1},
		{"int16_t", TDC_PC_INT16, 2}, {"uint16_t", TDC_PC_UINT16, 2},
		{"int32_t", TDC_PC_INT32, 4}, {"uint32_t", TDC_PC_UINT32, 4},
		{"int64_t", TDC_PC_INT64, 8}, {"uint64_t", TDC_PC_UINT64, 8},
		{"double", TDC_PC_DOUBLE, 8}, {"float", TDC_PC_FLOAT, 4},
	};

	for (size_t i = 0; i < sizeof(known) / sizeof(known[0]); i++)
		if (strcasecmp(t, known[i].name) == 0)
		{
			*size = known[i].size;
			return known[i].interp;
		}
	return 0;
}

/* What one <dimension> says, before it is placed by its position. */
typedef struct DimText
{
	TdcPcDim	d;
	long		position;
	bool		has_name,
				has_interp;
}			DimText;

/*
 * The one pass over the document.  path[] holds the local names of the
 * open elements; a text node is used only where path says what it is.
 */
int
tdc_pc_schema_parse(const char *xml, size_t len, TdcPcSchema *sch,
					char *err, size_t errlen)
{
	Scan		s = {xml, xml + len, err, errlen};
	char		path[XML_MAX_DEPTH][TEXT_MAX];
	int			depth = 0;
	bool		seen_root = false;
	DimText		cur;
	char		attr_name[TEXT_MAX] = "";	/* the open <Metadata>'s name */
	const char *text_start = NULL;
	bool		have_compression = false;

	memset(sch, 0, sizeof(*sch));
	memset(&cur, 0, sizeof(cur));
	sch->x = sch->y = sch->z = -1;

	while (s.p < s.end)
	{
		if (*s.p != '<')
		{
			if (depth == 0 && !isspace((unsigned char) *s.p))
				return tdc_pc_fail(err, errlen, TDC_PC_ERR_SCHEMA, "text outside the root element");
			s.p++;
			continue;
		}
		if (starts(&s, "<!--"))
		{
			if (!skip_past(&s, "-->"))
				return tdc_pc_fail(err, errlen, TDC_PC_ERR_SCHEMA, "an unterminated comment");
			continue;
		}
		if (starts(&s, "<?"))
		{
			if (seen_root || !starts(&s, "<?xml") || !skip_past(&s, "?>"))
				return tdc_pc_fail(err, errlen, TDC_PC_ERR_SCHEMA, "a processing instruction");
			continue;
		}
		if (starts(&s, "<!"))
			return tdc_pc_fail(err, errlen, TDC_PC_ERR_SCHEMA, "a DOCTYPE or CDATA section");
		if (starts(&s, "</"))
		{
			char		name[TEXT_MAX],
						text[TEXT_MAX];
			const char *tend = s.p;

			s.p += 2;
			if (!scan_name(&s, name, sizeof(name)) || depth == 0 ||
				strcmp(name, path[depth - 1]) != 0)
				return tdc_pc_fail(err, errlen, TDC_PC_ERR_SCHEMA, "unbalanced tags");
			while (s.p < s.end && isspace((unsigned char) *s.p))
				s.p++;
			if (s.p >= s.end || *s.p != '>')
				return tdc_pc_fail(err, errlen, TDC_PC_ERR_SCHEMA, "an unterminated closing tag");
			s.p++;
			/* the text of a leaf we read */
			if (depth == 3 && strcmp(path[1], "dimension") == 0 && text_start != NULL)
			{
				const char *field = path[2];

				if (strcmp(field, "name") == 0 || strcmp(field, "interpretation") == 0 ||
					strcmp(field, "position") == 0 || strcmp(field, "scale") == 0 ||
					strcmp(field, "offset") == 0)
				{
					if (!decode_text(text_start, tend, text, sizeof(text)))
						return tdc_pc_fail(err, errlen, TDC_PC_ERR_SCHEMA,
									"the <%s> of a dimension is not plain text", field);
					if (strcmp(field, "name") == 0)
					{
						if (text[0] == '\0' || strlen(text) >= TDC_PC_NAME_MAX)
							return tdc_pc_fail(err, errlen, TDC_PC_ERR_SCHEMA,
										"a dimension name is empty or longer than %d bytes",
										TDC_PC_NAME_MAX - 1);
						strcpy(cur.d.name, text);
						cur.has_name = true;
					}
					else if (strcmp(field, "interpretation") == 0)
					{
						cur.d.interp = interp_of(text, &cur.d.size);
						if (cur.d.interp == 0)
							return tdc_pc_fail(err, errlen, TDC_PC_ERR_SCHEMA,
										"unknown interpretation \"%s\"", text);
						cur.has_interp = true;
					}
					else if (strcmp(field, "position") == 0)
					{
						char	   *e;

						cur.position = strtol(text, &e, 10);
						if (*e != '\0' || e == text || cur.position < 1 ||
							cur.position > TDC_PC_MAX_DIMS)
							return tdc_pc_fail(err, errlen, TDC_PC_ERR_SCHEMA,
										"a position \"%s\" not between 1 and %d", text,
										TDC_PC_MAX_DIMS);
					}
					else if (strcmp(field, "scale") == 0)
					{
						if (!parse_double(text, &cur.d.scale) || cur.d.scale == 0)
							return tdc_pc_fail(err, errlen, TDC_PC_ERR_SCHEMA,
										"a scale \"%s\" that is not a finite non-zero number", text);
					}
					else if (strcmp(field, "offset") == 0)
					{
						if (!parse_double(text, &cur.d.offset))
							return tdc_pc_fail(err, errlen, TDC_PC_ERR_SCHEMA,
										"an offset \"%s\" that is not a finite number", text);
					}
				}
			}
			else if (depth == 3 && strcmp(path[1], "metadata") == 0 &&
					 strcmp(path[2], "Metadata") == 0 && strcmp(attr_name, "compression") == 0 &&
					 text_start != NULL)
			{
				if (!decode_text(text_start, tend, text, sizeof(text)))
					return tdc_pc_fail(err, errlen, TDC_PC_ERR_SCHEMA, "the compression is not plain text");
				if (strcasecmp(text, "none") == 0)
					sch->compression = TDC_PC_NONE;
				else if (strcasecmp(text, "dimensional") == 0)
					sch->compression = TDC_PC_DIMENSIONAL;
				else if (strcasecmp(text, "laz") == 0)
					sch->compression = TDC_PC_LAZ;
				else
					return tdc_pc_fail(err, errlen, TDC_PC_ERR_COMPRESSION,
								"unknown compression \"%s\"", text);
				if (have_compression)
					return tdc_pc_fail(err, errlen, TDC_PC_ERR_SCHEMA, "two compressions");
				have_compression = true;
			}
			else if (depth == 2 && strcmp(path[1], "dimension") == 0)
			{
				/* a complete dimension: place it */
				TdcPcDim   *d;

				if (!cur.has_name || !cur.has_interp || cur.position == 0)
					return tdc_pc_fail(err, errlen, TDC_PC_ERR_SCHEMA,
								"a dimension without a name, an interpretation or a position");
				d = &sch->dims[cur.position - 1];
				if (d->interp != 0)
					return tdc_pc_fail(err, errlen, TDC_PC_ERR_SCHEMA,
								"position %ld given twice", cur.position);
				*d = cur.d;
				sch->ndims++;
			}
			text_start = NULL;
			depth--;
			continue;
		}
		/* an opening tag */
		{
			char		name[TEXT_MAX];
			bool		empty = false;

			s.p++;
			if (!scan_name(&s, name, sizeof(name)))
				return tdc_pc_fail(err, errlen, TDC_PC_ERR_SCHEMA, "a tag without a name");
			if (depth == XML_MAX_DEPTH)
				return tdc_pc_fail(err, errlen, TDC_PC_ERR_SCHEMA, "elements nested too deep");
			if (depth == 0)
			{
				if (seen_root || strcmp(name, "PointCloudSchema") != 0)
					return tdc_pc_fail(err, errlen, TDC_PC_ERR_SCHEMA,
								"the root element is not a single <PointCloudSchema>");
				seen_root = true;
			}
			if (depth == 1 && strcmp(name, "dimension") == 0)
			{
				memset(&cur, 0, sizeof(cur));
				cur.d.scale = 1.0;
			}
			if (depth == 2 && strcmp(name, "Metadata") == 0)
				attr_name[0] = '\0';
			/* attributes: name="value" or name='value' */
			for (;;)
			{
				char		an[TEXT_MAX],
							av[TEXT_MAX];
				char		q;
				const char *vb;

				while (s.p < s.end && isspace((unsigned char) *s.p))
					s.p++;
				if (s.p >= s.end)
					return tdc_pc_fail(err, errlen, TDC_PC_ERR_SCHEMA, "an unterminated tag");
				if (*s.p == '>')
				{
					s.p++;
					break;
				}
				if (starts(&s, "/>"))
				{
					s.p += 2;
					empty = true;
					break;
				}
				if (!scan_name(&s, an, sizeof(an)) || s.p >= s.end || *s.p != '=')
					return tdc_pc_fail(err, errlen, TDC_PC_ERR_SCHEMA, "a malformed attribute");
				s.p++;
				if (s.p >= s.end || (*s.p != '"' && *s.p != '\''))
					return tdc_pc_fail(err, errlen, TDC_PC_ERR_SCHEMA, "an unquoted attribute");
				q = *s.p++;
				vb = s.p;
				while (s.p < s.end && *s.p != q)
					s.p++;
				if (s.p >= s.end)
					return tdc_pc_fail(err, errlen, TDC_PC_ERR_SCHEMA, "an unterminated attribute");
				if (!decode_text(vb, s.p, av, sizeof(av)))
					return tdc_pc_fail(err, errlen, TDC_PC_ERR_SCHEMA, "an attribute that is not plain text");
				s.p++;
				if (depth == 2 && strcmp(name, "Metadata") == 0 && strcmp(an, "name") == 0)
					strcpy(attr_name, av);
			}
			if (empty)
			{
				if (depth == 1 && strcmp(name, "dimension") == 0)
					return tdc_pc_fail(err, errlen, TDC_PC_ERR_SCHEMA, "an empty dimension");
				continue;
			}
			strcpy(path[depth], name);
			depth++;
			text_start = s.p;
		}
	}
	if (!seen_root || depth != 0)
		return tdc_pc_fail(err, errlen, TDC_PC_ERR_SCHEMA, "no complete <PointCloudSchema> element");
	if (sch->ndims == 0)
		return tdc_pc_fail(err, errlen, TDC_PC_ERR_SCHEMA, "no dimension");
	/* positions 1..ndims, each once (the count of placed ones is ndims) */
	for (int i = 0; i < sch->ndims; i++)
	{
		TdcPcDim   *d = &sch->dims[i];

		if (d->interp == 0)
			return tdc_pc_fail(err, errlen, TDC_PC_ERR_SCHEMA, "no dimension at position %d", i + 1);
		d->offset_bytes = sch->point_size;
		sch->point_size += (size_t) d->size;
		if (strcasecmp(d->name, "X") == 0 || strcasecmp(d->name, "Longitude") == 0 ||
			strcasecmp(d->name, "Lon") == 0)
			sch->x = i;
		else if (strcasecmp(d->name, "Y") == 0 || strcasecmp(d->name, "Latitude") == 0 ||
				 strcasecmp(d->name, "Lat") == 0)
			sch->y = i;
		else if (strcasecmp(d->name, "Z") == 0 || strcasecmp(d->name, "H") == 0 ||
				 strcasecmp(d->name, "Height") == 0)
			sch->z = i;
	}
	if (sch->x < 0 || sch->y < 0 || sch->z < 0)
		return tdc_pc_fail(err, errlen, TDC_PC_ERR_NOXYZ, "the schema has no %s dimension",
					sch->x < 0 ? "X" : sch->y < 0 ? "Y" : "Z");
	return TDC_PC_OK;
}

/*
 * A filter "name=v1[,v2...]": keep the points whose dimension "name"
 * (ignoring case), scaled and offset, equals one of the values.  NULL or
 * an empty text: no filter.
 */
int
tdc_pc_filter_parse(const char *text, const TdcPcSchema *s, TdcPcFilter *f,
					char *err, size_t errlen)
{
	const char *eq;
	char		name[TDC_PC_NAME_MAX];
	size_t		n;
	const char *p;

	memset(f, 0, sizeof(*f));
	f->dim = -1;
	if (text == NULL || text[0] == '\0')
		return TDC_PC_OK;
	eq = strchr(text, '=');
	if (eq == NULL)
		return tdc_pc_fail(err, errlen, TDC_PC_ERR_FILTER, "no \"=\": write dimension=value[,value...]");
	while (text < eq && isspace((unsigned char) *text))
		text++;
	n = (size_t) (eq - text);
	while (n > 0 && isspace((unsigned char) text[n - 1]))
		n--;
	if (n == 0 || n >= sizeof(name))
		return tdc_pc_fail(err, errlen, TDC_PC_ERR_FILTER, "no dimension name before \"=\"");
	memcpy(name, text, n);
	name[n] = '\0';
	for (int i = 0; i < s->ndims; i++)
		if (strcasecmp(s->dims[i].name, name) == 0)
		{
			f->dim = i;
			break;
		}
	if (f->dim < 0)
		return tdc_pc_fail(err, errlen, TDC_PC_ERR_FILTER, "the schema has no dimension \"%s\"", name);
	p = eq + 1;
	for (;;)
	{
		char	   *end;
		double		v;

		while (isspace((unsigned char) *p))
			p++;
		v = strtod(p, &end);
		if (end == p || !isfinite(v))
			return tdc_pc_fail(err, errlen, TDC_PC_ERR_FILTER, "a value that is not a finite number");
		if (f->nvals == TDC_PC_FILTER_MAX)
			return tdc_pc_fail(err, errlen, TDC_PC_ERR_FILTER, "more than %d values", TDC_PC_FILTER_MAX);
		f->vals[f->nvals++] = v;
		p = end;
		while (isspace((unsigned char) *p))
			p++;
		if (*p == '\0')
			break;
		if (*p != ',')
			return tdc_pc_fail(err, errlen, TDC_PC_ERR_FILTER, "values must be separated by \",\"");
		p++;
	}
	return TDC_PC_OK;
}
