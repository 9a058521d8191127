/*
 * tmpdir.c
 *		The temporary directory of ./tdc --max-memory: made under --tmpdir
 *		(or $TMPDIR, or /tmp) before the input is staged, removed with
 *		whatever is in it at exit, also when ./tdc dies.
 *
 * ./tdc keeps its staged text input there (input.xy, input.z, input.c);
 * the core's bounded run creates and removes its own files in it
 * (tdc_bounded_run in tdc.h).  The directory is the process's, hence its
 * one global.
 */
#include <dirent.h>
#include <stdio.h>
#include <stdlib.h>
#include <unistd.h>

#include "cli.h"

char		tmp_dir[4096];

/* tmp_dir := a new directory under base; removed at exit */
void
tmp_create(const char *base)
{
	snprintf(tmp_dir, sizeof(tmp_dir), "%s/tdc.XXXXXX", base);
	if (mkdtemp(tmp_dir) == NULL)
	{
		tmp_dir[0] = '\0';
		die(1, "cannot create a temporary directory in %s", base);
	}
	atexit(tmp_cleanup);
}

void
tmp_cleanup(void)
{
	DIR		   *d;
	struct dirent *e;

	if (tmp_dir[0] == '\0')
		return;
	if ((d = opendir(tmp_dir)) != NULL)
	{
		while ((e = readdir(d)) != NULL)
		{
			char		p[4400];

			if (e->d_name[0] == '.')
				continue;
			snprintf(p, sizeof(p), "%s/%s", tmp_dir, e->d_name);
			unlink(p);
		}
		closedir(d);
	}
	rmdir(tmp_dir);
	tmp_dir[0] = '\0';
}

FILE *
tmp_open(const char *name, const char *mode)
{
	char		p[4400];
	FILE	   *f;

	snprintf(p, sizeof(p), "%s/%s", tmp_dir, name);
	f = fopen(p, mode);
	if (f == NULL)
		die(1, "cannot open temporary file %s", p);
	return f;
}
